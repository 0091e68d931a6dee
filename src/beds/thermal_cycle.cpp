// `cohdem bed thermal-cycle`: a bed in a pipe under a spring-loaded lid, walls cycled in
// temperature; per cycle the peak contact force, wall stresses and lid travel.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "beds/bed_protocols.hpp"
#include "core/error.hpp"
#include "io/atomic_file.hpp"
#include "io/contact_network.hpp"
#include "io/csv.hpp"
#include "io/plot.hpp"
#include "io/runner.hpp"
#include "thermal/thermal.hpp"

namespace cohdem::beds {

namespace fs = std::filesystem;

namespace {

struct Sample {
  double t, T_mean, T_min, T_max, T_wall, f_max, f_mean, pipe_stress, base_stress, lid_stress, lid_travel;
};

Sample take(const System& s, size_t pipe, size_t base, size_t lid) {
  const ParticleStore& P = s.particles;
  Sample q{};
  q.t = s.time;
  q.T_min = INFINITY;
  q.T_max = -INFINITY;
  for (double T : P.temperature) { q.T_mean += T; q.T_min = std::min(q.T_min, T); q.T_max = std::max(q.T_max, T); }
  q.T_mean = P.size() ? q.T_mean / double(P.size()) : NAN;
  if (!P.size()) q.T_min = q.T_max = NAN;
  q.T_wall = s.thermal->wall_temperature(pipe, s.time);
  const ContactForceStats fs = pair_force_stats(s);
  q.f_max = fs.max;
  q.f_mean = fs.mean;
  const Wall &Wp = s.walls[pipe], &Wb = s.walls[base], &Wl = s.walls[lid];
  const double A = M_PI * Wp.radius * Wp.radius;
  const double H = std::max(1e-12, dot(Wl.point - Wb.point, Wb.normal));
  double fn = 0;
  const NeighborList& nl = s.nl;
  const auto& fw = s.wall_forces();
  const auto& cw = s.wall_contact_points();
  for (size_t i = 0; i + 1 < nl.wstart.size(); ++i)
    for (uint32_t e = nl.wstart[i]; e < nl.wstart[i + 1]; ++e)
      if (nl.whist.live[e] && nl.wall[e] == pipe) fn += dot(fw[e], normalized(P.x[i] - cw[e]));
  q.pipe_stress = fn / (2 * M_PI * Wp.radius * H);
  q.base_stress = -dot(Wb.force, Wb.normal) / A;
  q.lid_stress = -dot(Wl.force, Wl.normal) / A;
  q.lid_travel = -Wl.travel;  // upward (away from the bed) positive
  return q;
}

}  // namespace

int run_thermal_cycle(const BedOptions& o, const ThermalCycleOptions& t) {
  const Case c = load(o);
  const fs::path out = out_folder(o, c);
  const fs::path ckpt = out / "thermal_cycle_checkpoint.bin";
  Stage st = open_stage(c, o, ckpt);
  System* const s = st.s.get();
  if (!s->thermal) throw InputError(c.file, 0, "thermal", "thermal-cycle needs a case with a [thermal] table");
  const size_t pipe = find_wall(c, *s, t.pipe, "--pipe"), base = find_wall(c, *s, t.base, "--base"),
               lid = find_wall(c, *s, t.lid, "--lid");
  check_pipe(c, *s, pipe, base);
  if (s->walls[lid].control != WallControl::Spring)
    throw InputError(c.file, 0, "wall." + t.lid + ".control", "the lid must have control = \"spring\"");
  if (!s->thermal->wall_fixed(pipe))
    throw InputError(c.file, 0, "wall." + t.pipe + ".temperature", "the pipe wall needs a temperature (schedule)");
  fs::create_directories(out);
  std::vector<Sample> samples;
  const uint64_t every = std::max<uint64_t>(1, uint64_t(std::llround(t.sample / c.cfg.dt)));
  CsvWriter csv(out / "thermal_cycle.csv", {"time", "T_mean", "T_min", "T_max", "T_wall", "max_contact_force",
                                             "mean_contact_force", "pipe_wall_stress", "base_stress", "lid_stress",
                                             "lid_travel"});
  auto row = [&](const Sample& q) {
    csv.row({q.t, q.T_mean, q.T_min, q.T_max, q.T_wall, q.f_max, q.f_mean, q.pipe_stress, q.base_stress, q.lid_stress,
             q.lid_travel});
  };
  auto sample = [&](System& sys) {
    samples.push_back(take(sys, pipe, base, lid));
    row(samples.back());
  };
  // The samples so far travel with the checkpoint (11 numbers each, exact in CBOR).
  auto state = [&]() {
    nlohmann::json a = nlohmann::json::array();
    for (const Sample& q : samples)
      a.push_back({q.t, q.T_mean, q.T_min, q.T_max, q.T_wall, q.f_max, q.f_mean, q.pipe_stress, q.base_stress,
                   q.lid_stress, q.lid_travel});
    return a;
  };
  if (st.resumed) {
    for (const auto& r : st.state) {
      const std::vector<double> v = r.get<std::vector<double>>();
      samples.push_back({v.at(0), v.at(1), v.at(2), v.at(3), v.at(4), v.at(5), v.at(6), v.at(7), v.at(8), v.at(9), v.at(10)});
      row(samples.back());
    }
  } else {
    s->prepare();
    sample(*s);
  }
  spdlog::info("thermal cycling: {} particles, {:.3g} s, cycles of {:.3g} s from t = {:.3g} s", s->particles.size(),
               c.duration, t.period, t.start);
  run_stage(st, c, o, ckpt, "thermal cycle", sample, every, state);
  csv.flush();
  write_state_vtk(*s, out.string(), "final", true);

  // Per cycle.
  nlohmann::json j;
  j["case"] = c.name;
  j["period"] = t.period;
  j["time_scale"] = s->thermal->settings().time_scale;
  // Whole cycles run; the run ends within a step of start + k period (time is a sum of steps).
  const int ncyc = int(std::floor((s->time + s->cfg.dt - t.start) / t.period + 1e-9));
  const Sample* before = nullptr;
  for (const Sample& q : samples)
    if (q.t <= t.start + 1e-12) before = &q;
  if (before)
    j["before"] = {{"max_contact_force", before->f_max}, {"pipe_wall_stress", before->pipe_stress},
                   {"base_stress", before->base_stress}, {"lid_stress", before->lid_stress}, {"lid_travel", before->lid_travel}};
  for (int k = 0; k < ncyc; ++k) {
    const double a = t.start + k * t.period, b = a + t.period;
    Sample peak{};
    peak.lid_travel = -INFINITY;
    double lid_min = INFINITY;
    const Sample* end = nullptr;
    for (const Sample& q : samples) {
      if (q.t <= a || q.t > b + 1e-12) continue;
      peak.T_max = std::max(peak.T_max, q.T_mean);
      peak.f_max = std::max(peak.f_max, q.f_max);
      peak.pipe_stress = std::max(peak.pipe_stress, q.pipe_stress);
      peak.base_stress = std::max(peak.base_stress, q.base_stress);
      peak.lid_stress = std::max(peak.lid_stress, q.lid_stress);
      peak.lid_travel = std::max(peak.lid_travel, q.lid_travel);
      lid_min = std::min(lid_min, q.lid_travel);
      end = &q;
    }
    if (!end) continue;
    j["cycles"].push_back({{"cycle", k + 1},
                           {"peak_mean_temperature", peak.T_max},
                           {"peak_contact_force", peak.f_max},
                           {"peak_pipe_wall_stress", peak.pipe_stress},
                           {"peak_base_stress", peak.base_stress},
                           {"peak_lid_stress", peak.lid_stress},
                           {"lid_travel_range", peak.lid_travel - lid_min},
                           {"lid_travel_max", peak.lid_travel},
                           {"end", {{"max_contact_force", end->f_max}, {"pipe_wall_stress", end->pipe_stress},
                                    {"base_stress", end->base_stress}, {"lid_travel", end->lid_travel},
                                    {"mean_temperature", end->T_mean}}}});
    spdlog::info("cycle {}: peak contact force {:.4g} N, pipe wall stress {:.4g} Pa, base {:.4g} Pa, lid {:.4g} Pa, lid travel {:.3g} um",
                 k + 1, peak.f_max, peak.pipe_stress, peak.base_stress, peak.lid_stress, 1e6 * (peak.lid_travel - lid_min));
  }
  write_file_atomic(out / "thermal_cycle.json", j.dump(2) + "\n");

  // Plots from a tenth of a period before the first cycle (the pour and the lid drop before it
  // would dwarf the thermal response); lid travel relative to its position at the start.
  const double t_plot = std::max(0.0, t.start - 0.1 * t.period);
  double lid0 = 0;
  for (const Sample& q : samples)
    if (q.t <= t.start + 1e-12) lid0 = q.lid_travel;
  auto series = [&](const std::string& label, double Sample::*m, double scale = 1.0, double offset = 0.0) {
    Series sr{label, {}, {}, "lines"};
    for (const Sample& q : samples)
      if (q.t >= t_plot) { sr.x.push_back(q.t); sr.y.push_back((q.*m - offset) * scale); }
    return sr;
  };
  std::vector<std::pair<double, std::string>> marks;
  for (int k = 0; k < ncyc; ++k) marks.push_back({t.start + k * t.period, "cycle " + std::to_string(k + 1)});
  PlotSpec pT, pL, pS, pF;
  pT.title = "Temperatures";
  pT.xlabel = pL.xlabel = pS.xlabel = pF.xlabel = "time (s, simulated)";
  pT.ylabel = "temperature (K)";
  pT.series = {series("pipe and base wall", &Sample::T_wall), series("bed mean", &Sample::T_mean),
               series("bed min", &Sample::T_min), series("bed max", &Sample::T_max)};
  {  // room above the curves for the legend
    double lo = INFINITY, hi = -INFINITY;
    for (const auto& sr : pT.series)
      for (double y : sr.y)
        if (std::isfinite(y)) { lo = std::min(lo, y); hi = std::max(hi, y); }
    if (hi > lo) pT.yrange = std::pair{lo - 0.05 * (hi - lo), hi + 0.4 * (hi - lo)};
  }
  pL.title = "Lid rise since the first cycle began";
  pL.ylabel = "lid rise (um)";
  pL.series = {series("lid", &Sample::lid_travel, 1e6, lid0)};
  pS.title = "Stresses";
  pS.ylabel = "stress (Pa)";
  pS.series = {series("pipe wall (normal)", &Sample::pipe_stress), series("base", &Sample::base_stress),
               series("lid", &Sample::lid_stress)};
  pF.title = "Contact forces";
  pF.ylabel = "force (N)";
  pF.series = {series("largest", &Sample::f_max), series("mean", &Sample::f_mean)};
  for (PlotSpec* p : {&pT, &pL, &pS, &pF}) p->vlines = marks;
  plot_png_panels(out / "thermal_cycle.png", {pT, pL, pS, pF}, 2);
  fmt::print("{} cycles; {}\n", ncyc, (out / "thermal_cycle.json").string());
  return 0;
}

}  // namespace cohdem::beds
