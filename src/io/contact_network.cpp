#include "io/contact_network.hpp"

#include <algorithm>
#include <stdexcept>

#include "thermal/thermal.hpp"

namespace cohdem {

VtuData contact_network_vtu(const System& s) {
  const ParticleStore& P = s.particles;
  const NeighborList& nl = s.nl;
  const ThermalModel* th = s.thermal.get();
  std::vector<Vec3> pts;
  std::vector<std::array<uint32_t, 2>> lines;
  std::vector<int32_t> kind;
  std::vector<double> fn, a, h;
  std::vector<Vec3> f;
  const auto& ap = s.pair_contact_radii();
  const auto& aw = s.wall_contact_radii();
  if (ap.size() < nl.pair_count() || aw.size() < nl.wall_entry_count())
    throw std::logic_error("contact_network_vtu: contact radii were not recorded (SimConfig::record_contacts)");
  for (size_t i = 0; i + 1 < nl.start.size(); ++i)
    for (uint32_t k = nl.start[i]; k < nl.start[i + 1]; ++k) {
      if (!nl.hist.live[k]) continue;
      const Vec3 xj = P.x[nl.jdx[k]] + nl.shift[nl.image[k]];
      lines.push_back({uint32_t(pts.size()), uint32_t(pts.size() + 1)});
      pts.push_back(P.x[i]);
      pts.push_back(xj);
      kind.push_back(0);
      fn.push_back(dot(s.pair_force(k), normalized(P.x[i] - xj)));
      f.push_back(s.pair_force(k));
      a.push_back(ap[k]);
      h.push_back(th && k < th->h_pair.size() ? th->h_pair[k] : 0.0);
    }
  const auto& fw = s.wall_forces();
  const auto& cw = s.wall_contact_points();
  for (size_t i = 0; i + 1 < nl.wstart.size(); ++i)
    for (uint32_t e = nl.wstart[i]; e < nl.wstart[i + 1]; ++e) {
      if (!nl.whist.live[e]) continue;
      lines.push_back({uint32_t(pts.size()), uint32_t(pts.size() + 1)});
      pts.push_back(P.x[i]);
      pts.push_back(cw[e]);
      kind.push_back(1);
      fn.push_back(dot(fw[e], normalized(P.x[i] - cw[e])));
      f.push_back(fw[e]);
      a.push_back(aw[e]);
      h.push_back(th && e < th->h_wall.size() ? th->h_wall[e] : 0.0);
    }
  VtuData d = lines_vtu(std::move(pts), lines);
  d.add_cell_int("kind", std::move(kind));
  d.add_cell_scalar("normal_force", std::move(fn));
  d.add_cell_vector("force", f);
  d.add_cell_scalar("contact_radius", std::move(a));
  d.add_cell_scalar("conductance", std::move(h));
  return d;
}

ContactForceStats pair_force_stats(const System& s) {
  const ParticleStore& P = s.particles;
  const NeighborList& nl = s.nl;
  ContactForceStats st;
  double sum = 0;
  for (size_t i = 0; i + 1 < nl.start.size(); ++i)
    for (uint32_t k = nl.start[i]; k < nl.start[i + 1]; ++k) {
      if (!nl.hist.live[k]) continue;
      const double f = dot(s.pair_force(k), normalized(P.x[i] - P.x[nl.jdx[k]] - nl.shift[nl.image[k]]));
      st.max = std::max(st.max, f);
      sum += f;
      ++st.count;
    }
  st.mean = st.count ? sum / double(st.count) : 0.0;
  return st;
}

}  // namespace cohdem
