// `cohdem bed janssen`: pedestal force against bed height with the pipe wall moving up (silo,
// Walton Eq. 13) and down (piston, Eq. 16), mu k fitted, stresses against depth.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "analysis/janssen.hpp"
#include "beds/bed_protocols.hpp"
#include "beds/bed_stress.hpp"
#include "core/error.hpp"
#include "io/atomic_file.hpp"
#include "io/csv.hpp"
#include "io/plot.hpp"
#include "io/runner.hpp"

namespace cohdem::beds {

namespace fs = std::filesystem;

namespace {

constexpr double kPaperMuK = 0.232;  // Walton (seed 001): 3 mm glass beads, 4 cm acrylic pipe

struct Point {
  double height = 0, force = 0, force_sd = 0, weight = 0;
  size_t particles = 0;
  double max_overlap = 0;
};

/// k, mobilised wall friction and their product from one stress profile (slices from one
/// slice above the base to two below the surface).
nlohmann::json stress_fit(const SliceStresses& s, double z0, double top, double d, bool piston, std::vector<double>& depth) {
  std::vector<double> sv, sw, tw, sh;
  depth.clear();
  for (size_t b = 0; b + 1 < s.edges.size(); ++b) {
    const double zc = s.centre(b);
    if (s.edges[b] < z0 + d || s.edges[b + 1] > top - 2 * d) continue;
    depth.push_back(top - zc);
    sv.push_back(s.sigma_v[b]);
    sw.push_back(s.wall_normal[b]);
    sh.push_back(s.sigma_h[b]);
    tw.push_back(piston ? -s.wall_shear[b] : s.wall_shear[b]);  // friction resisting the relative motion
  }
  nlohmann::json j;
  if (sv.size() < 2) return j;
  // A bed that carries no load in its slices (not settled: the fill too short) cannot be
  // fitted; the tables and plots already measured are still written, with the reason here.
  try {
    const RatioFit k = fit_stress_ratio(sv, sw);
    const RatioFit kb = fit_stress_ratio(sv, sh);
    const RatioFit mu = fit_wall_friction(sw, tw);
    j = {{"k_wall", k.value}, {"k_bulk", kb.value}, {"mu_wall_mobilised", mu.value}, {"mu_k", mu.value * k.value},
         {"slices", sv.size()}};
  } catch (const std::invalid_argument& e) {
    const std::string why = std::string(e.what()) + " (is the bed settled? a longer fill, simulation.duration, may help)";
    spdlog::warn("stress fit of the {} bed skipped: {}", piston ? "wall-down" : "wall-up", why);
    j = {{"skipped", why}, {"slices", sv.size()}};
  }
  return j;
}

}  // namespace

void check_pipe(const Case& c, const System& s, size_t pipe, size_t base) {
  const Wall &P = s.walls[pipe], &B = s.walls[base];
  if (P.shape != WallShape::Cylinder || !P.inside || std::fabs(std::fabs(P.normal.z) - 1) > 1e-12)
    throw InputError(c.file, 0, "wall." + P.name, "the pipe must be a cylinder with particles inside and its axis along z");
  if (B.shape != WallShape::Plane || std::fabs(B.normal.z - 1) > 1e-12)
    throw InputError(c.file, 0, "wall." + B.name, "the pedestal must be a plane with normal [0, 0, 1]");
}

PipeFill fill_pipe(const BedOptions& o, const std::string& pipe, const std::string& base) {
  PipeFill f;
  f.c = load(o);
  f.out = out_folder(o, f.c);
  const fs::path ckpt = fs::path(f.out) / "fill_checkpoint.bin";
  Stage st = open_stage(f.c, o, ckpt);
  const System& s = *st.s;
  f.pipe = find_wall(f.c, s, pipe, "--pipe");
  f.base = find_wall(f.c, s, base, "--base");
  check_pipe(f.c, s, f.pipe, f.base);
  fs::create_directories(f.out);
  f.R = s.walls[f.pipe].radius;
  f.z0 = s.walls[f.base].point.z;
  f.g = norm(f.c.cfg.gravity);
  spdlog::info("fill: {} particles, {:.3g} s", s.particles.size(), f.c.duration);
  run_stage(st, f.c, o, ckpt, "fill");
  f.s = std::move(st.s);
  f.bed = measure_pipe_bed(*f.s, f.R, f.z0);
  f.d = 2 * mean_radius(*f.s);
  return f;
}

PipeMotion move_pipe(const Case& c, const System& filled, size_t pipe, size_t base, double height, double velocity,
                     double travel, double settle, double rho_bulk, bool stresses, double slice,
                     const std::string& label, bool quiet, const std::string& vtk_dir) {
  auto t = clone(c, filled);
  const double R = t->walls[pipe].radius, z0 = t->walls[base].point.z;
  trim_above(*t, z0 + height);
  advance(*t, settle, label + " settle", quiet);
  const PipeBed bed = measure_pipe_bed(*t, R, z0);
  t->walls[pipe].velocity = {0, 0, velocity};
  const double duration = travel / std::fabs(velocity), t_half = t->time + 0.5 * duration;
  const uint64_t every = std::max<uint64_t>(1, uint64_t(duration / t->cfg.dt / 400));
  double sum = 0, sum2 = 0;
  size_t n = 0, ns = 0;
  SliceStresses acc;
  const double d = 2 * mean_radius(*t);
  const int nbins = std::max(2, int(std::floor((bed.top + 2 * d - z0) / (slice * d))));
  std::unique_ptr<CsvWriter> trace;  // the pedestal load through the motion (stress stages)
  if (stresses)
    trace = std::make_unique<CsvWriter>(fs::path(vtk_dir) / (label + "_trace.csv"),
                                        std::vector<std::string>{"time", "pipe_travel", "pedestal_force"});
  const double t_start = t->time;
  auto sample = [&](System& s) {
    const double load = -dot(s.walls[base].force, s.walls[base].normal);
    if (trace) trace->row({s.time, velocity * (s.time - t_start), load});
    if (s.time < t_half) return;
    sum += load;
    sum2 += load * load;
    ++n;
    if (stresses && n % 8 == 1) {
      acc.accumulate(slice_stresses(s, pipe, z0, z0 + nbins * slice * d, nbins), 1.0);
      ++ns;
    }
  };
  advance(*t, duration, label, quiet, sample, every);
  PipeMotion m;
  m.height = bed.mass / (rho_bulk * M_PI * R * R);
  m.force = n ? sum / double(n) : 0.0;
  m.force_sd = n > 1 ? std::sqrt(std::max(0.0, sum2 / double(n) - m.force * m.force)) : 0.0;
  m.weight = bed.mass * norm(t->cfg.gravity);
  m.particles = bed.count;
  m.solids_fraction = bed.phi;
  m.max_overlap = t->max_relative_overlap();
  if (stresses && ns) {
    acc.scale(1.0 / double(ns));  // the mean of the samples
    m.stress = acc;
    write_state_vtk(*t, vtk_dir, label, true);
  }
  spdlog::info("{}: bed height {:.4f} m ({} particles), pedestal force {:.4g} +/- {:.2g} N, weight {:.4g} N, "
               "largest overlap {:.2f}% of the radius", label, m.height, m.particles, m.force, m.force_sd, m.weight,
               100 * m.max_overlap);
  return m;
}

int run_janssen(const BedOptions& o, const JanssenOptions& jo) {
  PipeFill f = fill_pipe(o, jo.pipe, jo.base);
  const Case& c = f.c;
  auto& s = f.s;
  const size_t pipe = f.pipe, base = f.base;
  const fs::path out = f.out;
  const double R = f.R, z0 = f.z0, g = f.g, d = f.d;
  const PipeBed b0 = f.bed;
  spdlog::info("filled bed: height {:.4f} m ({:.1f} diameters of the pipe), solids fraction {:.4f}, bulk density {:.1f} kg/m^3",
               b0.height, b0.height / (2 * R), b0.phi, b0.rho_bulk);
  std::vector<double> heights = jo.heights;
  if (heights.empty())
    for (int k = 0; k < jo.count; ++k) heights.push_back(0.9 * b0.height * double(jo.count - k) / jo.count);
  std::sort(heights.rbegin(), heights.rend());
  for (double H : heights)
    if (!(H > 2 * d) || H > b0.top - z0)
      throw InputError("command line", 0, "--heights", "bed heights must lie between 2 diameters and the filled top (" +
                                                           std::to_string(b0.top - z0) + " m)");
  const JanssenSetup js{b0.rho_bulk, g, R};

  nlohmann::json j;
  j["case"] = c.name;
  j["fill"] = {{"particles", b0.count}, {"height", b0.height}, {"solids_fraction", b0.phi}, {"bulk_density", b0.rho_bulk},
               {"pipe_radius", R}, {"diameter", d}};
  j["protocol"] = {{"speed", jo.speed}, {"travel_up", jo.travel_up}, {"travel_down", jo.travel_down}, {"settle", jo.settle}};
  std::vector<std::string> dirs;
  if (jo.direction != "down") dirs.push_back("up");
  if (jo.direction != "up") dirs.push_back("down");
  std::map<std::string, std::vector<Point>> pts;
  std::map<std::string, SliceStresses> prof;
  std::map<std::string, double> prof_top;
  for (const auto& dir : dirs) {
    const bool up = dir == "up";
    for (size_t k = 0; k < heights.size(); ++k) {
      const std::string label = "wall " + dir + " H=" + fmt::format("{:.3f}", heights[k]);
      const PipeMotion m =
          move_pipe(c, *s, pipe, base, heights[k], up ? jo.speed : -jo.speed, up ? jo.travel_up : jo.travel_down,
                    jo.settle, b0.rho_bulk, k == 0, jo.slice, k == 0 ? "janssen_" + dir : label, o.quiet, out.string());
      pts[dir].push_back({m.height, m.force, m.force_sd, m.weight, m.particles, m.max_overlap});
      if (k == 0) { prof[dir] = m.stress; prof_top[dir] = z0 + m.height; }
    }
  }

  // Fits and predictions.
  {
    CsvWriter csv(out / "janssen.csv", {"direction_up", "height", "pedestal_force", "force_sd", "weight", "particles",
                                        "janssen_fit", "prediction_from_wall_up"});
    JanssenFit up_fit, down_fit;
    auto HF = [&](const std::string& dir) {
      std::vector<double> H, F;
      for (const auto& p : pts[dir]) { H.push_back(p.height); F.push_back(p.force); }
      return std::pair{H, F};
    };
    if (pts.count("up")) {
      auto [H, F] = HF("up");
      up_fit = fit_janssen_mu_k(JanssenMode::Silo, H, F, js);
      j["wall_up"] = {{"mu_k", up_fit.mu_k}, {"asymptote_force", up_fit.asymptote_force},
                      {"asymptote_stress", up_fit.asymptote_stress}, {"rms_residual", up_fit.rms_residual},
                      {"at_bound", up_fit.at_bound}, {"tallest_force", F.front()},
                      {"tallest_over_asymptote", F.front() / up_fit.asymptote_force},
                      {"paper_asymptote_force", janssen_force(JanssenMode::Silo, kPaperMuK, 1e3, js)}};
    }
    if (pts.count("down")) {
      auto [H, F] = HF("down");
      down_fit = fit_janssen_mu_k(JanssenMode::Piston, H, F, js);
      j["wall_down"] = {{"mu_k", down_fit.mu_k}, {"rms_residual", down_fit.rms_residual}, {"at_bound", down_fit.at_bound}};
      if (pts.count("up")) {
        double worst = 0, sum = 0;
        for (size_t k = 0; k < H.size(); ++k) {
          const double r = F[k] / janssen_force(JanssenMode::Piston, up_fit.mu_k, H[k], js);
          worst = std::max(worst, std::fabs(std::log(r)));
          sum += std::log(r);
        }
        j["wall_down"]["prediction_from_wall_up"] = {{"geometric_mean_ratio", std::exp(sum / double(H.size()))},
                                                     {"worst_ratio", std::exp(worst)}};
      }
    }
    for (const auto& dir : dirs)
      for (const auto& p : pts[dir]) {
        const bool up = dir == "up";
        const double fit = up ? janssen_force(JanssenMode::Silo, up_fit.mu_k, p.height, js)
                              : janssen_force(JanssenMode::Piston, down_fit.mu_k, p.height, js);
        const double pred = pts.count("up") ? janssen_force(up ? JanssenMode::Silo : JanssenMode::Piston, up_fit.mu_k, p.height, js) : NAN;
        csv.row({up ? 1.0 : 0.0, p.height, p.force, p.force_sd, p.weight, double(p.particles), fit, pred});
        j["points"][dir].push_back({{"height", p.height}, {"force", p.force}, {"force_sd", p.force_sd}, {"weight", p.weight},
                                    {"particles", p.particles}, {"max_overlap", p.max_overlap}});
      }
    j["paper_mu_k"] = kPaperMuK;

    // Plots: force against height with the fitted curves (and the paper's mu k for reference).
    const double Hmax = heights.front() * 1.05;
    auto curve = [&](JanssenMode m, double muk, const std::string& label) {
      Series sr{label, {}, {}, "lines"};
      for (int q = 0; q <= 100; ++q) {
        const double H = Hmax * q / 100.0;
        sr.x.push_back(H);
        sr.y.push_back(q == 0 && m == JanssenMode::Piston ? NAN : janssen_force(m, muk, H, js));
      }
      return sr;
    };
    auto points = [&](const std::string& dir, const std::string& label) {
      Series sr{label, {}, {}, "points"};
      for (const auto& p : pts[dir]) { sr.x.push_back(p.height); sr.y.push_back(p.force); }
      return sr;
    };
    auto weight = [&](const std::string& dir) {
      Series sr{"bed weight (no wall friction)", {}, {}, "linespoints"};
      for (const auto& p : pts[dir]) { sr.x.push_back(p.height); sr.y.push_back(p.weight); }
      return sr;
    };
    if (pts.count("up")) {
      PlotSpec ps;
      ps.title = fmt::format("Wall up (silo): fitted mu k = {:.3f}, asymptote {:.3g} N", up_fit.mu_k, up_fit.asymptote_force);
      ps.xlabel = "bed height (m)";
      ps.ylabel = "pedestal force (N)";
      ps.series = {points("up", "DEM, wall moving up"), curve(JanssenMode::Silo, up_fit.mu_k, "Eq. 13, fitted mu k"),
                   curve(JanssenMode::Silo, kPaperMuK, "Eq. 13, mu k = 0.232 (experiment)"), weight("up"),
                   {"asymptote rho g R/(2 mu k) pi R^2", {0, Hmax}, {up_fit.asymptote_force, up_fit.asymptote_force}, "lines"}};
      plot_png(out / "janssen_up.png", ps);
    }
    if (pts.count("down")) {
      PlotSpec ps;
      ps.title = fmt::format("Wall down (piston): fitted mu k = {:.3f}", down_fit.mu_k);
      ps.xlabel = "bed height (m)";
      ps.ylabel = "pedestal force (N)";
      ps.logy = true;
      ps.series = {points("down", "DEM, wall moving down"), curve(JanssenMode::Piston, down_fit.mu_k, "Eq. 16, fitted mu k"),
                   curve(JanssenMode::Piston, kPaperMuK, "Eq. 16, mu k = 0.232 (experiment)"), weight("down")};
      if (pts.count("up")) {
        ps.series.insert(ps.series.begin() + 1,
                         curve(JanssenMode::Piston, up_fit.mu_k, fmt::format("Eq. 16 with mu k = {:.3f} from wall up", up_fit.mu_k)));
        ps.title += fmt::format("; predicted from wall up: {:.3f}", up_fit.mu_k);
      }
      plot_png(out / "janssen_down.png", ps);
    }
  }

  // Stresses against depth in the tallest bed.
  std::vector<PlotSpec> panels;
  for (const auto& dir : dirs) {
    const SliceStresses& sp = prof[dir];
    if (sp.edges.empty()) continue;
    const double top = prof_top[dir];
    std::vector<double> depth;
    j["stresses"][dir] = stress_fit(sp, z0, top, d, dir == "down", depth);
    CsvWriter csv(out / ("stress_" + dir + ".csv"), {"z", "depth", "sigma_v", "sigma_h", "wall_normal", "wall_shear", "solids_fraction"});
    PlotSpec ps;
    ps.title = fmt::format("Wall {}: stresses against depth (tallest bed)", dir);
    ps.xlabel = "depth below the surface (m)";
    ps.ylabel = "stress (Pa)";
    Series v{"vertical sigma_v", {}, {}, "linespoints"}, w{"wall normal sigma_w", {}, {}, "linespoints"},
        t{"wall shear (resisting)", {}, {}, "linespoints"};
    for (size_t b = 0; b + 1 < sp.edges.size(); ++b) {
      const double y = top - sp.centre(b);
      csv.row({sp.centre(b), y, sp.sigma_v[b], sp.sigma_h[b], sp.wall_normal[b], sp.wall_shear[b], sp.fraction[b]});
      if (y < 0) continue;
      v.x.push_back(y); v.y.push_back(sp.sigma_v[b]);
      w.x.push_back(y); w.y.push_back(sp.wall_normal[b]);
      t.x.push_back(y); t.y.push_back(dir == "down" ? -sp.wall_shear[b] : sp.wall_shear[b]);
    }
    ps.series = {v, w, t};
    panels.push_back(ps);
  }
  if (!panels.empty()) plot_png_panels(out / "janssen_stress.png", panels, int(panels.size()));
  write_file_atomic(out / "janssen.json", j.dump(2) + "\n");
  // A fit whose minimum lies at the edge of its search range says so (an unsettled bed with
  // no load on the pedestal gives one).
  auto bound = [&](const char* key) {
    return j[key].value("at_bound", false) ? " (at the bound of the search range: not a fit)" : "";
  };
  if (j.contains("wall_up")) fmt::print("wall up: mu k = {:.4f} (paper 0.232){}\n", double(j["wall_up"]["mu_k"]), bound("wall_up"));
  if (j.contains("wall_down")) fmt::print("wall down: mu k = {:.4f}{}\n", double(j["wall_down"]["mu_k"]), bound("wall_down"));
  fmt::print("{}\n", (out / "janssen.json").string());
  return 0;
}

}  // namespace cohdem::beds
