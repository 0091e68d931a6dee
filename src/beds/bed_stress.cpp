#include "beds/bed_stress.hpp"

#include <algorithm>
#include <cmath>

#include "analysis/packing_profile.hpp"

namespace cohdem::beds {

void SliceStresses::accumulate(const SliceStresses& o, double w) {
  if (edges.empty()) {
    *this = o;
    scale(w);
    return;
  }
  auto add = [w](std::vector<double>& a, const std::vector<double>& b) {
    for (size_t i = 0; i < a.size(); ++i) a[i] += w * b[i];
  };
  add(sigma_v, o.sigma_v);
  add(sigma_h, o.sigma_h);
  add(wall_normal, o.wall_normal);
  add(wall_shear, o.wall_shear);
  add(fraction, o.fraction);
}

void SliceStresses::scale(double f) {
  for (auto* v : {&sigma_v, &sigma_h, &wall_normal, &wall_shear, &fraction})
    for (double& x : *v) x *= f;
}

SliceStresses slice_stresses(const System& s, size_t pipe, double z_lo, double z_hi, int nbins) {
  const ParticleStore& P = s.particles;
  const NeighborList& nl = s.nl;
  const double R = s.walls[pipe].radius, dz = (z_hi - z_lo) / nbins;
  const double V = M_PI * R * R * dz;
  SliceStresses out;
  out.edges.resize(nbins + 1);
  for (int b = 0; b <= nbins; ++b) out.edges[b] = z_lo + b * dz;
  std::vector<double> szz(nbins, 0.0), sxx(nbins, 0.0), syy(nbins, 0.0);
  out.wall_normal.assign(nbins, 0.0);
  out.wall_shear.assign(nbins, 0.0);

  // Adds f (x) l, spread over the heights za..zb that the branch segment spans.
  auto add_branch = [&](const Vec3& f, const Vec3& l, double za, double zb) {
    if (za > zb) std::swap(za, zb);
    const double len = zb - za;
    auto put = [&](int b, double w) {
      szz[b] += w * f.z * l.z / V;
      sxx[b] += w * f.x * l.x / V;
      syy[b] += w * f.y * l.y / V;
    };
    if (len <= 1e-12 * (std::fabs(za) + 1e-3)) {
      const int b = int(std::floor((za - z_lo) / dz));
      if (b >= 0 && b < nbins) put(b, 1.0);
      return;
    }
    const int b0 = std::max(0, int(std::floor((za - z_lo) / dz))), b1 = std::min(nbins - 1, int(std::floor((zb - z_lo) / dz)));
    for (int b = b0; b <= b1; ++b) {
      const double lo = std::max(za, out.edges[b]), hi = std::min(zb, out.edges[b + 1]);
      if (hi > lo) put(b, (hi - lo) / len);
    }
  };

  for (size_t i = 0; i + 1 < nl.start.size(); ++i)
    for (uint32_t k = nl.start[i]; k < nl.start[i + 1]; ++k) {
      if (!nl.hist.live[k]) continue;
      const Vec3 xj = P.x[nl.jdx[k]] + nl.shift[nl.image[k]];
      add_branch(s.pair_force(k), P.x[i] - xj, xj.z, P.x[i].z);
    }
  const auto& fw = s.wall_forces();
  const auto& cw = s.wall_contact_points();
  const Wall& W = s.walls[pipe];
  for (size_t i = 0; i + 1 < nl.wstart.size(); ++i)
    for (uint32_t e = nl.wstart[i]; e < nl.wstart[i + 1]; ++e) {
      if (!nl.whist.live[e]) continue;
      add_branch(fw[e], P.x[i] - cw[e], cw[e].z, P.x[i].z);
      if (nl.wall[e] != pipe) continue;
      const int b = int(std::floor((cw[e].z - z_lo) / dz));
      if (b < 0 || b >= nbins) continue;
      const Vec3 n = normalized(P.x[i] - cw[e]);  // from the wall into the bed
      out.wall_normal[b] += dot(fw[e], n) / (2 * M_PI * W.radius * dz);
      out.wall_shear[b] += fw[e].z / (2 * M_PI * W.radius * dz);
    }
  out.sigma_v = szz;
  out.sigma_h.resize(nbins);
  for (int b = 0; b < nbins; ++b) out.sigma_h[b] = 0.5 * (sxx[b] + syy[b]);
  std::vector<Vec3> x;
  std::vector<double> r;
  for (size_t i = 0; i < P.size(); ++i)
    if (P.flag[i] == kFree) { x.push_back(P.x[i]); r.push_back(P.radius[i]); }
  out.fraction = solids_fraction_profile(x, r, 2, z_lo, z_hi, nbins, M_PI * R * R).fraction;
  return out;
}

}  // namespace cohdem::beds
