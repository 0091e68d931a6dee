// `cohdem bed packing`: solids fraction of monosized spheres poured between two walls.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "analysis/packing_profile.hpp"
#include "beds/bed_protocols.hpp"
#include "core/error.hpp"
#include "io/atomic_file.hpp"
#include "io/csv.hpp"
#include "io/plot.hpp"
#include "io/runner.hpp"

namespace cohdem::beds {

namespace fs = std::filesystem;

namespace {

/// The gap: two axis-aligned plane walls facing each other across a horizontal axis.
struct Gap {
  int axis = -1;       ///< 0 (x) or 1 (y)
  double lo = 0, hi = 0;
  int periodic = -1;   ///< the other horizontal axis
  double z_floor = 0;
};

Gap find_gap(const Case& c) {
  Gap g;
  for (const Wall& a : c.walls)
    for (const Wall& b : c.walls) {
      if (a.shape != WallShape::Plane || b.shape != WallShape::Plane) continue;
      for (int d = 0; d < 2; ++d)
        if (a.normal[d] == 1 && b.normal[d] == -1 && g.axis < 0) {
          g.axis = d;
          g.lo = a.point[d];
          g.hi = b.point[d];
        }
    }
  for (const Wall& a : c.walls)
    if (a.shape == WallShape::Plane && a.normal.z == 1) g.z_floor = a.point.z;
  if (g.axis < 0 || !(g.hi > g.lo))
    throw InputError(c.file, 0, "wall", "packing needs two plane walls facing each other across x or y (normals +1 and -1)");
  g.periodic = 1 - g.axis;
  if (!c.cfg.domain.periodic[g.periodic])
    throw InputError(c.file, 0, "domain.periodic",
                     std::string("packing needs the domain periodic in ") + "xy"[g.periodic] + " (along the walls)");
  return g;
}

}  // namespace

int run_packing(const BedOptions& o, const PackingOptions& p) {
  const Case c0 = load(o);
  const Gap gap = find_gap(c0);
  const fs::path out = out_folder(o, c0);
  fs::create_directories(out);
  const double Lp = c0.cfg.domain.hi[gap.periodic] - c0.cfg.domain.lo[gap.periodic];
  const double W = gap.hi - gap.lo;

  nlohmann::json j;
  j["case"] = c0.name;
  j["case_file"] = c0.file;
  j["contact_model"] = c0.model;
  for (const auto& [k, v] : c0.pair_params[0].values()) j["contact"][k] = v;
  std::vector<double> phis, cores;
  std::vector<std::vector<double>> profiles;
  double d = 0;
  int nb = 0;
  for (int seed : p.seeds) {
    Case c = c0;
    c.seed = uint64_t(seed);
    const fs::path ckpt = out / ("seed" + std::to_string(seed) + "_checkpoint.bin");
    Stage st = open_stage(c, o, ckpt);
    spdlog::info("seed {}: {} particles, {:.3g} s", seed, st.s->particles.size(), c.duration);
    run_stage(st, c, o, ckpt, "seed " + std::to_string(seed));
    const std::unique_ptr<System> s = std::move(st.s);
    const ParticleStore& P = s->particles;
    d = 2 * mean_radius(*s);
    std::vector<Vec3> x;
    std::vector<double> r, z;
    for (size_t i = 0; i < P.size(); ++i) {
      if (P.flag[i] != kFree) continue;
      Vec3 xi = P.x[i];
      const double lo = c.cfg.domain.lo[gap.periodic];
      xi[gap.periodic] = lo + std::fmod(std::fmod(xi[gap.periodic] - lo, Lp) + Lp, Lp);
      x.push_back(xi);
      r.push_back(P.radius[i]);
      z.push_back(xi.z);
    }
    std::sort(z.begin(), z.end());
    const double top = z[size_t(0.99 * double(z.size() - 1))];
    const double zlo = gap.z_floor + p.band_margin * d, zhi = top - p.band_margin * d;
    if (!(zhi > zlo + d))
      throw RunError("the bed is too shallow for a band " + std::to_string(p.band_margin) + " diameters from floor and top");
    // Mean over the band: exact in z (all spheres lie between the walls).
    const double phi = mean_solids_fraction(x, r, 2, zlo, zhi, W * Lp);
    // Profile across the gap from the spheres centred in the band.
    std::vector<Vec3> xb;
    std::vector<double> rb;
    for (size_t q = 0; q < x.size(); ++q)
      if (x[q].z >= zlo && x[q].z < zhi) { xb.push_back(x[q]); rb.push_back(r[q]); }
    nb = std::max(2, int(std::lround(W / d * p.bins_per_diameter)));
    const Profile prof = solids_fraction_profile(xb, rb, gap.axis, gap.lo, gap.hi, nb, Lp * (zhi - zlo));
    const double core = mean_solids_fraction(xb, rb, gap.axis, gap.lo + 2 * d, gap.hi - 2 * d, Lp * (zhi - zlo));
    phis.push_back(phi);
    cores.push_back(core);
    profiles.push_back(prof.fraction);
    spdlog::info("seed {}: solids fraction {:.4f} (band z = {:.4g}..{:.4g} m), core (2 d from the walls) {:.4f}", seed, phi,
                 zlo, zhi, core);
    j["seeds"].push_back({{"seed", seed}, {"particles", x.size()}, {"solids_fraction", phi},
                          {"core_solids_fraction", core}, {"band", {zlo, zhi}}, {"bed_top", top}});
    if (seed == p.seeds.back()) write_state_vtk(*s, out.string(), "seed" + std::to_string(seed), true);
  }
  auto stats = [](const std::vector<double>& v) {
    double m = 0, q = 0;
    for (double x : v) m += x;
    m /= double(v.size());
    for (double x : v) q += (x - m) * (x - m);
    return std::pair<double, double>{m, v.size() > 1 ? std::sqrt(q / double(v.size() - 1)) : 0.0};
  };
  const auto [phi_m, phi_s] = stats(phis);
  const auto [core_m, core_s] = stats(cores);
  j["diameter"] = d;
  j["gap_diameters"] = W / d;
  j["solids_fraction_mean"] = phi_m;
  j["solids_fraction_std"] = phi_s;
  j["core_solids_fraction_mean"] = core_m;
  j["core_solids_fraction_std"] = core_s;

  // Profile folded about the mid-plane (distance from the nearer wall), averaged over seeds.
  const int half = nb / 2;
  std::vector<double> dist, mean(half, 0.0), lo(half, INFINITY), hi(half, -INFINITY);
  for (int b = 0; b < half; ++b) {
    dist.push_back((b + 0.5) * W / nb / d);
    for (const auto& f : profiles) {
      const double v = 0.5 * (f[b] + f[nb - 1 - b]);
      mean[b] += v / double(profiles.size());
      lo[b] = std::min(lo[b], v);
      hi[b] = std::max(hi[b], v);
    }
  }
  {
    CsvWriter csv(out / "packing_profile.csv", {"distance_from_wall_diameters", "solids_fraction", "min_over_seeds",
                                                "max_over_seeds"});
    for (int b = 0; b < half; ++b) csv.row({dist[b], mean[b], lo[b], hi[b]});
  }
  write_file_atomic(out / "packing.json", j.dump(2) + "\n");
  PlotSpec ps;
  const double mu = c0.pair_params[0].has("mu") ? c0.pair_params[0].values().at("mu") : 0.0;
  ps.title = fmt::format("{}: mu = {:g}, mean solids fraction {:.3f} +/- {:.3f} ({} seeds)", c0.name, mu, phi_m, phi_s,
                         phis.size());
  ps.xlabel = "distance from the wall / particle diameter";
  ps.ylabel = "solids fraction";
  ps.series.push_back({"profile (mean of seeds)", dist, mean, "lines"});
  ps.series.push_back({"band mean", {0, dist.back()}, {phi_m, phi_m}, "lines"});
  ps.yrange = std::pair{0.0, 1.0};
  plot_png(out / "packing_profile.png", ps);
  fmt::print("solids fraction {:.4f} +/- {:.4f} over {} seeds (core {:.4f} +/- {:.4f}); {}\n", phi_m, phi_s, phis.size(),
             core_m, core_s, (out / "packing.json").string());
  return 0;
}

}  // namespace cohdem::beds
