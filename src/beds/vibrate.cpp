// `cohdem bed vibrate`: densify a poured bed by shaking its container vertically, and compare
// the piston (wall-down) force of the loose and the dense bed at the same bed height.
#include <spdlog/spdlog.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "analysis/janssen.hpp"
#include "analysis/packing_profile.hpp"
#include "beds/bed_protocols.hpp"
#include "io/atomic_file.hpp"
#include "io/plot.hpp"
#include "io/runner.hpp"

namespace cohdem::beds {

namespace fs = std::filesystem;

namespace {

Series vertical_profile(const System& s, double R, double z0, double top, double d, const std::string& label) {
  std::vector<Vec3> x;
  std::vector<double> r;
  for (size_t i = 0; i < s.particles.size(); ++i)
    if (s.particles.flag[i] == kFree) { x.push_back(s.particles.x[i]); r.push_back(s.particles.radius[i]); }
  const int nb = std::max(2, int((top - z0) / (0.5 * d)));
  const Profile p = solids_fraction_profile(x, r, 2, z0, top, nb, M_PI * R * R);
  Series sr{label, {}, {}, "lines"};
  for (int b = 0; b < nb; ++b) { sr.x.push_back(p.centre(b) - z0); sr.y.push_back(p.fraction[b]); }
  return sr;
}

}  // namespace

int run_vibrate(const BedOptions& o, const VibrateOptions& v) {
  PipeFill f = fill_pipe(o, v.pipe, v.base);
  const Case& c = f.c;
  auto& s = f.s;
  const size_t pipe = f.pipe, base = f.base;
  const fs::path out = f.out;
  const double R = f.R, z0 = f.z0, g = f.g, d = f.d;
  const PipeBed loose = f.bed;

  // Shake a clone: pipe and base oscillate together, a whole number of cycles (so the walls
  // end where they started), then settle.
  auto dense = clone(c, *s);
  const double cycles = std::max(1.0, std::round(v.cycles));
  for (size_t w : {pipe, base}) {
    dense->walls[w].osc_amplitude = v.amplitude;
    dense->walls[w].osc_frequency = v.frequency;
    dense->walls[w].osc_dir = {0, 0, 1};
  }
  const double Gamma = v.amplitude * std::pow(2 * M_PI * v.frequency, 2) / g;
  spdlog::info("shaking: amplitude {:.3g} m, {:.3g} Hz (Gamma = {:.2f}), {:.0f} cycles", v.amplitude, v.frequency, Gamma, cycles);
  advance(*dense, cycles / v.frequency, "shake", o.quiet);
  for (size_t w : {pipe, base}) dense->walls[w].osc_amplitude = 0;
  advance(*dense, v.settle, "settle", o.quiet);
  const PipeBed packed = measure_pipe_bed(*dense, R, z0);
  spdlog::info("solids fraction {:.4f} -> {:.4f} ({:+.2f}%), bed height {:.4f} -> {:.4f} m", loose.phi, packed.phi,
               100 * (packed.phi / loose.phi - 1), loose.height, packed.height);
  write_state_vtk(*dense, out.string(), "shaken", true);

  // Piston test on both at the same bed height (same slug length; the dense one is heavier).
  const double H = v.height > 0 ? v.height : 0.9 * std::min(loose.top, packed.top) - z0;
  const PipeMotion a = move_pipe(c, *s, pipe, base, H, -v.speed, v.travel, 0.02, loose.rho_bulk, false, 2, "piston loose", o.quiet, out.string());
  const PipeMotion b = move_pipe(c, *dense, pipe, base, H, -v.speed, v.travel, 0.02, packed.rho_bulk, false, 2, "piston dense", o.quiet, out.string());
  auto muk = [&](const PipeMotion& m, double rho) {
    const double h = m.height;
    const double f = m.force;
    return fit_janssen_mu_k(JanssenMode::Piston, std::span<const double>(&h, 1), std::span<const double>(&f, 1), {rho, g, R}).mu_k;
  };
  nlohmann::json j;
  j["case"] = c.name;
  j["shaking"] = {{"amplitude", v.amplitude}, {"frequency", v.frequency}, {"cycles", cycles}, {"Gamma", Gamma}};
  j["loose"] = {{"solids_fraction", loose.phi}, {"height", loose.height}, {"piston_height", a.height},
                {"piston_force", a.force}, {"piston_force_sd", a.force_sd}, {"weight", a.weight}, {"mu_k", muk(a, loose.rho_bulk)},
                {"max_overlap", a.max_overlap}};
  j["dense"] = {{"solids_fraction", packed.phi}, {"height", packed.height}, {"piston_height", b.height},
                {"piston_force", b.force}, {"piston_force_sd", b.force_sd}, {"weight", b.weight}, {"mu_k", muk(b, packed.rho_bulk)},
                {"max_overlap", b.max_overlap}};
  j["densification_percent"] = 100 * (packed.phi / loose.phi - 1);
  j["force_ratio"] = b.force / a.force;
  j["paper"] = "up to 5x the piston force for 3.5% denser packing (Arroyo-Cetto et al. 2003, cited by Walton)";
  write_file_atomic(out / "vibrate.json", j.dump(2) + "\n");

  PlotSpec ps;
  ps.title = fmt::format("Shaking (Gamma = {:.1f}, {:.0f} cycles): solids fraction {:.3f} -> {:.3f}, piston force x {:.2f}", Gamma,
                         cycles, loose.phi, packed.phi, b.force / a.force);
  ps.xlabel = "height above the base (m)";
  ps.ylabel = "solids fraction";
  ps.series = {vertical_profile(*s, R, z0, loose.top + d, d, "poured"), vertical_profile(*dense, R, z0, packed.top + d, d, "shaken")};
  ps.yrange = std::pair{0.0, 0.8};
  plot_png(out / "vibrate_profile.png", ps);
  fmt::print("solids fraction {:.4f} -> {:.4f} ({:+.2f}%); piston force at H = {:.3f} m: {:.4g} N -> {:.4g} N (x {:.2f}); {}\n",
             loose.phi, packed.phi, 100 * (packed.phi / loose.phi - 1), H, a.force, b.force, b.force / a.force,
             (out / "vibrate.json").string());
  return 0;
}

}  // namespace cohdem::beds
