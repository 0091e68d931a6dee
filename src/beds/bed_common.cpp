#include "beds/bed_common.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iterator>
#include <sstream>

#include "analysis/packing_profile.hpp"
#include "core/error.hpp"
#include "io/checkpoint.hpp"
#include "io/runner.hpp"
#include "sim/timestep_audit.hpp"

namespace cohdem::beds {

Case load(const BedOptions& o) {
  std::vector<std::string> sets = o.sets;
  if (o.threads > 0) sets.push_back("simulation.threads=" + std::to_string(o.threads));
  return load_case_file(o.case_path, sets);
}

std::string out_folder(const BedOptions& o, const Case& c) { return o.out_dir.empty() ? c.output.folder : o.out_dir; }

std::unique_ptr<System> build_checked(const Case& c) {
  auto s = build_system(c);
  s->cfg.record_contacts = true;  // the protocols write the contact network and measure stresses
  const auto a = audit_timestep(*s, min_radius_by_material(*s), audit_velocity(c));
  for (const auto& m : a.messages) spdlog::warn("time step: {}", m);
  if (a.level == TimestepAudit::Error)
    throw InputError(c.file, c.dt_line, "simulation.dt", "time step past its hard bound; reduce dt");
  return s;
}

std::unique_ptr<System> clone(const Case& c, const System& src) {
  auto s = std::make_unique<System>();
  s->cfg = src.cfg;
  s->materials = src.materials;
  s->set_model(make_contact_model(c.model, c.rolling, c.file), c.pair_params);
  s->walls = src.walls;
  s->particles = src.particles;
  s->nl = src.nl;
  s->pours = src.pours;
  s->rng = src.rng;
  s->time = src.time;
  s->step = src.step;
  s->next_id = src.next_id;
  if (src.thermal) s->thermal = std::make_shared<ThermalModel>(*src.thermal);
  s->prepare();  // rebuilds the lists from the copied ones: history carried over by id
  return s;
}

void advance(System& s, double duration, const std::string& label, bool quiet,
             const std::function<void(System&)>& sample, uint64_t every) {
  advance_steps(s, uint64_t(std::llround(duration / s.cfg.dt)), label, quiet, sample, every);
}

void advance_steps(System& s, uint64_t n, const std::string& label, bool quiet, const std::function<void(System&)>& sample,
                   uint64_t every, const std::function<void(System&)>& after,
                   const std::function<bool(const System&)>& after_reads) {
  using clock = std::chrono::steady_clock;
  const auto t0 = clock::now();
  auto last = t0;
  for (uint64_t k = 1; k <= n; ++k) {
    // What reads the state after this step is decided before it (the clock read here): a
    // step after which nothing does lets the force loop apply the next step's opening
    // half-kick and drift (System::step_once(true), the same operations, bit-identical).
    const auto now = clock::now();
    const bool progress_due = !quiet && std::chrono::duration<double>(now - last).count() >= 10;
    const bool sample_due = sample && every && k % every == 0;
    const bool check_due = k % 1000 == 0 || k == n;
    const bool open = k < n && !progress_due && !sample_due && !check_due && (!after || (after_reads && !after_reads(s)));
    s.step_once(open);
    if (sample_due) sample(s);
    if (after) after(s);
    if (check_due) {
      const Vec3 x = s.particles.size() ? s.particles.x[0] : Vec3{};
      if (!std::isfinite(x.x + x.y + x.z + s.kinetic_energy()))
        throw RunError(label + ": non-finite state at t = " + std::to_string(s.time) + " s (time step too large?)");
    }
    if (progress_due) {
      last = now;
      const double el = std::chrono::duration<double>(now - t0).count();
      spdlog::info("{}: t = {:.4f} s, step {}/{}, {} particles, KE {:.3g} J, ETA {:.0f} s", label, s.time, k, n,
                   s.particles.size(), s.kinetic_energy(), el / k * (n - k));
    }
  }
}

namespace {

/// What a stage checkpoint must have been written with to be resumed: the case file's text,
/// the --set options and the seed. Options that do not change results are left out: the
/// [output] keys (folder, checkpoint interval, ...) and the thread count.
nlohmann::json stage_fingerprint(const Case& c, const BedOptions& o) {
  std::ifstream f(c.file, std::ios::binary);
  std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  std::vector<std::string> sets;
  for (const std::string& a : o.sets)
    if (a.rfind("output.", 0) != 0 && a.rfind("simulation.threads=", 0) != 0) sets.push_back(a);
  return {{"case_text", text}, {"sets", sets}, {"seed", c.seed}};
}

}  // namespace

Stage open_stage(const Case& c, const BedOptions& o, const std::filesystem::path& ckpt) {
  Stage st;
  if (!o.resume || !std::filesystem::exists(ckpt)) {
    if (o.resume) spdlog::warn("--resume: no checkpoint {} yet: this stage starts from the beginning", ckpt.string());
    st.s = build_checked(c);
    return st;
  }
  auto s = build_system(c, false);
  s->cfg.record_contacts = true;
  const std::string blob = read_checkpoint(ckpt, *s);
  nlohmann::json j;
  try {
    j = nlohmann::json::from_cbor(std::vector<uint8_t>(blob.begin(), blob.end()));
    if (!j.contains("fingerprint") || !j.contains("complete")) throw std::runtime_error("no stage state");
  } catch (const std::exception&) {
    throw InputError(ckpt.string(), 0, "--resume", "not a checkpoint of a packed-bed protocol stage");
  }
  const nlohmann::json now = stage_fingerprint(c, o);
  for (const auto& [key, what] : {std::pair{"case_text", "case file text"}, {"sets", "set of --set options"}, {"seed", "seed"}})
    if (j["fingerprint"][key] != now[key])
      throw InputError(ckpt.string(), 0, "--resume",
                       std::string("written with another ") + what + " than this run's (" + c.file +
                           "): resume with the same case and options, or start without --resume");
  st.s = std::move(s);
  st.resumed = true;
  st.complete = j["complete"].get<bool>();
  st.state = j.value("state", nlohmann::json());
  spdlog::info("resuming from {}: step {} (t = {:.6g} s){}", ckpt.string(), st.s->step, st.s->time,
               st.complete ? ", the stage had ended" : "");
  return st;
}

void run_stage(Stage& st, const Case& c, const BedOptions& o, const std::filesystem::path& ckpt, const std::string& label,
               const std::function<void(System&)>& sample, uint64_t every, const std::function<nlohmann::json()>& state) {
  using clock = std::chrono::steady_clock;
  System& s = *st.s;
  const uint64_t n = uint64_t(std::llround(c.duration / s.cfg.dt));
  const nlohmann::json fp = stage_fingerprint(c, o);
  auto write = [&](bool complete) {
    nlohmann::json j{{"fingerprint", fp}, {"complete", complete}, {"stage", label}};
    if (state) j["state"] = state();
    const std::vector<uint8_t> bytes = nlohmann::json::to_cbor(j);
    write_checkpoint(ckpt, s, std::string(bytes.begin(), bytes.end()));
  };
  auto last = clock::now();
  const double interval = c.output.checkpoint_interval;
  // Samples at the steps that are multiples of `every` counted from t = 0, so that a resumed
  // stage samples where the uninterrupted one did. Whether a checkpoint follows a step is
  // decided before it (after_reads), so that the step before a checkpoint or a sample is
  // complete (advance_steps lets the others take the fused opening).
  bool ck_due = false;
  auto after_reads = [&](const System& sys) {
    const uint64_t next = sys.step + 1;  // the step about to be taken
    ck_due = interval > 0 && next < n && std::chrono::duration<double>(clock::now() - last).count() >= interval;
    return ck_due || (sample && every && next % every == 0);
  };
  auto after = [&](System& sys) {
    if (sample && every && sys.step % every == 0) sample(sys);
    if (!ck_due) return;
    write(false);
    last = clock::now();
    ck_due = false;
  };
  if (s.step < n) advance_steps(s, n - s.step, label, o.quiet, {}, 0, after, after_reads);
  if (!st.complete) write(true);
  st.complete = true;
}

size_t find_wall(const Case& c, const System& s, const std::string& name, const std::string& option) {
  for (size_t w = 0; w < s.walls.size(); ++w)
    if (s.walls[w].name == name) return w;
  std::string names;
  for (const auto& w : s.walls) names += (names.empty() ? "" : ", ") + w.name;
  throw InputError(c.file, 0, option, "no wall called '" + name + "' in the case; walls: " + names);
}

double mean_radius(const System& s) {
  double sum = 0;
  for (double r : s.particles.radius) sum += r;
  return s.particles.size() ? sum / double(s.particles.size()) : 0.0;
}

PipeBed measure_pipe_bed(const System& s, double R, double z_base) {
  const ParticleStore& P = s.particles;
  PipeBed b;
  b.R = R;
  b.z_base = z_base;
  std::vector<Vec3> x;
  std::vector<double> r, z;
  double rho = 0;
  for (size_t i = 0; i < P.size(); ++i) {
    if (P.flag[i] != kFree) continue;
    x.push_back(P.x[i]);
    r.push_back(P.radius[i]);
    z.push_back(P.x[i].z);
    b.mass += P.mass[i];
    // The solid density from the reference radius (a thermal run's radii follow temperature).
    rho += P.mass[i] / (4.0 / 3.0 * M_PI * std::pow(P.thermal() ? P.radius0[i] : P.radius[i], 3));
  }
  b.count = x.size();
  if (x.empty()) return b;
  rho /= double(b.count);
  std::sort(z.begin(), z.end());
  b.top = z[size_t(0.99 * double(z.size() - 1))];
  const double d = 2 * mean_radius(s);
  const double lo = z_base + 2 * d, hi = b.top - 3 * d;
  // Exact in z; every sphere lies inside the pipe, so its whole section counts.
  b.phi = hi > lo + d ? mean_solids_fraction(x, r, 2, lo, hi, M_PI * R * R)
                      : mean_solids_fraction(x, r, 2, z_base, b.top, M_PI * R * R);
  b.rho_bulk = rho * b.phi;
  b.height = b.mass / (b.rho_bulk * M_PI * R * R);
  return b;
}

size_t trim_above(System& s, double z) {
  std::vector<uint8_t> rm(s.particles.size(), 0);
  size_t n = 0;
  for (size_t i = 0; i < rm.size(); ++i)
    if (s.particles.flag[i] == kFree && s.particles.x[i].z > z) { rm[i] = 1; ++n; }
  if (n) s.remove_particles(rm);
  return n;
}

std::vector<double> parse_list(const std::string& text, const std::string& option) {
  std::vector<double> v;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    try {
      size_t used = 0;
      v.push_back(std::stod(item, &used));
      if (used != item.size()) throw std::invalid_argument(item);
    } catch (const std::exception&) {
      throw InputError("command line", 0, option, "expected comma-separated numbers, got '" + text + "'");
    }
  }
  return v;
}

}  // namespace cohdem::beds
