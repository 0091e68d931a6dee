#include "apps/ring_shear.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "analysis/yield_locus.hpp"
#include "apps/ring_shear_spec.hpp"
#include "core/error.hpp"
#include "io/checkpoint.hpp"
#include "io/atomic_file.hpp"
#include "io/csv.hpp"
#include "io/plot.hpp"
#include "io/toml_section.hpp"
#include "io/vtk.hpp"
#include "sim/timestep_audit.hpp"

namespace cohdem {

namespace fs = std::filesystem;

RingShearSpec parse_ring_shear(Section& s, const std::vector<std::string>& materials, const std::vector<double>& densities) {
  RingShearSpec r;
  r.line = s.line();
  auto mat = [&](const std::string& key) {
    const std::string name = s.str(key, std::nullopt);
    for (size_t i = 0; i < materials.size(); ++i)
      if (materials[i] == name) return int(i);
    s.fail(key, "unknown material '" + name + "'");
  };
  r.cell = s.str("cell", "shear_box", {"shear_box", "annulus"});
  if (r.cell == "shear_box") {
    r.length = s.num("length", std::nullopt, 0, kInf, true, "m");
    r.width = s.num("width", r.length, 0, kInf, true, "m");
  } else {
    r.r_inner = s.num("r_inner", std::nullopt, 0, kInf, true, "m");
    r.r_outer = s.num("r_outer", std::nullopt, r.r_inner, kInf, true, "m");
  }
  r.material = mat("material");
  r.base_material = mat("base_material");
  r.wall_material = r.cell == "annulus" ? mat("wall_material") : r.base_material;
  r.size = read_size_distribution(*s.table("size", true));
  r.bed_height = s.num("bed_height", std::nullopt, 0, kInf, true, "m");
  r.packing_guess = s.num("packing_guess", 0.55, 0.2, 0.74, false, "");
  r.rough_layers = s.boolean("rough_layers", true);
  r.fill_kadh_fraction = s.num("fill_kadh_fraction", 0.1, 0, kInf, false, "(of k2)");
  r.settle_time = s.num("settle_time", 1.0, 0, kInf, false, "s");
  r.settle_velocity = s.num("settle_velocity", 0.05, 0, kInf, true, "m/s");
  r.approach_speed = s.num("approach_speed", 0.2, 0, kInf, true, "m/s");
  r.sigma_pre = s.num("sigma_pre", std::nullopt, 0, kInf, true, "Pa");
  r.fractions = s.numbers("fractions", r.fractions);
  if (r.fractions.size() < 2) s.fail("fractions", "at least two shear points are needed for a yield locus");
  for (double f : r.fractions)
    if (!(f > 0 && f < 1)) s.fail("fractions", "each fraction of sigma_pre must be in (0, 1)");
  // Shear speed: given, or the fastest that keeps the inertial number at the lowest shear
  // point (the most demanding) at inertial_number_max; when both are given, checked.
  r.inertial_number_max = s.num("inertial_number_max", 0.0, 0, 1, false, "");
  const bool speed_given = s.has("shear_velocity");
  r.shear_velocity = s.num("shear_velocity", 0.02, 0, kInf, true, "m/s");
  if (r.inertial_number_max > 0) {
    const double rho = densities.at(size_t(r.material));
    const double sig_low = *std::min_element(r.fractions.begin(), r.fractions.end()) * r.sigma_pre;
    const double v_max = r.inertial_number_max / ring_shear_inertial_number(1.0, sig_low, rho);  // I is linear in v
    if (!speed_given) {
      r.shear_velocity = v_max;
    } else if (ring_shear_inertial_number(r.shear_velocity, sig_low, rho) > r.inertial_number_max * (1 + 1e-9)) {
      s.fail("shear_velocity", fmt::format("{} m/s gives an inertial number of {:.3g} at the lowest shear point ({:.4g} Pa), above "
                                           "inertial_number_max = {:.3g}: at most {:.4g} m/s (or leave shear_velocity out)",
                                           r.shear_velocity, ring_shear_inertial_number(r.shear_velocity, sig_low, rho), sig_low,
                                           r.inertial_number_max, v_max));
    }
  }
  r.lid_mass = s.num("lid_mass", 0.0, 0, kInf, false, "kg");
  r.tau_window = s.num("tau_window", 0.0005, 0, kInf, false, "m");
  r.consolidate_time = s.num("consolidate_time", 0.05, 0, kInf, false, "s");
  r.first_preshear_distance = s.num("first_preshear_distance", 0.01, 0, kInf, true, "m");
  r.preshear_distance = s.num("preshear_distance", 0.005, 0, kInf, true, "m");
  r.shear_distance = s.num("shear_distance", 0.005, 0, kInf, true, "m");
  r.relax_time = s.num("relax_time", 0.01, 0, kInf, false, "s");
  r.peak_drop = s.num("peak_drop", 0.1, 0, 1, true, "");
  r.steady_drift = s.num("steady_drift", 0.1, 0, kInf, true, "");
  r.normalize_points = s.boolean("normalize_points", false);
  r.preshear_max_factor = s.num("preshear_max_factor", 2.5, 1, kInf, false, "");
  r.sample_interval = s.num("sample_interval", 0.0, 0, kInf, false, "s");
  s.finish();
  return r;
}

namespace {

/// Rough layer: a random monolayer of spheres (2-D random sequential addition) resting on a
/// plane at height z0 (below it when `below`), inside the cell's cross-section.
void rough_layer(System& s, const RingShearSpec& r, double z0, bool below, int body, Rng& rng) {
  const double rmax = r.size.max_radius();
  std::vector<Vec3> placed;
  std::vector<double> radii;
  const double area = r.cell == "shear_box" ? r.length * r.width : M_PI * (r.r_outer * r.r_outer - r.r_inner * r.r_inner);
  const size_t tries = size_t(200 * area / (M_PI * rmax * rmax));
  for (size_t t = 0; t < tries; ++t) {
    const double rad = r.size.sample(rng);
    Vec3 x;
    if (r.cell == "shear_box") {
      x = {rng.uniform(0, r.length), rng.uniform(0, r.width), 0};
    } else {
      const double a = r.r_inner + rad, b = r.r_outer - rad;
      const double rho = std::sqrt(rng.uniform(a * a, b * b)), th = rng.uniform(0, 2 * M_PI);
      x = {rho * std::cos(th), rho * std::sin(th), 0};
    }
    x.z = below ? z0 - rad : z0 + rad;
    bool ok = true;
    for (size_t q = 0; q < placed.size() && ok; ++q) {
      Vec3 d = x - placed[q];
      if (r.cell == "shear_box") {  // periodic in x and y
        d.x -= r.length * std::round(d.x / r.length);
        d.y -= r.width * std::round(d.y / r.width);
      }
      ok = norm2(d) >= (rad + radii[q]) * (rad + radii[q]);
    }
    if (!ok) continue;
    placed.push_back(x);
    radii.push_back(rad);
  }
  for (size_t q = 0; q < placed.size(); ++q) {
    const size_t i = s.add_particle(r.material, radii[q], placed[q]);
    if (body < 0)
      s.particles.flag[i] = kFrozen;
    else
      s.particles.attach(i, body);
  }
}

struct Sample {
  double t, x, sigma, tau, height, density;
  int phase;
  double tau_base;  ///< shear stress on the base (plane + its glued layer)
};

struct Point { double sigma, tau, tau_pre, sigma_pre_meas; };

/// Settings a checkpoint must have been written with to be resumed by this case.
nlohmann::json fingerprint(const Case& c) {
  const RingShearSpec& r = *c.ring_shear;
  return {{"ring_shear.cell", r.cell}, {"ring_shear.length", r.length}, {"ring_shear.width", r.width},
          {"ring_shear.r_inner", r.r_inner}, {"ring_shear.r_outer", r.r_outer}, {"ring_shear.sigma_pre", r.sigma_pre},
          {"ring_shear.fractions", r.fractions}, {"ring_shear.shear_velocity", r.shear_velocity},
          {"ring_shear.lid_mass", r.lid_mass}, {"simulation.dt", c.cfg.dt}, {"simulation.seed", c.seed}};
}

}  // namespace

int run_ring_shear(const Case& c, const RunOptions& opt) {
  using clock = std::chrono::steady_clock;
  const RingShearSpec& r = *c.ring_shear;
  const auto t_wall0 = clock::now();
  const bool resuming = !opt.resume.empty();
  const bool box = r.cell == "shear_box";
  const double area = box ? r.length * r.width : M_PI * (r.r_outer * r.r_outer - r.r_inner * r.r_inner);
  const double r_mean = box ? 0.0 : 0.5 * (r.r_inner + r.r_outer);
  const double rmax = r.size.max_radius();

  // --- System, walls, rough layers --------------------------------------------------------
  auto sys = build_system(c, !resuming);  // materials, model, [[wall]]s if any
  System& s = *sys;
  if (box) {
    s.cfg.domain.lo = {0, 0, -1};
    s.cfg.domain.hi = {r.length, r.width, 1};
    s.cfg.domain.periodic = {true, true, false};
  }
  Wall base;
  base.name = "base";
  base.material = r.base_material;
  base.point = {0, 0, 0};
  base.normal = {0, 0, 1};
  s.walls.push_back(base);
  if (!box) {
    Wall in, out;
    in.name = "inner";
    in.shape = out.shape = WallShape::Cylinder;
    in.material = out.material = r.wall_material;
    in.radius = r.r_inner;
    in.inside = false;
    out.name = "outer";
    out.radius = r.r_outer;
    out.inside = true;
    s.walls.push_back(in);
    s.walls.push_back(out);
  }
  // Fill: insert loosely into a tall region, enough particles for the target bed height.
  const double layer = r.rough_layers ? 2 * rmax : 0.0;
  const double n_target = r.packing_guess * area * r.bed_height / r.size.mean_volume();
  // Random insertion jams near 0.28 in a large region; the region's side walls lower that in
  // narrow cells (under 10 diameters), which are filled looser.
  const double narrow = box ? std::min(r.length, r.width) : r.r_outer - r.r_inner;
  const double h_insert = r.bed_height * r.packing_guess / (narrow >= 20 * rmax ? 0.25 : 0.18);
  const double lid_park = layer + h_insert + 4 * rmax;  // lid out of the way while filling
  Wall lid;
  lid.name = "lid";
  lid.material = r.base_material;
  lid.point = {box ? 0.5 * r.length : 0.0, box ? 0.5 * r.width : 0.0, lid_park};
  lid.center = lid.point;
  lid.normal = {0, 0, -1};
  s.walls.push_back(lid);
  const int lid_idx = int(s.walls.size()) - 1;
  if (r.rough_layers && !resuming) {
    Rng rng(c.seed + 101);
    rough_layer(s, r, 0.0, false, -1, rng);
    rough_layer(s, r, lid_park, true, lid_idx, rng);
  }
  size_t n_fixed = s.particles.size();
  if (!resuming) {
    InsertSpec ins;
    ins.species = r.material;
    ins.size = r.size;
    ins.count = uint64_t(std::ceil(n_target));
    if (box) {
      ins.region.kind = Region::Kind::Box;
      ins.region.lo = {0, 0, layer};
      ins.region.hi = {r.length, r.width, layer + h_insert};
    } else {
      ins.region.kind = Region::Kind::Annulus;
      ins.region.r_in = r.r_inner;
      ins.region.r_out = r.r_outer;
      ins.region.zmin = layer;
      ins.region.zmax = layer + h_insert;
    }
    ins.region.name = "ring_shear fill";
    ins.max_attempts = 20000;
    try {
      s.insert(ins);
    } catch (const RunError& e) {
      throw InputError(c.file, r.line, "ring_shear.bed_height", e.what());
    }
  }
  size_t n_free = s.particles.size() - n_fixed;

  // Full and filling parameters (adhesion reduced while filling, as the MEPA paper does).
  const std::vector<ParamSet> full = c.pair_params;
  std::vector<ParamSet> filling = full;
  const bool has_kadh = std::any_of(full.begin(), full.end(), [](const ParamSet& p) { return p.has("kadh"); });
  if (has_kadh)
    for (auto& p : filling)
      if (p.has("k2")) p.set("kadh", r.fill_kadh_fraction * p.values().at("k2"));
  if (has_kadh && !resuming) s.set_model(make_contact_model(c.model, c.rolling, c.file), filling);

  // Time-step audit.
  const auto audit = audit_timestep(s, min_radius_by_material(s), audit_velocity(c));
  for (const auto& m : audit.messages) spdlog::warn("time step: {}", m);
  if (audit.level == TimestepAudit::Error) throw InputError(c.file, c.dt_line, "simulation.dt", "time step past its hard bound");

  const fs::path out = opt.out_dir.empty() ? fs::path(c.output.folder) : fs::path(opt.out_dir);
  fs::create_directories(out);

  // --- Procedure state, saved with the system at the end of every stage ---------------------
  // Stages: 0 fill, settle and consolidate; 1 first pre-shear; then for each shear point i,
  // 2 + 2i shear to failure, 3 + 2i the pre-shear after it. `stage` counts the stages done.
  int stage = 0;
  double sheared = 0;  // shear displacement of the lid (annulus: at the mean radius), m
  int phase = 0;
  std::vector<Sample> series;
  std::vector<std::pair<double, std::string>> marks;
  std::vector<Point> points;
  std::vector<double> pre_tau, pre_sigma, pre_dist, pre_base;
  double free_mass = 0, wall_before = 0, cpu_before = 0;
  for (size_t i = 0; i < s.particles.size(); ++i)
    if (s.particles.flag[i] == kFree) free_mass += s.particles.mass[i];
  auto save_state = [&] {
    nlohmann::json j;
    j["fingerprint"] = fingerprint(c);
    j["stage"] = stage;
    j["sheared"] = sheared;
    j["phase"] = phase;
    j["free_mass"] = free_mass;
    j["wall_s"] = wall_before + std::chrono::duration<double>(clock::now() - t_wall0).count();
    j["cpu_s"] = cpu_before + double(std::clock()) / CLOCKS_PER_SEC;
    auto& js = j["series"] = nlohmann::json::array();
    for (const auto& q : series) js.push_back({q.t, q.x, q.sigma, q.tau, q.height, q.density, q.phase, q.tau_base});
    auto& jm = j["marks"] = nlohmann::json::array();
    for (const auto& m : marks) jm.push_back({m.first, m.second});
    auto& jp = j["points"] = nlohmann::json::array();
    for (const auto& p : points) jp.push_back({p.sigma, p.tau, p.tau_pre, p.sigma_pre_meas});
    j["pre_tau"] = pre_tau;
    j["pre_sigma"] = pre_sigma;
    j["pre_dist"] = pre_dist;
    j["pre_base"] = pre_base;
    const std::vector<uint8_t> bytes = nlohmann::json::to_cbor(j);
    return std::string(bytes.begin(), bytes.end());
  };
  if (resuming) {
    const std::string blob = read_checkpoint(opt.resume, s);
    nlohmann::json j;
    try {
      if (blob.empty()) throw std::runtime_error("no ring shear state");
      j = nlohmann::json::from_cbor(std::vector<uint8_t>(blob.begin(), blob.end()));
    } catch (const std::exception&) {
      throw InputError(opt.resume, 0, "--resume", "not a checkpoint of a ring shear run");
    }
    const nlohmann::json now = fingerprint(c);
    for (const auto& [key, value] : now.items())
      if (j["fingerprint"][key] != value)
        throw InputError(c.file, r.line, key, "differs from the run that wrote " + opt.resume + " (" + j["fingerprint"][key].dump() +
                                                  " there, " + value.dump() + " here): resume with the same case and --set options");
    stage = j["stage"];
    sheared = j["sheared"];
    phase = j["phase"];
    free_mass = j["free_mass"];
    n_free = size_t(std::count(s.particles.flag.begin(), s.particles.flag.end(), uint8_t(kFree)));
    n_fixed = s.particles.size() - n_free;  // the glued layers
    wall_before = j["wall_s"];
    cpu_before = j["cpu_s"];
    for (const auto& q : j["series"])
      series.push_back({q[0].get<double>(), q[1].get<double>(), q[2].get<double>(), q[3].get<double>(), q[4].get<double>(),
                        q[5].get<double>(), q[6].get<int>(), q[7].get<double>()});
    for (const auto& m : j["marks"]) marks.push_back({m[0].get<double>(), m[1].get<std::string>()});
    for (const auto& p : j["points"]) points.push_back({p[0].get<double>(), p[1].get<double>(), p[2].get<double>(), p[3].get<double>()});
    pre_tau = j["pre_tau"].get<std::vector<double>>();
    pre_sigma = j["pre_sigma"].get<std::vector<double>>();
    pre_dist = j["pre_dist"].get<std::vector<double>>();
    pre_base = j["pre_base"].get<std::vector<double>>();
    spdlog::info("resuming the ring shear test from {} after stage {} of {} (step {}, t = {:.6g} s)", opt.resume, stage,
                 2 + 2 * r.fractions.size(), s.step, s.time);
  }
  const int stages = int(2 + 2 * r.fractions.size());
  // Ends a stage: writes the checkpoint; true when the wall-time budget is spent (stop there).
  auto stage_done = [&] {
    ++stage;
    write_checkpoint(out / "checkpoint.bin", s, save_state());
    if (opt.max_wall_time < 0 || stage >= stages ||
        std::chrono::duration<double>(clock::now() - t_wall0).count() < opt.max_wall_time)
      return false;
    spdlog::warn("wall-time limit of {} s reached: stopped after stage {} of {} (t = {:.6g} s); continue with --resume {}",
                 opt.max_wall_time, stage, stages, s.time, (out / "checkpoint.bin").string());
    return true;
  };
  spdlog::info("ring shear ({}): {} particles + {} in rough layers, area {:.4g} m^2, sigma_pre {:.4g} Pa, dt {:.3g} s, shear at {:.4g} m/s{}",
               r.cell, n_free, n_fixed, area, r.sigma_pre, c.cfg.dt, r.shear_velocity,
               r.inertial_number_max > 0 ? fmt::format(" (inertial number at most {:.3g})", r.inertial_number_max) : std::string());

  // --- Measurements ------------------------------------------------------------------------
  Wall* L = &s.walls[lid_idx];
  auto sigma_now = [&] { return L->force.z / area; };
  auto tau_now = [&] {
    if (box) return std::fabs(L->force.x) / area;
    return 3.0 * std::fabs(L->torque.z) / (2 * M_PI * (std::pow(r.r_outer, 3) - std::pow(r.r_inner, 3)));
  };
  // The base's share: the base plane plus the frozen rough layer glued to it (the torque about
  // the cell axis in the annulus). At steady shear it balances the lid's (the sample's momentum
  // is steady; the annulus' side walls take the rest when they have friction).
  const Wall* B = &s.walls[0];
  auto tau_base_now = [&] {
    Vec3 f = B->force, m = B->torque;  // torque about the base's centre, the cell axis
    for (size_t i = 0; i < s.particles.size(); ++i)
      if (s.particles.flag[i] == kFrozen) {
        f += s.particles.force[i];
        m += cross(s.particles.x[i] - B->center, s.particles.force[i]) + s.particles.torque[i];
      }
    if (box) return std::fabs(f.x) / area;
    return 3.0 * std::fabs(m.z) / (2 * M_PI * (std::pow(r.r_outer, 3) - std::pow(r.r_inner, 3)));
  };
  auto height_now = [&] { return L->point.z - 2 * layer; };  // between the rough layers
  const uint64_t sample_every =
      r.sample_interval > 0 ? std::max<uint64_t>(1, uint64_t(r.sample_interval / c.cfg.dt)) : 200;
  auto last_progress = clock::now();
  auto advance = [&](double duration, const std::function<bool()>& stop = {}) {
    const uint64_t n = uint64_t(std::llround(duration / c.cfg.dt));
    for (uint64_t k = 0; k < n; ++k) {
      // A step after which nothing reads the particles lets the force loop apply the next
      // step's opening half-kick and drift (System::step_once(true): the same operations,
      // bit-identical): all but the sampled steps (the stop test reads the walls' loads there,
      // and the bed's mass) and the last of the call (phase changes and outputs follow). The
      // progress line reads only the walls, time and step.
      s.step_once(k + 1 < n && (s.step + 1) % sample_every != 0);
      if (L->control != WallControl::Prescribed || norm(L->velocity) > 0 || norm(L->omega) > 0)
        sheared += (box ? std::fabs(L->velocity.x) : std::fabs(L->omega.z) * r_mean) * c.cfg.dt;
      if (s.step % sample_every == 0) {
        const double h = height_now();
        series.push_back({s.time, sheared, sigma_now(), tau_now(), h, h > 0 ? free_mass / (area * h) : 0.0, phase, tau_base_now()});
        if (stop && stop()) return;
      }
      if (!opt.quiet && std::chrono::duration<double>(clock::now() - last_progress).count() > c.output.progress_interval) {
        last_progress = clock::now();
        const double el = std::chrono::duration<double>(last_progress - t_wall0).count();
        spdlog::info("phase {}  t = {:.4g} s  shear {:.3g} mm  sigma {:.4g} Pa  tau {:.4g} Pa  lid z {:.4g} m  {:.3g} particle-steps/s", phase,
                     s.time, 1e3 * sheared, sigma_now(), tau_now(), L->point.z, double(s.step) * s.particles.size() / el);
      }
    }
  };
  auto set_shear = [&](double v) {
    if (box) L->velocity = {v, 0, 0};
    else L->omega = {0, 0, v / r_mean};
  };
  // The lid floats: a counterbalanced mass pressed down by the normal load (the dead weight of
  // the lab tester), so the normal stress it applies is exact on average and the lid is free to
  // dilate and compact; its motion follows the contact forces (WallControl::Spring, k = 0).
  const double lid_mass = r.lid_mass > 0 ? r.lid_mass : free_mass;
  auto set_sigma = [&](double sig) {
    L->control = WallControl::Spring;
    L->mass = lid_mass;
    L->spring_k = 0;
    L->spring_preload = sig * area - lid_mass * dot(s.cfg.gravity, L->normal);  // weight counterbalanced
  };
  auto servo_approach = [&](double sig) {
    L->control = WallControl::Servo;
    L->target_force = sig * area;
    L->servo_gain = r.approach_speed / (r.sigma_pre * area);
    L->servo_vmax = r.approach_speed;
  };
  // Averages of the last samples over tau_window of shear displacement.
  const size_t win = std::max<size_t>(1, size_t(std::llround(r.tau_window / (r.shear_velocity * sample_every * c.cfg.dt))));
  auto window_mean = [&](double Sample::*field) {
    const size_t m = std::min(win, series.size());
    double a = 0;
    for (size_t q = series.size() - m; q < series.size(); ++q) a += series[q].*field;
    return m ? a / double(m) : 0.0;
  };

  // --- Procedure ---------------------------------------------------------------------------
  if (stage < 1) {  // stage 0: fill, settle, lid, consolidate
    s.prepare();
    phase = 0;  // fill and settle: at least the free-fall time of the fill, then until calm
    const double t_fall = std::sqrt(2 * h_insert / std::max(norm(c.cfg.gravity), 1e-12));
    advance(std::min(t_fall, r.settle_time));
    while (s.time < r.settle_time) {
      double vmax = 0;
      for (size_t i = 0; i < s.particles.size(); ++i)  // free particles (indices change when the list re-sorts)
        if (s.particles.flag[i] == kFree) vmax = std::max(vmax, norm(s.particles.v[i]));
      if (vmax < r.settle_velocity) break;
      advance(0.005);
    }
    marks.push_back({sheared, "settled"});
    // Lower the lid onto the bed (rigidly with its rough layer) just above the 95th percentile
    // of the particle tops (a few particles may still bounce), restore full adhesion.
    std::vector<double> tops;
    for (size_t i = 0; i < s.particles.size(); ++i)
      if (s.particles.flag[i] == kFree) tops.push_back(s.particles.x[i].z + s.particles.radius[i]);
    std::sort(tops.begin(), tops.end());
    const double top = tops.empty() ? layer : tops[size_t(0.95 * double(tops.size() - 1))];
    const double drop = L->point.z - (top + layer + 0.5 * rmax);
    L->point.z -= drop;
    L->center.z -= drop;
    for (size_t i = 0; i < s.particles.size(); ++i)
      if (s.particles.flag[i] == kAttached) s.particles.x[i].z -= drop;
    if (has_kadh) s.set_model(make_contact_model(c.model, c.rolling, c.file), full);
    else s.prepare();
    phase = 1;  // consolidation: approach fast until the lid carries 10% of the load, then servo
    servo_approach(r.sigma_pre);
    spdlog::debug("lid at z = {:.5g} m, bed top (95%) {:.5g} m, vn {:.3g}", L->point.z, top, L->vn);
    advance(1.0, [&] { return sigma_now() > 0.1 * r.sigma_pre; });
    set_sigma(r.sigma_pre);
    advance(r.consolidate_time);
    if (c.output.vtk) write_state_vtk(s, out.string(), "consolidated", false);  // ParaView: particles_consolidated.vtu
    if (stage_done()) return kExitResumable;
  }

  // Pre-shear to steady state (ASTM D6773): shear `dist`, then go on in steps of dist/4 while
  // tau over the last quarter of the pre-shear still drifts by more than steady_drift, up to
  // preshear_max_factor x dist. The steady value is the mean over that last quarter.
  auto preshear = [&](double dist) {
    phase = 2;
    set_sigma(r.sigma_pre);
    const size_t first = series.size();
    marks.push_back({sheared, "pre-shear"});
    set_shear(r.shear_velocity);
    advance(dist / r.shear_velocity);
    double done = dist;
    SteadyState st;
    double sig_mean = 0, base_mean = 0;
    for (;;) {
      std::vector<double> t, tau, sig, base;
      for (size_t q = first; q < series.size(); ++q) {
        t.push_back(series[q].t); tau.push_back(series[q].tau); sig.push_back(series[q].sigma); base.push_back(series[q].tau_base);
      }
      if (t.size() < 8) throw RunError("pre-shear too short to sample: raise preshear_distance or lower sample_interval");
      st = steady_state_value(t, tau, t.front(), t.back(), 0.25, r.steady_drift);
      sig_mean = base_mean = 0;
      size_t ns = 0;
      for (size_t q = t.size() * 3 / 4; q < t.size(); ++q) { sig_mean += sig[q]; base_mean += base[q]; ++ns; }
      sig_mean /= double(ns);
      base_mean /= double(ns);
      if (st.steady || done >= r.preshear_max_factor * dist * (1 - 1e-9)) break;
      advance(0.25 * dist / r.shear_velocity);
      done += 0.25 * dist;
    }
    set_shear(0);
    pre_tau.push_back(st.mean);
    pre_sigma.push_back(sig_mean);
    pre_dist.push_back(done);
    pre_base.push_back(base_mean);
    if (!st.steady)
      spdlog::warn("pre-shear {} not steady after {:.3g} mm (relative drift {:.3f} over the last quarter, limit {:.3f})", pre_tau.size(),
                   1e3 * done, st.relative_drift, r.steady_drift);
  };
  if (stage < 2) {
    preshear(r.first_preshear_distance);
    if (stage_done()) return kExitResumable;
  }
  for (size_t i = 0; i < r.fractions.size(); ++i) {
    const double f = r.fractions[i];
    if (stage < int(3 + 2 * i)) {  // stage 2 + 2i: shear to failure at f x sigma_pre
      // Relieve to the lower normal stress at rest, then shear to failure.
      phase = 3;
      set_sigma(f * r.sigma_pre);
      advance(r.relax_time);
      phase = 4;
      marks.push_back({sheared, "shear " + std::to_string(int(std::lround(100 * f))) + "%"});
      set_shear(r.shear_velocity);
      // Failure: the peak of tau averaged over tau_window (single samples of a small cell are
      // noisy); the normal stress is averaged over the same window.
      double tau_max = 0, sig_at_max = 0;
      const size_t first = series.size();
      advance(r.shear_distance / r.shear_velocity, [&] {
        if (series.size() - first < win) return false;
        const double tm = window_mean(&Sample::tau);
        if (tm > tau_max) { tau_max = tm; sig_at_max = window_mean(&Sample::sigma); }
        return tau_max > 0 && tm < (1 - r.peak_drop) * tau_max;
      });
      set_shear(0);
      points.push_back({sig_at_max, tau_max, pre_tau.back(), pre_sigma.back()});
      spdlog::info("shear point {}: sigma = {:.4g} Pa, tau = {:.4g} Pa (pre-shear tau {:.4g} Pa)", points.size(), sig_at_max, tau_max,
                   pre_tau.back());
      // Pre-shear again before the next point (and at the end, for the last steady value).
      phase = 3;
      set_sigma(r.sigma_pre);
      advance(r.relax_time);
      if (stage_done()) return kExitResumable;
    }
    if (stage < int(4 + 2 * i)) {  // stage 3 + 2i: pre-shear again
      preshear(r.preshear_distance);
      if (stage_done()) return kExitResumable;
    }
  }

  if (c.output.vtk) write_state_vtk(s, out.string(), "final", false);

  // --- Evaluation --------------------------------------------------------------------------
  double tp = 0, sp = 0;
  for (size_t q = 0; q < pre_tau.size(); ++q) { tp += pre_tau[q]; sp += pre_sigma[q]; }
  tp /= pre_tau.size();
  sp /= pre_sigma.size();
  // ASTM D6773 (and Schulze's evaluation) normalize each shear point to the mean pre-shear
  // stress, tau * tau_pre_mean / tau_pre_i with tau_pre_i the pre-shear just before it, to take
  // out random scatter of the pre-shears. MEPA samples strengthen steadily with accumulated
  // shear (the pre-shear tau of the copper ore runs rose 30-55% over the test), and normalizing
  // folds that drift into the locus; so the measured points are evaluated by default
  // (normalize_points = false) and the other evaluation is reported beside it.
  std::vector<ShearPoint> sp_pts, raw_pts;
  std::vector<ShearPoint> norm_pts;
  for (const auto& p : points) {
    norm_pts.push_back({p.sigma, p.tau_pre > 0 ? p.tau * tp / p.tau_pre : p.tau});
    raw_pts.push_back({p.sigma, p.tau});
  }
  sp_pts = r.normalize_points ? norm_pts : raw_pts;                 // the reported evaluation
  const std::vector<ShearPoint>& other_pts = r.normalize_points ? raw_pts : norm_pts;
  double mean_density = 0;
  {
    size_t n = 0;
    for (const auto& q : series)
      if (q.phase == 2) { mean_density += q.density; ++n; }
    mean_density = n ? mean_density / n : 0;
  }
  nlohmann::json j;
  j["cell"] = r.cell;
  j["particles"] = n_free;
  j["rough_layer_particles"] = n_fixed;
  j["sigma_pre_target"] = r.sigma_pre;
  double tb = 0;
  for (double v : pre_base) tb += v;
  tb /= double(pre_base.size());
  j["pre_shear"] = {{"sigma", sp}, {"tau", tp}, {"tau_each", pre_tau}, {"sigma_each", pre_sigma}, {"distance_each", pre_dist},
                    {"tau_base", tb}, {"tau_base_each", pre_base}};
  for (size_t q = 0; q < points.size(); ++q)
    j["shear_points"].push_back({{"sigma", points[q].sigma}, {"tau_measured", points[q].tau},
                                 {"tau_normalized", norm_pts[q].tau}, {"tau_preshear_before", points[q].tau_pre}});
  j["normalized_points"] = r.normalize_points;
  j["bulk_density_preshear"] = mean_density;
  const double d50 = 2 * std::cbrt(r.size.mean_volume() * 3 / (4 * M_PI));
  const double rho_p = c.materials[r.material].density;
  const double h_band = 10 * d50;
  const double sig_low = *std::min_element(r.fractions.begin(), r.fractions.end()) * r.sigma_pre;
  j["inertial_number"] = {{"shear_band_thickness", h_band},
                          {"shear_velocity", r.shear_velocity},
                          {"limit", r.inertial_number_max > 0 ? nlohmann::json(r.inertial_number_max) : nlohmann::json(nullptr)},
                          {"at_sigma_pre", ring_shear_inertial_number(r.shear_velocity, r.sigma_pre, rho_p)},
                          {"at_lowest_shear_point", ring_shear_inertial_number(r.shear_velocity, sig_low, rho_p)}};
  YieldLocusResult yl;
  bool evaluated = false;
  std::string eval_error;
  try {
    yl = evaluate_yield_locus({sp, tp}, sp_pts, mean_density, /*allow_preshear_above=*/true);
    evaluated = true;
  } catch (const std::invalid_argument& e) {
    eval_error = e.what();
  }
  const double deg = 180.0 / M_PI;
  // ffc in summary.json: a number, "inf" without cohesion, null without a steady-state circle.
  const auto ffc_json = [](const YieldLocusResult& y) {
    return !y.steady_state ? nlohmann::json(nullptr) : y.ffc_infinite ? nlohmann::json("inf") : nlohmann::json(y.ffc);
  };
  try {
    const YieldLocusResult raw = evaluate_yield_locus({sp, tp}, other_pts, mean_density, true);
    auto& o = j[r.normalize_points ? "yield_locus_measured_points" : "yield_locus_normalized_points"];
    o = {{"phi_lin_deg", raw.phi_lin * deg}, {"cohesion", raw.cohesion}, {"sigma_c", raw.sigma_c},
         {"ffc", ffc_json(raw)}};
    if (!raw.steady_state) o["steady_state_error"] = raw.steady_state_error;
  } catch (const std::invalid_argument& e) {
    j[r.normalize_points ? "yield_locus_measured_points" : "yield_locus_normalized_points"] = {{"error", e.what()}};
  }
  if (evaluated) {
    // Without a steady-state circle (sigma_2 < 0) its values are null and the reason is given.
    const auto circ = [&](double v) { return yl.steady_state ? nlohmann::json(v) : nlohmann::json(nullptr); };
    j["yield_locus"] = {{"phi_lin_deg", yl.phi_lin * deg}, {"cohesion", yl.cohesion}, {"r_squared", yl.r_squared},
                        {"sigma_1", circ(yl.sigma_1)}, {"sigma_2", circ(yl.sigma_2)}, {"sigma_c", yl.sigma_c},
                        {"ffc", ffc_json(yl)},
                        {"phi_e_deg", circ(yl.phi_e * deg)}, {"phi_sf_deg", yl.phi_sf * deg},
                        {"preshear_above_locus", yl.preshear_above_locus}};
    if (!yl.steady_state) {
      j["yield_locus"]["steady_state_error"] = yl.steady_state_error;
      spdlog::warn("yield locus: {}", yl.steady_state_error);
    }
    if (yl.preshear_above_locus)
      spdlog::warn("the pre-shear point lies above the linearized yield locus (scatter of a nearly cohesionless sample?): "
                   "sigma_1 from the circle tangent at the pre-shear point");
  } else {
    j["yield_locus"] = {{"error", eval_error}};
  }
  const double wall_s = wall_before + std::chrono::duration<double>(clock::now() - t_wall0).count();
  j["wall_time_s"] = wall_s;  // a resumed run adds the time of the runs before
  j["cpu_time_s"] = cpu_before + double(std::clock()) / CLOCKS_PER_SEC;  // all threads of this process
  j["steps"] = s.step;
  j["simulated_time"] = s.time;
  j["particle_steps_per_s"] = double(s.step) * double(s.particles.size()) / wall_s;
  j["neighbor_builds"] = s.nl.stats.builds;
  j["neighbor_checks"] = s.nl.stats.checks;      // local checks where the trigger fired (NeighborList::recheck)
  j["neighbor_deferred"] = s.nl.stats.deferred;  // of them, those that kept the lists
  write_file_atomic(out / "summary.json", j.dump(2) + "\n");
  {
    CsvWriter w(out / "series.csv", {"time", "shear_displacement", "sigma", "tau", "height", "bulk_density", "phase", "tau_base"});
    for (const auto& q : series) w.row({q.t, q.x, q.sigma, q.tau, q.height, q.density, double(q.phase), q.tau_base});
    CsvWriter p(out / "shear_points.csv", {"sigma", "tau_measured", "tau_normalized", "sigma_pre", "tau_pre"});
    for (size_t q = 0; q < points.size(); ++q)
      p.row({points[q].sigma, points[q].tau, norm_pts[q].tau, points[q].sigma_pre_meas, points[q].tau_pre});
  }
  // Plots.
  try {
    PlotSpec a;
    a.title = "ring shear: shear stress against shear displacement";
    a.xlabel = "shear displacement (mm)";
    a.ylabel = "stress (kPa)";
    Series st{"tau", {}, {}, "lines"}, sn{"sigma", {}, {}, "lines"};
    for (const auto& q : series)
      if (q.phase >= 1) { st.x.push_back(1e3 * q.x); st.y.push_back(1e-3 * q.tau); sn.x.push_back(1e3 * q.x); sn.y.push_back(1e-3 * q.sigma); }
    a.series = {st, sn};
    // The lid's first contact with the bed can spike sigma far above the test's stresses: the
    // stress axis spans the shearing phases (pre-shear and shear) with some room.
    double ymax = 1e-3 * r.sigma_pre;
    for (const auto& q : series)
      if (q.phase >= 2) ymax = std::max({ymax, 1e-3 * q.tau, 1e-3 * q.sigma});
    a.yrange = std::make_pair(std::min(0.0, -0.05 * ymax), 1.15 * ymax);
    for (const auto& m : marks) a.vlines.push_back({1e3 * m.first, m.second});
    a.width = 1100;
    plot_png(out / "shear_curve.png", a);
    PlotSpec b;
    b.title = evaluated ? fmt::format("yield locus: phi_lin = {:.1f} deg, c = {:.3g} kPa, ffc = {}", yl.phi_lin * deg,
                                      1e-3 * yl.cohesion,
                                      !yl.steady_state ? std::string("n/a (sigma_2 < 0)")
                                      : yl.ffc_infinite ? std::string("inf") : fmt::format("{:.2f}", yl.ffc))
                        : "yield locus (evaluation failed: " + eval_error + ")";
    b.xlabel = "normal stress sigma (kPa)";
    b.ylabel = "shear stress tau (kPa)";
    b.equal_axes = true;
    Series pts{"shear points", {}, {}, "points"}, pre{"pre-shear", {1e-3 * sp}, {1e-3 * tp}, "points"};
    for (const auto& q : sp_pts) { pts.x.push_back(1e-3 * q.sigma); pts.y.push_back(1e-3 * q.tau); }
    b.series = {pts, pre};
    if (evaluated) {
      const double smax = (yl.steady_state ? std::max(yl.sigma_1, sp) : sp) * 1.1;
      Series line{"yield locus", {0, 1e-3 * smax}, {1e-3 * yl.cohesion, 1e-3 * (yl.cohesion + std::tan(yl.phi_lin) * smax)}, "lines"};
      b.series.push_back(line);
      if (yl.steady_state)
        b.series.push_back(circle(1e-3 * 0.5 * (yl.sigma_1 + yl.sigma_2), 1e-3 * 0.5 * (yl.sigma_1 - yl.sigma_2), "steady-state flow", true));
      if (yl.sigma_c > 0) b.series.push_back(circle(1e-3 * 0.5 * yl.sigma_c, 1e-3 * 0.5 * yl.sigma_c, "unconfined failure", true));
    }
    plot_png(out / "yield_locus.png", b);
  } catch (const std::exception& e) {
    spdlog::warn("plots not written: {}", e.what());
  }
  // Text summary.
  fmt::print("\nring shear test ({}, {} particles, sigma_pre = {:.4g} kPa)\n", r.cell, n_free, 1e-3 * r.sigma_pre);
  fmt::print("  pre-shear (steady state): sigma = {:.4g} kPa, tau = {:.4g} kPa (lid; base {:.4g} kPa)\n", 1e-3 * sp, 1e-3 * tp, 1e-3 * tb);
  for (size_t q = 0; q < points.size(); ++q)
    fmt::print("  shear point {}: sigma = {:.4g} kPa, tau = {:.4g} kPa (after a pre-shear at {:.4g} kPa; normalized {:.4g} kPa)\n", q + 1,
               1e-3 * points[q].sigma, 1e-3 * points[q].tau, 1e-3 * points[q].tau_pre, 1e-3 * norm_pts[q].tau);
  if (evaluated) {
    fmt::print("  angle of internal friction (linearized yield locus) phi_lin = {:.2f} deg\n", yl.phi_lin * deg);
    fmt::print("  cohesion c = {:.4g} kPa, unconfined yield strength sigma_c = {:.4g} kPa\n", 1e-3 * yl.cohesion, 1e-3 * yl.sigma_c);
    if (yl.steady_state) {
      fmt::print("  major consolidation stress sigma_1 = {:.4g} kPa, ffc = {}\n", 1e-3 * yl.sigma_1,
                 yl.ffc_infinite ? std::string("inf (no cohesion)") : fmt::format("{:.2f}", yl.ffc));
      fmt::print("  effective angle of internal friction phi_e = {:.2f} deg, phi_sf = {:.2f} deg\n", yl.phi_e * deg, yl.phi_sf * deg);
    } else {
      fmt::print("  {}\n", yl.steady_state_error);
      fmt::print("  steady-state-flow angle phi_sf = {:.2f} deg\n", yl.phi_sf * deg);
    }
  } else {
    fmt::print("  yield locus evaluation failed: {}\n", eval_error);
  }
  fmt::print("  bulk density during pre-shear {:.0f} kg/m^3; inertial number {:.2g} (sigma_pre) .. {:.2g} (lowest point)\n",
             mean_density, double(j["inertial_number"]["at_sigma_pre"]), double(j["inertial_number"]["at_lowest_shear_point"]));
  fmt::print("  {} steps in {:.1f} s ({:.3g} particle-steps/s); report in {}\n", s.step, wall_s, double(j["particle_steps_per_s"]),
             out.string());
  return 0;
}

}  // namespace cohdem
