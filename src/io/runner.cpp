#include "io/runner.hpp"

#include <spdlog/spdlog.h>

#include <omp.h>

#include <malloc.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "core/error.hpp"
#include "io/atomic_file.hpp"
#include "io/checkpoint.hpp"
#include "apps/ring_shear.hpp"
#include <fstream>
#include "io/contact_network.hpp"
#include "io/csv.hpp"
#include "io/vtk.hpp"
#include "sim/screen.hpp"
#include "thermal/thermal.hpp"

namespace cohdem {

namespace fs = std::filesystem;

std::vector<double> min_radius_by_material(const System& s) {
  std::vector<double> r(s.materials.size(), 0.0);
  auto take = [&](int m, double v) { r[m] = r[m] > 0 ? std::min(r[m], v) : v; };
  for (size_t i = 0; i < s.particles.size(); ++i) take(s.particles.species[i], s.particles.radius[i]);
  for (const auto& p : s.pours) take(p.spec.species, p.spec.size.min_radius());
  return r;
}

double audit_velocity(const Case& c) {
  if (c.audit_velocity > 0) return c.audit_velocity;
  double v = 1.0;
  const Vec3 L = c.cfg.domain.length();
  double H = std::max({L.x, L.y, L.z});
  for (const auto& st : c.inserts) {
    v = std::max(v, norm(st.spec.velocity));
    const Region& r = st.spec.region;
    H = std::max(H, r.kind == Region::Kind::Box ? r.hi.z - r.lo.z : r.zmax - r.zmin);
  }
  for (const auto& w : c.walls) v = std::max(v, norm(w.velocity) + 2 * M_PI * w.osc_frequency * w.osc_amplitude);
  return std::max(v, std::sqrt(2 * norm(c.cfg.gravity) * H));
}

namespace {

/// The text of a run's series.csv without a row cut off mid-line: the killed run that is
/// being resumed went on writing after its checkpoint, so its last row may lack its line end.
/// Rows up to the checkpoint are complete (synced before the checkpoint was written); the
/// caller keeps those up to the checkpoint's step.
std::string series_complete_rows(const std::filesystem::path& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw RunError("cannot read " + path.string() + " to continue its series");
  std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  const size_t eol = text.rfind('\n');
  text.resize(eol == std::string::npos ? text.size() : eol + 1);
  return text;
}

std::string hms(double s) {
  if (!std::isfinite(s) || s < 0) return "--:--:--";
  const long t = long(s + 0.5);
  char b[32];
  std::snprintf(b, sizeof b, "%02ld:%02ld:%02ld", t / 3600, (t / 60) % 60, t % 60);
  return b;
}

void print_audit(const TimestepAudit& a) {
  if (a.rayleigh > 0) spdlog::info("Rayleigh time {:.4g} s ({}), dt/T_R = {:.3f}", a.rayleigh, a.rayleigh_material, a.dt / a.rayleigh);
  if (a.collision > 0 && std::isfinite(a.collision))
    spdlog::info("collision time {:.4g} s ({} at {:.3g} m/s): {:.1f} steps per collision", a.collision, a.collision_pair,
                 a.velocity, a.collision / a.dt);
  if (a.rolling > 0 && std::isfinite(a.rolling))
    spdlog::info("rolling spring half period {:.4g} s ({}): {:.1f} steps", a.rolling, a.rolling_pair, a.rolling / a.dt);
  for (const auto& m : a.messages) {
    if (a.level == TimestepAudit::Error) spdlog::error("time step: {}", m);
    else spdlog::warn("time step: {}", m);
  }
}

/// Extent of particles and walls, to size infinite wall meshes for ParaView.
void scene_bounds(const System& s, Vec3& lo, Vec3& hi) {
  lo = {INFINITY, INFINITY, INFINITY};
  hi = {-INFINITY, -INFINITY, -INFINITY};
  for (size_t i = 0; i < s.particles.size(); ++i)
    for (int d = 0; d < 3; ++d) {
      lo[d] = std::min(lo[d], s.particles.x[i][d] - s.particles.radius[i]);
      hi[d] = std::max(hi[d], s.particles.x[i][d] + s.particles.radius[i]);
    }
  for (int d = 0; d < 3; ++d) {
    if (s.cfg.domain.hi[d] > s.cfg.domain.lo[d]) { lo[d] = std::min(lo[d], s.cfg.domain.lo[d]); hi[d] = std::max(hi[d], s.cfg.domain.hi[d]); }
    if (!(hi[d] >= lo[d])) { lo[d] = -1; hi[d] = 1; }
  }
}

VtuData walls_vtu(const System& s) {
  Vec3 lo, hi;
  scene_bounds(s, lo, hi);
  const double size = norm(hi - lo);
  std::vector<VtuData> parts;
  for (size_t w = 0; w < s.walls.size(); ++w) {
    const Wall& W = s.walls[w];
    VtuData d;
    if (W.shape == WallShape::Plane) {
      if (W.rmax < INFINITY || W.rmin > 0) d = disk_annulus(W.point, W.normal, W.rmin, std::isfinite(W.rmax) ? W.rmax : size);
      else d = plane_patch(W.point, W.normal, 0.5 * size);
    } else {
      const double c0 = dot(0.5 * (lo + hi) - W.point, W.normal);
      const double z0 = std::isfinite(W.zmin) ? W.zmin : c0 - 0.5 * size;
      const double z1 = std::isfinite(W.zmax) ? W.zmax : c0 + 0.5 * size;
      d = cylinder_surface(W.point, W.normal, W.radius, z0, z1);
    }
    d.fill_cell_int("wall_id", int32_t(w));
    std::vector<double> fz(d.num_cells(), norm(W.force));
    d.add_cell_scalar("force_magnitude", fz);
    parts.push_back(std::move(d));
  }
  return merge(parts);
}

VtuData particles_frame(const System& s) {
  const ParticleStore& P = s.particles;
  VtuData d = particles_vtu(P.x);
  d.add_point_id("id", P.id);
  d.add_point_scalar("radius", P.radius);
  d.add_point_int("species", P.species);
  d.add_point_vector("velocity", P.v);
  d.add_point_vector("omega", P.omega);
  d.add_point_vector("force", P.force);
  d.add_point_u8("flag", P.flag);
  if (P.thermal()) {  // a mechanical run keeps no temperatures (ParticleStore::enable_thermal)
    d.add_point_scalar("temperature", P.temperature);
    d.add_point_scalar("heat_flow", P.heat_flow);
  }
  return d;
}

struct Series {
  std::vector<std::string> cols;
  std::vector<double> row;
};

Series series_columns(const Case& c, const System& s) {
  Series S;
  S.cols = {"time", "step", "kinetic_energy", "contacts"};
  for (const auto& p : c.output.probes)
    if (p != "kinetic_energy" && p != "contacts") S.cols.push_back(p);
  for (const Wall& w : s.walls) {
    for (const char* q : {"fx", "fy", "fz", "tx", "ty", "tz"}) S.cols.push_back("wall." + w.name + "." + q);
    if (w.control != WallControl::Prescribed) S.cols.push_back("wall." + w.name + ".travel");
  }
  if (s.thermal)
    for (size_t w = 0; w < s.walls.size(); ++w)
      if (s.thermal->wall_fixed(w))
        for (const char* q : {"temperature", "heat"}) S.cols.push_back("wall." + s.walls[w].name + "." + q);
  return S;
}

double probe(const std::string& name, const System& s) {
  const ParticleStore& P = s.particles;
  if (name == "rotational_energy") return s.rotational_energy();
  if (name == "max_overlap") return s.max_relative_overlap();
  if (name == "particles") return double(P.size());
  if (name == "rebuilds") return s.rebuild_count();
  if (name == "max_contact_force") return pair_force_stats(s).max;
  if (name == "mean_contact_force") return pair_force_stats(s).mean;
  if (name.ends_with("_temperature")) {
    double lo = INFINITY, hi = -INFINITY, sum = 0;
    for (double T : P.temperature) { lo = std::min(lo, T); hi = std::max(hi, T); sum += T; }
    if (P.size() == 0) return 0.0;
    return name == "min_temperature" ? lo : name == "max_temperature" ? hi : sum / double(P.size());
  }
  double sum = 0, mx = 0, top = -INFINITY;
  size_t nf = 0;
  for (size_t i = 0; i < P.size(); ++i) {
    if (P.flag[i] != kFree) continue;
    const double v = norm(P.v[i]);
    sum += v;
    mx = std::max(mx, v);
    top = std::max(top, P.x[i].z + P.radius[i]);
    ++nf;
  }
  if (name == "mean_velocity") return nf ? sum / nf : 0.0;
  if (name == "max_velocity") return mx;
  if (name == "bed_height") return nf ? top : 0.0;
  if (name == "coordination") return nf ? 2.0 * double(s.pair_contact_count()) / double(nf) : 0.0;
  return 0.0;
}

void fill_row(const Case& c, const System& s, Series& S) {
  S.row = {s.time, double(s.step), s.kinetic_energy(), double(s.contact_count())};
  for (const auto& p : c.output.probes)
    if (p != "kinetic_energy" && p != "contacts") S.row.push_back(probe(p, s));
  for (const Wall& w : s.walls) {
    for (int d = 0; d < 3; ++d) S.row.push_back(w.force[d]);
    for (int d = 0; d < 3; ++d) S.row.push_back(w.torque[d]);
    if (w.control != WallControl::Prescribed) S.row.push_back(w.travel);
  }
  if (s.thermal)
    for (size_t w = 0; w < s.walls.size(); ++w)
      if (s.thermal->wall_fixed(w)) {
        S.row.push_back(s.thermal->wall_temperature(w, s.time));
        S.row.push_back(w < s.thermal->wall_heat.size() ? s.thermal->wall_heat[w] : 0.0);
      }
}

void check_finite(const System& s) {
  const ParticleStore& P = s.particles;
  // The first such particle, found on the threads (every series row checks: at 10^6
  // particles a few ms on one thread).
  // Below parallel_min without entering an OpenMP region (a team of one still costs its set-up).
  const long n = long(P.size());
  auto finite = [&](const long i) {
    return std::isfinite(P.x[i].x + P.x[i].y + P.x[i].z + P.v[i].x + P.v[i].y + P.v[i].z);
  };
  long bad = n;
  if (n > s.cfg.parallel_min) {
#pragma omp parallel for schedule(static) reduction(min : bad)
    for (long i = 0; i < n; ++i)
      if (!finite(i)) bad = std::min(bad, i);
  } else {
    for (long i = 0; i < n && bad == n; ++i)
      if (!finite(i)) bad = i;
  }
  if (bad < n) {
    const size_t i = size_t(bad);
    throw RunError("particle " + std::to_string(P.id[i]) + " has a non-finite position or velocity at step " +
                     std::to_string(s.step) + " (t = " + std::to_string(s.time) +
                     " s): the time step is too large for the contact stiffness, or a particle was inserted overlapping");
  }
}

/// Above this many [[particle]] tables the note below is given: the TOML parse holds the
/// whole document, about 2 kB a particle at its peak (1.9 kB on the 32,000-sphere chute,
/// against 0.7 kB for its whole run with the particles in a CSV file).
constexpr size_t kManyParticleTables = 10000;
std::string many_tables_note(const Case& c) {
  return fmt::format("{} particles are [[particle]] tables: parsing them takes about {:.0f} MiB more; a [[particles]] CSV file "
                     "(docs/case-file.md) loads them without that",
                     c.particle_tables, 2e3 * double(c.particle_tables) / 1048576.0);
}

/// Peak resident memory of this process (VmHWM), bytes; 0 where /proc is not there.
double peak_rss_bytes() {
  std::ifstream f("/proc/self/status");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("VmHWM:", 0) == 0) return 1024.0 * std::stod(line.substr(6));  // kB
  return 0.0;
}

/// Hands freed heap back to the system and restarts the peak-RSS count (Linux: writing 5 to
/// clear_refs resets VmHWM to the current RSS), so the peak of the time loop can be read.
void reset_peak_rss() {
  malloc_trim(0);
  std::ofstream("/proc/self/clear_refs") << "5";
}

}  // namespace

void write_state_vtk(const System& s, const std::string& dir, const std::string& tag, bool contacts) {
  const fs::path d(dir);
  write_vtu(d / ("particles_" + tag + ".vtu"), particles_frame(s));
  if (!s.walls.empty()) write_vtu(d / ("walls_" + tag + ".vtu"), walls_vtu(s));
  if (contacts) write_vtu(d / ("contacts_" + tag + ".vtu"), contact_network_vtu(s));
}

int run_case(Case c, const RunOptions& opt) {
  if (c.ring_shear) return run_ring_shear(c, opt);  // resumes from its own stage checkpoints
  using clock = std::chrono::steady_clock;
  spdlog::info("case {} ({})", c.name.empty() ? c.file : c.name, c.file);
  const bool resuming = !opt.resume.empty();
  if (c.particle_tables > kManyParticleTables) spdlog::warn("{}", many_tables_note(c));
  auto sys = build_system(c, !resuming);
  System& s = *sys;
  std::vector<ExplicitParticle>().swap(c.particles);  // the system holds them now
  if (resuming) {
    if (const std::string app = read_checkpoint(opt.resume, s); !app.empty()) {
      // An application's checkpoint: a packed-bed protocol's stage (CBOR with a "complete"
      // flag) or the ring shear tester's.
      bool bed = false;
      try {
        bed = nlohmann::json::from_cbor(std::vector<uint8_t>(app.begin(), app.end())).contains("complete");
      } catch (const std::exception&) {
      }
      throw InputError(opt.resume, 0, "--resume",
                       bed ? "this checkpoint was written by a packed-bed protocol: resume it with the same `cohdem bed ...` command and --resume"
                           : "this checkpoint was written by the ring shear tester: resume it with its ring shear case");
    }
    spdlog::info("resuming from {} at step {} (t = {:.6g} s)", opt.resume, s.step, s.time);
  }
  const auto audit = audit_timestep(s, min_radius_by_material(s), audit_velocity(c));
  print_audit(audit);
  if (audit.level == TimestepAudit::Error) {
    std::string why;
    for (const auto& m : audit.messages)
      if (m.find("hard bound") != std::string::npos) why = m;
    throw InputError(c.file, c.dt_line, "simulation.dt", "time step past its hard bound: " + why);
  }

  const fs::path out = opt.out_dir.empty() ? fs::path(c.output.folder) : fs::path(opt.out_dir);
  fs::create_directories(out);
  const uint64_t nsteps = c.steps();
  spdlog::info("{} particles, {} walls, {} steps of {:.3g} s ({:.4g} s), contact model {} (rolling {}), output in {}",
               s.particles.size(), s.walls.size(), nsteps, c.cfg.dt, c.duration, c.model, c.rolling, out.string());
  {
    // The run's thread count before the line below asks System what it will do (prepare()
    // sets it too: before the seventieth round the line was written with the machine's
    // count, so a one-thread run was told two steps a sweep where it took four).
    if (c.cfg.threads > 0) omp_set_num_threads(c.cfg.threads);
    const int nt = c.cfg.threads > 0 ? c.cfg.threads : omp_get_max_threads();
    // Several steps per sweep (System::step_sweep): whether the size allows it; the run's
    // walls, pours and outputs decide step by step (summary.json's step_pairs counts them).
    const std::string pairs =
        c.cfg.pair_min < 0          ? "several steps per sweep off (pair_steps = false)"
        : System::pairs_off_by_env() ? "several steps per sweep off (COHDEM_PAIR=0)"
        : s.serial_blocks()          ? "several steps per sweep off (COHDEM_SERIAL_BLOCKS=1)"
        : c.thermal.enabled          ? "several steps per sweep off (thermal model)"
        : !s.pairs_fit_size()
            ? fmt::format("several steps per sweep off at this size (pair_min = {} particles per thread)", c.cfg.pair_min)
            : s.sweep_timing(2)
            ? fmt::format("2 or {} steps per sweep, whichever the run's timings find faster (sweep_tune), where the run "
                          "allows and the contacts are at most 1 a particle (summary.json: step_pairs)",
                          std::clamp(c.cfg.sweep_steps, 2, 4))
            : fmt::format("up to {} steps per sweep where the run allows and the contacts are at most 1 a particle "
                          "(summary.json: step_pairs)",
                          s.sweep_steps());
    spdlog::info("force loop: {} thread(s), list screening and contact lanes {}, {}", nt,
                 screen_avx512_enabled()
                     ? "AVX-512, eight at a time (COHDEM_SIMD=avx2 selects AVX2, four, COHDEM_SIMD=0 the scalar code)"
                 : screen_avx2_enabled() ? "AVX2, four at a time (COHDEM_SIMD=0 selects the scalar code)"
                                         : "scalar",
                 pairs);
    if (s.serial_blocks() && nt > 1)
      spdlog::warn("force loop: the {} threads' blocks run one after another on one thread (COHDEM_SERIAL_BLOCKS=1, "
                   "a diagnostic: the same results, not the threads' speed)",
                   nt);
  }

  if (!resuming) s.prepare();
  Series S = series_columns(c, s);
  // On resume keep the rows and frames written up to the checkpoint.
  std::vector<std::vector<double>> old_rows;
  nlohmann::json frames = nlohmann::json::array();
  if (resuming) {
    if (fs::exists(out / "series.csv")) {
      const CsvTable t = CsvTable::parse(series_complete_rows(out / "series.csv"), (out / "series.csv").string());
      if (t.has("step"))
        for (size_t r = 0; r < t.num_rows(); ++r) {
          if (t.column("step")[r] > double(s.step)) break;
          std::vector<double> row;
          for (const auto& col : S.cols) row.push_back(t.has(col) ? t.column(col)[r] : NAN);
          old_rows.push_back(row);
        }
    }
    if (fs::exists(out / "checkpoint.json")) {
      std::ifstream f(out / "checkpoint.json");
      frames = nlohmann::json::parse(f)["frames"];
    }
  }
  CsvWriter csv(out / "series.csv", S.cols);
  for (const auto& r : old_rows) csv.row(r);
  PvdSeries pvd_p(out / "particles.pvd"), pvd_w(out / "walls.pvd"), pvd_c(out / "contacts.pvd");
  int frame = 0;
  for (const auto& f : frames) {
    if (f["time"].get<double>() > s.time) break;
    pvd_p.add(f["time"].get<double>(), f["particles"].get<std::string>());
    if (f.contains("walls")) pvd_w.add(f["time"].get<double>(), f["walls"].get<std::string>());
    ++frame;
  }
  frames = nlohmann::json::array();
  for (const auto& e : pvd_p.entries()) frames.push_back({{"time", e.time}, {"particles", e.file}});
  for (size_t q = 0; q < pvd_w.entries().size() && q < frames.size(); ++q) frames[q]["walls"] = pvd_w.entries()[q].file;
  // Every series row up to this step is on disk before the checkpoint is: a run killed (or
  // a machine that loses power) after the checkpoint resumes with the whole series.
  auto checkpoint = [&]() {
    csv.sync();
    write_checkpoint(out / "checkpoint.bin", s);
    write_file_atomic(out / "checkpoint.json",
                      nlohmann::json({{"step", s.step}, {"time", s.time}, {"frames", frames}}).dump(1) + "\n",
                      Sync::durable);
  };
  auto write_frame = [&]() {
    if (!c.output.vtk) return;
    char name[64];
    std::snprintf(name, sizeof name, "particles_%05d.vtu", frame);
    write_vtu(out / name, particles_frame(s));
    pvd_p.add(s.time, name);
    frames.push_back({{"time", s.time}, {"particles", name}});
    if (!s.walls.empty()) {
      std::snprintf(name, sizeof name, "walls_%05d.vtu", frame);
      write_vtu(out / name, walls_vtu(s));
      pvd_w.add(s.time, name);
      frames.back()["walls"] = name;
    }
    if (c.output.contacts) {
      std::snprintf(name, sizeof name, "contacts_%05d.vtu", frame);
      write_vtu(out / name, contact_network_vtu(s));
      pvd_c.add(s.time, name);
    }
    ++frame;
  };
  const uint64_t series_every =
      c.output.series_interval > 0 ? std::max<uint64_t>(1, uint64_t(std::llround(c.output.series_interval / c.cfg.dt))) : 100;
  const uint64_t frame_every =
      c.output.frame_interval > 0 ? std::max<uint64_t>(1, uint64_t(std::llround(c.output.frame_interval / c.cfg.dt))) : 0;

  if (!resuming) {
    fill_row(c, s, S);
    csv.row(S.row);
    write_frame();
  }
  const double peak_rss_setup = peak_rss_bytes();
  reset_peak_rss();  // the case file's parse tree is gone: measure the run itself from here
  const auto t0 = clock::now();
  auto last = t0, last_ck = t0;
  uint64_t particle_steps = 0;
  const uint64_t first_step = s.step + 1;
  // Whether a series row or a frame is written after step k (the last step writes both).
  auto series_at = [&](const uint64_t k) { return k % series_every == 0 || k == nsteps; };
  auto frame_at = [&](const uint64_t k) {
    return (frame_every && k % frame_every == 0) || (k == nsteps && (!frame_every || k % frame_every != 0));
  };
  for (uint64_t k = first_step; k <= nsteps; ++k) {
    // What reads the state after this step is decided before it (the clock is read here,
    // once per step): a step after which nothing is written lets the force loop apply the
    // next step's opening half-kick and drift (System::step_once(true), bit-identical).
    const auto now = clock::now();
    const bool series_due = series_at(k);
    const bool frame_due = frame_at(k);
    // Checkpoints at the end of a step (a restart continues bit for bit from any step).
    const bool ck_due = c.output.checkpoint_interval > 0 &&
                        std::chrono::duration<double>(now - last_ck).count() >= c.output.checkpoint_interval;
    const bool stop_due =
        opt.max_wall_time >= 0 && k < nsteps && std::chrono::duration<double>(now - t0).count() >= opt.max_wall_time;
    const bool progress_due =
        !opt.quiet && std::chrono::duration<double>(now - last).count() >= c.output.progress_interval;
    const bool open_k = !(k == nsteps || series_due || frame_due || ck_due || stop_due || progress_due);
    // Several steps at once (System::step_sweep: the same results) when nothing is written
    // after this one or the next ones; the clock's events (checkpoint, progress, wall-time
    // limit) are then looked at a few steps later.
    if (open_k && s.mid_step() && k + 1 < nsteps && !series_at(k + 1) && !frame_at(k + 1) && s.pairs_allowed()) {
      // Up to sweep_steps() (four on one thread) while nothing is written after any of them.
      int g = 2;
      while (g < s.sweep_steps() && k + uint64_t(g) < nsteps && !series_at(k + uint64_t(g)) && !frame_at(k + uint64_t(g)))
        ++g;
      const int took = s.step_sweep(g);
      particle_steps += uint64_t(took) * s.particles.size();
      k += uint64_t(took - 1);
      continue;
    }
    s.step_once(open_k);
    particle_steps += s.particles.size();
    if (series_due) {
      check_finite(s);
      fill_row(c, s, S);
      csv.row(S.row);
    }
    if (frame_due) write_frame();
    if (ck_due) {
      checkpoint();
      last_ck = now;
    }
    if (stop_due) {
      check_finite(s);
      checkpoint();
      spdlog::warn("wall-time limit of {} s reached: stopped at step {} of {} (t = {:.6g} s); continue with --resume {}",
                   opt.max_wall_time, k, nsteps, s.time, (out / "checkpoint.bin").string());
      return kExitResumable;
    }
    if (progress_due) {
      last = now;
      const double el = std::chrono::duration<double>(clock::now() - t0).count();
      const double done = double(k - first_step + 1);
      spdlog::info("step {}/{} ({:.0f}%)  t = {:.5g} s  N = {}  contacts {}  KE {:.4g} J  {:.3g} particle-steps/s  ETA {}",
                   k, nsteps, 100.0 * k / nsteps, s.time, s.particles.size(), s.contact_count(), s.kinetic_energy(),
                   particle_steps / el, hms(el / done * double(nsteps - k)));
    }
  }
  // The rate is that of the time loop (as the peers' "loop time"); the final checkpoint
  // (hundreds of MB at 10^6 particles) is timed on its own.
  const auto t_loop = clock::now();
  const double loop_s = std::chrono::duration<double>(t_loop - t0).count();
  check_finite(s);
  checkpoint();  // lets a user extend the duration and resume
  const auto t_end = clock::now();
  const double wall_s = std::chrono::duration<double>(t_end - t0).count();
  nlohmann::json j;
  j["case"] = c.name;
  j["case_file"] = c.file;
  j["particles"] = s.particles.size();
  j["steps"] = nsteps;
  j["dt"] = c.cfg.dt;
  j["simulated_time"] = s.time;
  j["wall_time_s"] = wall_s;  // time loop and final checkpoint
  j["loop_time_s"] = loop_s;
  j["final_checkpoint_s"] = std::chrono::duration<double>(t_end - t_loop).count();
  j["particle_steps_per_s"] = loop_s > 0 ? double(particle_steps) / loop_s : 0.0;
  // System::step_sweep: sweeps of several steps evaluated (`pairs`, whatever their steps;
  // `steps` the steps in them, `steps_per_sweep` the most a sweep takes now), undone (a
  // rebuild fell between two of their steps) and the steps taken again after those; of the
  // sweeps, those evaluated near a rebuild on the displacements' forecast, and the calls
  // there that took plain steps; the calls that took plain steps because the contacts were
  // dense (SimConfig::pair_max_contacts); `snapshots`: the states saved for undoing a sweep
  // (after each list build and every 256 steps since). `tuning`: the choice between two steps a sweep and
  // sweep_steps by timing (System::SweepTune): the choices made, the steps chosen last and the
  // medians it chose on, ns a particle-step of the force loop (null until a choice is made).
  const System::SweepTune& tune = s.sweep_tune();
  const double per_ns = s.particles.size() == 0 ? 0.0 : 1e9 / double(s.particles.size());
  j["step_pairs"] = {{"pairs", s.pair_stats().pairs},
                     {"steps", s.pair_stats().swept_steps},
                     {"steps_per_sweep", s.sweep_steps()},
                     {"undone", s.pair_stats().replays},
                     {"steps_taken_again", s.pair_stats().replayed_steps},
                     {"forecast", s.pair_stats().forecast},
                     {"near_plain", s.pair_stats().near_plain},
                     {"dense_plain", s.pair_stats().dense_plain},
                     {"snapshots", s.pair_stats().snapshots},
                     {"tuning", tune.tunings == 0 ? nlohmann::json(nullptr)
                                                  : nlohmann::json{{"choices", tune.tunings},
                                                                   {"steps_per_sweep", tune.best > 0 ? tune.best : 0},
                                                                   {"two_ns", tune.s_two * per_ns},
                                                                   {"more_ns", tune.s_more * per_ns}}}};
  j["kinetic_energy"] = s.kinetic_energy();
  {  // flow observables of the free particles (benchmarks compare them with peer codes)
    double mfree = 0;
    for (size_t i = 0; i < s.particles.size(); ++i)
      if (s.particles.flag[i] == kFree) mfree += s.particles.mass[i];
    const Vec3 p = s.momentum();
    j["rotational_energy"] = s.rotational_energy();
    j["translational_energy"] = s.kinetic_energy() - s.rotational_energy();
    j["free_mass"] = mfree;
    const double im = mfree > 0 ? 1.0 / mfree : 0.0;
    j["mean_velocity"] = {p.x * im, p.y * im, p.z * im};
  }
  j["threads"] = omp_get_max_threads();
  {  // where the threads' time went, when the force loop ran on several (PairSlots' totals)
    const PairSlots& ts = s.thread_split();
    if (ts.timed_calls > 0) {
      const double calls = double(ts.timed_calls);
      nlohmann::json sweep = nlohmann::json::array(), handed = nlohmann::json::array(),
                     head = nlohmann::json::array();
      for (size_t t = 0; t < ts.busy_total.size(); ++t) {
        sweep.push_back(1e6 * ts.busy_total[t] / calls);
        head.push_back(1e6 * ts.head_total[t] / calls);
        handed.push_back(double(ts.handed_total[t]) / calls);
      }
      j["thread_sweep"] = {{"force_calls", ts.timed_calls},
                           {"sweep_us_per_call", sweep},
                           {"head_us_per_call", head},  // of the sweep: the next block's head finished
                           {"handed_over_per_call", handed},  // a step's time: loop_time_s / steps
                           // the mean over the calls of the longest sweep, and of the sweep
                           // had each call's work been split to end together (PairSlots)
                           {"longest_sweep_us_per_call", 1e6 * ts.longest_total / calls},
                           {"balanced_sweep_us_per_call", 1e6 * ts.balanced_total / calls},
                           {"rebalances", ts.rebalances},  // splits moved by the measured times
                           {"shares", ts.share},  // each block's share of the modelled work at the end
                           // the blocks swept one after another on one thread (SimConfig::serial_blocks)
                           {"serial_blocks", s.serial_blocks()},
                           {"serial_calls", ts.serial_calls}};
    }
  }
  j["screening"] = screen_simd_name();  // the force loop's list screening (results identical)
  j["peak_rss_bytes"] = std::max(peak_rss_setup, peak_rss_bytes());  // whole process
  j["peak_rss_run_bytes"] = peak_rss_bytes();  // from the start of the time loop
  j["run_bytes_per_particle"] = s.particles.size() ? peak_rss_bytes() / double(s.particles.size()) : 0.0;
  j["contacts"] = s.contact_count();
  j["neighbor_builds"] = s.nl.stats.builds;
  j["neighbor_checks"] = s.nl.stats.checks;      // local checks where the trigger fired (NeighborList::recheck)
  j["neighbor_deferred"] = s.nl.stats.deferred;  // of them, those that kept the lists
  j["lost_contacts"] = s.nl.stats.lost_contacts;
  j["frames"] = frame;
  j["timestep_audit"] = {{"rayleigh_time", audit.rayleigh}, {"collision_time", audit.collision},
                         {"audit_velocity", audit.velocity}};
  if (audit.rolling > 0 && std::isfinite(audit.rolling)) j["timestep_audit"]["rolling_half_period"] = audit.rolling;
  for (const Wall& w : s.walls)
    j["walls"][w.name] = {{"force", {w.force.x, w.force.y, w.force.z}}, {"torque", {w.torque.x, w.torque.y, w.torque.z}}};
  if (s.thermal) {
    double lo = INFINITY, hi = -INFINITY, sum = 0;
    for (double T : s.particles.temperature) { lo = std::min(lo, T); hi = std::max(hi, T); sum += T; }
    const size_t np = s.particles.size();
    j["thermal"] = {{"mean_temperature", np ? sum / double(np) : 0.0}, {"min_temperature", np ? lo : 0.0},
                    {"max_temperature", np ? hi : 0.0}, {"time_scale", s.thermal->settings().time_scale},
                    {"last_stability_ratio", s.thermal->stability}};
    for (size_t w = 0; w < s.walls.size(); ++w)
      if (s.thermal->wall_fixed(w)) j["walls"][s.walls[w].name]["heat"] = s.thermal->wall_heat[w];
  }
  write_file_atomic(out / "summary.json", j.dump(2) + "\n");
  spdlog::info("done: {} steps in {:.2f} s ({:.3g} particle-steps/s; final checkpoint {:.2f} s), {} frames, final KE {:.4g} J, {} contacts",
               nsteps, loop_s, double(j["particle_steps_per_s"]), double(j["final_checkpoint_s"]), frame, s.kinetic_energy(),
               s.contact_count());
  return 0;
}

int check_case(const Case& c) {
  System s;
  s.cfg = c.cfg;
  s.materials = c.materials;
  s.set_model(make_contact_model(c.model, c.rolling, c.file), c.pair_params);
  s.walls = c.walls;
  std::vector<double> rmin(c.materials.size(), 0.0);
  std::vector<double> count(c.materials.size(), 0.0), mass(c.materials.size(), 0.0);
  double rmax = 0, volume = 0;  // largest radius, particles' total volume (memory estimate)
  auto take = [&](int m, double r, double r_hi) {
    rmin[m] = rmin[m] > 0 ? std::min(rmin[m], r) : r;
    rmax = std::max(rmax, r_hi);
  };
  for (const auto& st : c.inserts) {
    const int m = st.spec.species;
    take(m, st.spec.size.min_radius(), st.spec.size.max_radius());
    const double n = st.spec.count ? double(st.spec.count)
                                   : std::floor(st.spec.solids_fraction * st.spec.region.volume() / st.spec.size.mean_volume());
    count[m] += n;
    mass[m] += n * st.spec.size.mean_volume() * c.materials[m].density;
    volume += n * st.spec.size.mean_volume();
  }
  if (c.ring_shear) {
    const RingShearSpec& r = *c.ring_shear;
    const double area = r.cell == "shear_box" ? r.length * r.width : M_PI * (r.r_outer * r.r_outer - r.r_inner * r.r_inner);
    const double n = std::ceil(r.packing_guess * area * r.bed_height / r.size.mean_volume());
    take(r.material, r.size.min_radius(), r.size.max_radius());
    count[r.material] += n;
    mass[r.material] += n * r.size.mean_volume() * c.materials[r.material].density;
    volume += n * r.size.mean_volume();
    fmt::print("ring shear: {} cell, area {:.4g} m^2, sigma_pre {:.4g} Pa, {} shear points (plus rough layers)\n", r.cell, area,
               r.sigma_pre, r.fractions.size());
  }
  for (const auto& p : c.particles) {
    take(p.material, p.radius, p.radius);
    count[p.material] += 1;
    mass[p.material] += 4.0 / 3.0 * M_PI * std::pow(p.radius, 3) * c.materials[p.material].density;
    volume += 4.0 / 3.0 * M_PI * std::pow(p.radius, 3);
  }
  double total = 0;
  fmt::print("case: {} ({})\n", c.name.empty() ? "(unnamed)" : c.name, c.file);
  fmt::print("contact model: {} (rolling {}), {} bytes of history per contact\n", c.model, c.rolling, s.model->state_size());
  for (size_t m = 0; m < c.materials.size(); ++m) {
    if (count[m] == 0) continue;
    total += count[m];
    fmt::print("material {}: {:.0f} particles, smallest radius {:.4g} m, mean particle mass {:.4g} kg, total mass {:.4g} kg\n",
               c.materials[m].name, count[m], rmin[m], mass[m] / count[m], mass[m]);
  }
  fmt::print("particles: {:.0f} (fills and explicit; pours included)\n", total);
  fmt::print("steps: {} of dt = {:.4g} s for {:.4g} s simulated\n", c.steps(), c.cfg.dt, c.duration);
  const auto a = audit_timestep(s, rmin, audit_velocity(c));
  if (a.rayleigh > 0) fmt::print("Rayleigh time: {:.4g} s ({}), dt/T_R = {:.3f}\n", a.rayleigh, a.rayleigh_material, a.dt / a.rayleigh);
  if (a.collision > 0 && std::isfinite(a.collision))
    fmt::print("collision time: {:.4g} s ({} at {:.3g} m/s), {:.1f} steps per collision\n", a.collision, a.collision_pair,
               a.velocity, a.collision / a.dt);
  if (a.rolling > 0 && std::isfinite(a.rolling))
    fmt::print("rolling spring half period: {:.4g} s ({}), {:.1f} steps\n", a.rolling, a.rolling_pair, a.rolling / a.dt);
  double crit = INFINITY;
  if (a.rayleigh > 0) crit = std::min(crit, kWarnRayleigh * a.rayleigh);
  if (a.collision > 0 && std::isfinite(a.collision)) crit = std::min(crit, a.collision / kWarnStepsPerCollision);
  if (a.rolling > 0 && std::isfinite(a.rolling)) crit = std::min(crit, a.rolling / kWarnStepsPerCollision);
  if (std::isfinite(crit)) fmt::print("critical time step (safe): {:.4g} s\n", crit);
  // Memory of a one-thread run's time loop (its peak, as summary.json's peak_rss_run_bytes
  // measures it; with [[particle]] tables the parse of the case file can peak higher, about
  // 2 kB a particle): per particle, the particle arrays (157 bytes, particles/particle_store.hpp;
  // 4 more with particles attached to walls: their wall; 24 more with [thermal]: reference
  // radius, temperature, heat flow), the lists' per-particle arrays and reference state (80;
  // 8 more with [thermal]: the radii at the build) and the force loop's reverse sums (48);
  // per entry of the half list, partner, image, transposed index, live flag, the pair as
  // found at a build (9) and the history record, with the lists' eighth of headroom; per
  // contact, the copy a build makes of it (partner and record). The half list of a bed at
  // random close packing (solids fraction 0.64) holds 0.5 x 0.64 x 8 (1 + skin / d)^3
  // entries per particle of diameter d (here the particles' volume-mean diameter; d = 1,
  // skin 0.1: 3.4, the chute benchmark's measured 3.47), and 3 contacts (coordination
  // number 6). Plus the program itself, ~7 MiB. A looser bed or a gas holds fewer entries
  // and contacts, so this is an upper estimate for one size of particles.
  if (total > 0) {
    bool attached = c.ring_shear.has_value();  // the tester's ribs are carried by its walls
    for (const auto& p : c.particles) attached = attached || p.attach_wall >= 0;
    const double d = 2 * std::cbrt(3 * volume / (4 * M_PI * total));
    const double skin = c.cfg.skin > 0 ? c.cfg.skin : 0.2 * rmax;  // System::prepare's default
    const double entries = 0.5 * 0.64 * 8 * std::pow(1 + skin / d, 3);
    const double rec = double(s.model->state_size());
    const double per_particle =
        157 + (attached ? 4 : 0) + (c.thermal.enabled ? 24 + 8 : 0) + 80 + 48 + 1.125 * entries * (19 + rec) +
        3 * (4 + rec);
    const double bytes = 7.0 * 1048576 + total * per_particle;
    fmt::print("memory estimate: {:.1f} MiB for the time loop on one thread ({:.0f} bytes per particle, ~{:.1f} list entries each in a dense bed)\n",
               bytes / 1048576.0, bytes / total, entries);
    if (c.particle_tables > kManyParticleTables) fmt::print("note: {}\n", many_tables_note(c));
  }
  if (c.thermal.enabled) {
    int fixed = 0;
    for (const auto& w : c.thermal.walls) fixed += w.fixed;
    fmt::print("thermal: initial temperature {:.6g} K, time_scale {:.4g}, expansion {}, contact radius from {}, "
               "{} fixed-temperature walls, {} heat sources\n",
               c.cfg.initial_temperature, c.thermal.time_scale, c.thermal.expansion ? "on" : "off",
               c.thermal.contact_radius == ThermalSettings::SpotRadius::Model ? "the contact law" : "the Hertz force",
               fixed, c.thermal.sources.size());
  }
  for (const auto& m : a.messages) fmt::print("{}: {}\n", a.level == TimestepAudit::Error ? "error" : "warning", m);
  if (a.level == TimestepAudit::Error) {
    fmt::print(stderr, "error: {}:{}: key 'simulation.dt': time step past its hard bound\n", c.file, c.dt_line);
    return 1;
  }
  fmt::print("ok\n");
  return 0;
}

}  // namespace cohdem
