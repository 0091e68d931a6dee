#include "sim/system.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <map>
#include <stdexcept>
#include <string>

#include "core/error.hpp"
#include "core/grow.hpp"
#include "sim/force_context.hpp"
#include "thermal/thermal.hpp"

namespace cohdem {

namespace {
/// Rotates v about unit axis a by angle th (Rodrigues).
Vec3 rotate(const Vec3& v, const Vec3& a, double th) {
  const double c = std::cos(th), s = std::sin(th);
  return v * c + cross(a, v) * s + a * (dot(a, v) * (1 - c));
}
}  // namespace

void System::set_model(std::unique_ptr<ContactModel> m, const std::vector<ParamSet>& pair_params) {
  const int n = int(materials.size());
  std::vector<PairMaterial> mats(size_t(n) * n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const Material &a = materials[i], &b = materials[j];
      if (a.E > 0 && b.E > 0) mats[i * n + j] = PairMaterial::make(a.E, a.nu, b.E, b.nu, false);
    }
  m->set_params(n, pair_params, mats);
  model = std::move(m);
  nl.hist.stride = nl.whist.stride = model->state_size();
  nl.hist.flip = model->flipper();
  dirty_ = true;
}

size_t System::add_particle(int species, double r, const Vec3& x, const Vec3& v, const Vec3& w) {
  dirty_ = true;
  return particles.add(next_id++, species, r, materials.at(species).density, x, v, w, cfg.initial_temperature);
}

Vec3 System::initial_velocity(const InsertSpec& spec) {
  if (spec.velocity_jitter <= 0) return spec.velocity;
  const double a = spec.velocity_jitter;
  return spec.velocity + Vec3{rng.uniform(-a, a), rng.uniform(-a, a), rng.uniform(-a, a)};
}

size_t System::insert(const InsertSpec& spec) {
  const InsertResult res = insert_random(spec, rng, particles.x, particles.radius);
  for (size_t k = 0; k < res.x.size(); ++k) add_particle(spec.species, res.r[k], res.x[k], initial_velocity(spec));
  return res.x.size();
}

void System::resume_prepare(const NeighborList::Reference* ref) {
  opened_ = false;  // a restart starts at a step boundary
  prepare_reach();
  if (ref) nl.rebuild_at(particles, walls, cfg.domain, cfg.skin, reach_, *ref);
  else nl.build(particles, walls, cfg.domain, cfg.skin, reach_, false);
  if (has_pending_) install_pending();
  dirty_ = false;
}

void System::prepare_reach() {
  if (!model) throw RunError("no contact model set");
  // The thermal fields, kept only with a thermal model (however it was attached; a particle
  // without them starts at the initial temperature), before any re-sort permutes them.
  if (thermal) particles.enable_thermal(cfg.initial_temperature);
  if (cfg.threads > 0) omp_set_num_threads(cfg.threads);
  // Every particle attached to a wall names one (ParticleStore::attach).
  if (const size_t i = particles.first_bad_attachment(walls.size()); i < particles.size())
    throw RunError("particle " + std::to_string(particles.id[i]) + " is flagged as attached but names no wall of the " +
                   std::to_string(walls.size()) + " (ParticleStore::attach)");
  double rmax = 0;
  for (double r : particles.radius) rmax = std::max(rmax, r);
  for (const auto& p : pours) rmax = std::max(rmax, p.spec.size.max_radius());
  // Skin 0 means the default, 0.2 x the largest radius, however the particles were made
  // (case tables, pours, an application's own fill); without it the lists would be rebuilt
  // at every step.
  if (cfg.skin <= 0) cfg.skin = 0.2 * rmax;
  reach_ = 0;
  const int n = int(materials.size());
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) reach_ = std::max(reach_, model->reach(i, j, rmax));
}

void System::prepare() {
  if (opened_) throw std::logic_error("System::prepare in the middle of a step (step_once(true))");
  prepare_reach();
  const bool resort = cfg.sort_every > 0 && nl.stats.builds % uint64_t(cfg.sort_every) == 0;
  nl.build(particles, walls, cfg.domain, cfg.skin, reach_, resort);
  if (has_pending_) install_pending();
  // Forces at this instant without advancing the springs: no time passes. At the start they
  // are zero (as in LAMMPS's setup); in the middle of a run (particles removed, a lid moved,
  // a copied bed) they already hold this instant's increment, which a second increment would
  // count twice (History.PrepareInTheMiddleOfARunDoesNotAdvanceTheSprings).
  compute_forces(0, false, nullptr, true);
  if (thermal) thermal->update(*this, false);
  dirty_ = false;
}

void System::install_pending() {
  // Match saved keys against the freshly built lists (both small: a map is fine here).
  const size_t st = nl.hist.stride;
  std::map<std::pair<uint64_t, uint64_t>, size_t> pk, wk;
  for (size_t q = 0; q < pending_.pair_keys.size(); ++q) pk[pending_.pair_keys[q]] = q;
  for (size_t q = 0; q < pending_.wall_keys.size(); ++q) wk[pending_.wall_keys[q]] = q;
  size_t found = 0;
  // A pair saved from the other side (its two particles in the other order: a checkpoint
  // whose lists held it in the other's row) is rewritten as seen from this row's particle.
  for (size_t i = 0; i + 1 < nl.start.size(); ++i)
    for (uint32_t k = nl.start[i]; k < nl.start[i + 1]; ++k) {
      const uint64_t a = particles.id[i], b = particles.id[nl.jdx[k]];
      auto it = pk.find({a, b});
      const bool swapped = it == pk.end();
      if (swapped) it = pk.find({b, a});
      if (it == pk.end()) continue;
      std::memcpy(nl.hist.at(k), pending_.pair_data.data() + it->second * st, st);
      if (swapped && nl.hist.flip) nl.hist.flip(nl.hist.at(k));
      nl.hist.live[k] = 1;
      ++found;
    }
  for (size_t i = 0; i + 1 < nl.wstart.size(); ++i)
    for (uint32_t e = nl.wstart[i]; e < nl.wstart[i + 1]; ++e) {
      auto it = wk.find({particles.id[i], nl.wall[e]});
      if (it == wk.end()) continue;
      std::memcpy(nl.whist.at(e), pending_.wall_data.data() + it->second * st, st);
      nl.whist.live[e] = 1;
      ++found;
    }
  if (found != pk.size() + wk.size())
    throw RunError("checkpoint: " + std::to_string(pk.size() + wk.size() - found) +
                   " saved contacts have no pair in the rebuilt neighbor list");
  pending_ = {};
  has_pending_ = false;
}

void System::move_wall_geometry(double dt) {
  wall_dx_.resize(walls.size());
  for (size_t w = 0; w < walls.size(); ++w) {
    Wall& W = walls[w];
    const double w0 = 2 * M_PI * W.osc_frequency;
    const Vec3 osc = W.osc_amplitude != 0
                         ? W.osc_dir * (W.osc_amplitude * (std::sin(w0 * (time + dt)) - std::sin(w0 * time)))
                         : Vec3{};
    const Vec3 dx = W.velocity * dt + W.normal * (W.vn * dt) + osc;
    wall_dx_[w] = dx;
    W.point += dx;
    W.center += dx;
    if (W.control != WallControl::Prescribed) W.travel += W.vn * dt;
  }
}

void System::control_walls(double dt) {
  for (Wall& W : walls) {
    if (time < W.control_start) continue;  // held (e.g. a lid released once the bed has settled)
    switch (W.control) {
      case WallControl::Prescribed: break;
      case WallControl::Servo: {
        // Compressive load on the wall: particles push it against its normal.
        const double load = -dot(W.force, W.normal);
        W.vn = std::clamp(W.servo_gain * (W.target_force - load), -W.servo_vmax, W.servo_vmax);
        break;
      }
      case WallControl::Spring: {
        const double f = dot(W.force, W.normal) + W.spring_preload - W.spring_k * W.travel +
                         W.mass * dot(cfg.gravity, W.normal);
        W.vn += f / W.mass * dt;
        break;
      }
    }
  }
}

void System::do_pours() {
  for (PourSource& s : pours) {
    if (s.inserted >= s.spec.count || time < s.t_start || time < s.next_time) continue;
    // Insert what the rate allows up to now, as far as the region has room.
    const uint64_t due = std::min<uint64_t>(s.spec.count, uint64_t((time - s.t_start) * s.rate) + 1);
    if (due <= s.inserted) continue;
    InsertSpec batch = s.spec;
    batch.count = due - s.inserted;
    const InsertResult res = insert_random(batch, rng, particles.x, particles.radius, batch.count);
    for (size_t k = 0; k < res.x.size(); ++k) add_particle(batch.species, res.r[k], res.x[k], initial_velocity(batch));
    s.inserted += res.x.size();
    s.next_time = time + s.interval;
  }
}

void System::compute_forces(double kick_h, bool open_next, Drift* second, bool hold_springs, Drift* third,
                            Drift* fourth) {
  const size_t np = nl.pair_count(), nw = nl.wall_entry_count();
  const bool record = thermal || cfg.record_contacts;  // per-contact forces and radii
  contacts_recorded_ = record;
  if (rev_.size() < particles.size()) rev_.resize(particles.size());
  if (f_wall_.size() < nw) { f_wall_.resize(nw); tw_wall_.resize(nw); c_wall_.resize(nw); }
  if (record) {
    grow_to(a_pair_, np);
    if (a_wall_.size() < nw) a_wall_.resize(nw);
  }
  // Gravity is added by the kernel, after the contact forces of each free particle.
  ForceContext ctx{particles, nl, walls, hold_springs ? 0.0 : cfg.dt, time, pair_, rev_, f_wall_, tw_wall_, c_wall_, cfg.gravity};
  ctx.parallel_min = cfg.parallel_min;
  ctx.kick_h = kick_h;
  if (open_next) {
    open_drift_ = Drift{};
    ctx.open_dt = cfg.dt;
    ctx.drift = &open_drift_;
    ctx.drift2 = second;  // step_sweep: the next steps in the same sweep
    ctx.drift_more[0] = third;
    ctx.drift_more[1] = fourth;
  }
  ctx.keep_pair = record;
  ctx.slots = &slots_;
  ctx.serial_blocks = serial_blocks();
  ctx.a_pair = record ? a_pair_.data() : nullptr;
  ctx.a_wall = record ? a_wall_.data() : nullptr;
  // The per-pair results exist only when read (one thread without recording never touches
  // them: 48 bytes per list entry saved).
  if (ctx.needs_pair_buffer(long(particles.size()))) grow_to(pair_, np);
  model->compute(ctx);

  // Wall totals in a fixed order, whatever the thread count: partial sums over fixed blocks
  // of particles, then the blocks in order. Within a block, its wall entries in list order
  // (a contiguous range: the entries are stored particle by particle), then its particles
  // attached to a wall, ascending (the list's record of them). No per-particle indirection:
  // at 10^4 particles the walk over the particles with wall entries cost 4-5 us per step,
  // 3-4 % of a two-thread step.
  if (walls.empty()) return;
  const long n = long(particles.size());
  const size_t nwall = walls.size();
  constexpr long kBlock = 4096;
  const long nb = (n + kBlock - 1) / kBlock;
  wall_part_.assign(size_t(nb) * nwall * 2, Vec3{});
  const std::vector<uint32_t>& att = nl.attached;
  auto block_sums = [&](const long b) {
    Vec3* part = wall_part_.data() + size_t(b) * nwall * 2;  // force, torque of each wall
    const long lo = b * kBlock, end = std::min(n, lo + kBlock);
    const uint8_t* const live = nl.whist.live.data();
    for (uint32_t e = nl.wstart[size_t(lo)], e1 = nl.wstart[size_t(end)]; e < e1; ++e) {
      if (!live[e]) continue;
      const size_t w = nl.wall[e];
      part[2 * w] -= f_wall_[e];
      part[2 * w + 1] += cross(c_wall_[e] - walls[w].center, -f_wall_[e]) + tw_wall_[e];
    }
    for (auto q = std::lower_bound(att.begin(), att.end(), uint32_t(lo)); q != att.end() && long(*q) < end; ++q) {
      const size_t i = *q, w = particles.body[i];
      part[2 * w] += particles.force[i];
      part[2 * w + 1] += cross(particles.x[i] - walls[w].center, particles.force[i]) + particles.torque[i];
    }
  };
  // The work is the wall entries' and the attached particles': on one thread below
  // parallel_min of them, without entering an OpenMP construct (a region on one thread
  // still costs a team's set-up; the result is the same).
  const long work = long(nl.wall_entry_count() + att.size());
  if (work > cfg.parallel_min) {
#pragma omp parallel for schedule(static)
    for (long b = 0; b < nb; ++b) block_sums(b);
  } else {
    for (long b = 0; b < nb; ++b) block_sums(b);
  }
  for (Wall& W : walls) { W.force = {}; W.torque = {}; }
  for (long b = 0; b < nb; ++b)
    for (size_t w = 0; w < nwall; ++w) {
      walls[w].force += wall_part_[(size_t(b) * nwall + w) * 2];
      walls[w].torque += wall_part_[(size_t(b) * nwall + w) * 2 + 1];
    }
}

void System::step_once(bool open_next) {
  // step_sweep's snapshot stays where an undone sweep can take this step again from it with
  // the same result (the undoing takes every step since the snapshot as a plain step, and a
  // plain step's state is the same, bit for bit, whether or not it was opened by the force
  // loop): replayable() checked before the step and after it (a wall's control may set it
  // moving), the time step and gravity before it (the step does not change them). The
  // runner's steps after which something is written came between sweeps, and each of them
  // cost a new snapshot (at 10^6 particles 15-25 ms, more than a step; a series row every
  // 100 steps: ten snapshots in 1000 steps instead of three).
  const bool keep = snap_.valid && snap_.same_config(cfg) && replayable();
  begin_step();
  end_step(open_next);
  if (keep && replayable())
    ++snap_.swept;  // steps since the snapshot, which an undone sweep takes again
  else
    snap_.valid = false;
}

void System::begin_step() {
  if (dirty_) {
    if (opened_) throw std::logic_error("System: particles or walls changed in the middle of a step (step_once(true))");
    prepare();
  }
  const double dt = cfg.dt, h = 0.5 * dt;
  ParticleStore& P = particles;
  const long n = long(P.size());
  // Walls move first: their motion does not depend on the particles (servo and lid speeds
  // were set at the end of the previous step).
  move_wall_geometry(dt);
  // One pass over the particles: velocity Verlet's opening half-kick and the drift of free
  // particles, the rigid carrying of particles attached to walls (rotated about the wall's
  // old centre, then translated), and their displacement since the last list build, for the
  // rebuild decision (the reduction is exact: the same on any number of threads). After
  // step_once(true) the force loop has done the free (and frozen) particles' part already.
  const bool opened = opened_;
  opened_ = false;
  const bool tracked = nl.has_reference(size_t(n));
  const double t1 = time + dt;
  Drift drift = opened ? open_drift_ : Drift{};
  // Rigid carrying of particle i, attached to wall body[i]: rotated about the wall's old
  // centre, then translated.
  auto carry = [&](const size_t i) {
    const Wall& W = walls[size_t(P.body[i])];
    const double wn = norm(W.omega);
    const Vec3 dx = wall_dx_[size_t(P.body[i])];  // the wall's translation this step
    Vec3 x = P.x[i];
    // W.center has already moved by dx: rotate about the old centre, then translate.
    if (wn > 0) x = (W.center - dx) + rotate(x - (W.center - dx), W.omega / wn, wn * dt);
    P.x[i] = x + dx;
    P.v[i] = W.velocity_at(P.x[i], t1);
    P.omega[i] = W.omega;
  };
  // Below parallel_min on one thread, with no OpenMP region (drift_pass).
  if (opened) {
    // Only the attached particles are left (the list's record of them: flags change only
    // with a prepare(), which rebuilds it); none, no parallel region either.
    const std::vector<uint32_t>& att = nl.attached;
    const long na = long(att.size());
    drift_pass(na, na > cfg.parallel_min, drift, [&](const long q, Drift& d) {
      carry(att[size_t(q)]);
      if (tracked) nl.add_drift(d, P, att[size_t(q)]);
    });
  } else {
    drift_pass(n, n > cfg.parallel_min, drift, [&](const long i, Drift& d) {
      const uint8_t f = P.flag[i];
      if (f == kFree) {
        // In registers, each result stored once: x[i] += v[i] dt right after storing v[i]
        // would read it back through a 16-byte load the store buffer cannot forward (a stall).
        Vec3 v = P.v[i], w = P.omega[i];
        open_free(v, w, P.x[i], P.force[i], P.torque[i], h / P.mass[i], h / P.inertia[i], dt);
        P.v[i] = v;
        P.omega[i] = w;
      } else if (f == kAttached) {
        carry(size_t(i));
      }
      if (tracked) nl.add_drift(d, P, size_t(i));  // frozen particles only mark the set
    });
  }
  time = t1;
  ++step;
  if (!pours.empty()) {
    const size_t before = P.size();
    do_pours();
    if (P.size() != before) dirty_ = true;
  }
  nl.parallel_min = cfg.parallel_min;
  nl.local_cutoffs = cfg.local_rebuild;
  // Where the trigger fires, the local check may find the lists good still (sheared flows:
  // NeighborList::recheck); otherwise a build.
  if (dirty_ || !tracked || (nl.rebuild_due(drift, walls, cfg.skin) && !nl.recheck(P, walls, cfg.skin))) {
    const bool resort = cfg.sort_every > 0 && nl.stats.builds % uint64_t(cfg.sort_every) == 0;
    nl.build(P, walls, cfg.domain, cfg.skin, reach_, resort);
    dirty_ = false;
  }
}

void System::end_step(bool open_next) {
  const double dt = cfg.dt, h = 0.5 * dt;
  ParticleStore& P = particles;
  // The closing half-kick: applied by the force kernel to each particle as its force is
  // complete (one pass fewer), unless a thermal model changes radii and inertia first; so is
  // the next step's opening when the caller allows it (not with a thermal model either, nor
  // while the lists still count radius growth since their build: the fused drift reads none).
  const bool fuse = open_next && !thermal && !nl.tracks_radii();
  compute_forces(thermal ? 0.0 : h, fuse);
  if (thermal) {
    thermal->update(*this, true);  // heat flow, temperatures, radii (and inertia)
    const long n2 = long(P.size());
    auto kick = [&](const long i) {
      if (P.flag[i] != kFree) return;
      P.v[i] += P.force[i] * (h / P.mass[i]);
      P.omega[i] += P.torque[i] * (h / P.inertia[i]);
    };
    if (n2 > cfg.parallel_min) {
#pragma omp parallel for schedule(static)
      for (long i = 0; i < n2; ++i) kick(i);
    } else {
      for (long i = 0; i < n2; ++i) kick(i);
    }
  }
  control_walls(dt);
  opened_ = fuse;
}

bool System::pairs_off_by_env() {
  static const bool off = [] {
    const char* e = std::getenv("COHDEM_PAIR");
    return e != nullptr && std::string(e) == "0";
  }();
  return off;
}

int System::sweep_steps_by_env() {
  static const int k = [] {
    const char* e = std::getenv("COHDEM_SWEEP");
    if (e == nullptr || *e == '\0') return 0;
    char* end = nullptr;
    const long v = std::strtol(e, &end, 10);
    if (*end != '\0' || v < 2 || v > 4)
      throw RunError(std::string("environment variable COHDEM_SWEEP: expected 2, 3 or 4 steps a sweep, got '") + e + "'");
    return int(v);
  }();
  return k;
}

int System::untimed_sweep_steps() const {
  const long n = long(particles.size());
  if (n > cfg.parallel_min && omp_get_max_threads() > 1) return 2;  // the force loop on several threads
  const int env = sweep_steps_by_env();
  if (env > 0) return env;
  return n >= cfg.sweep_min ? std::clamp(cfg.sweep_steps, 2, 4) : 2;
}

int System::timed_choice() const {
  const int most = untimed_sweep_steps();
  return cfg.sweep_tune && most > 2 && sweep_steps_by_env() == 0 ? most : 0;
}

int System::sweep_steps() const {
  const int most = timed_choice();
  if (most == 0) return untimed_sweep_steps();
  if (tune_.best > 0) return tune_.best;
  return tune_.more_next ? most : 2;
}

bool System::sweep_timing(const int wanted) const {
  const int most = timed_choice();
  return most > 0 && tune_.best == 0 && (wanted == 2 || wanted == most);
}

void System::note_sweep_time(const int K, const double seconds) {
  const int most = timed_choice();
  if (tune_.best > 0 || most == 0 || (K != 2 && K != most) || !(seconds >= 0)) return;
  (K == 2 ? tune_.two : tune_.more).push_back(seconds);
  tune_.more_next = K == 2;  // alternated, so that a slow spell of the machine weighs on both
  if (tune_.two.size() < SweepTune::kSamples || tune_.more.size() < SweepTune::kSamples) return;
  auto median = [](std::vector<double>& v) {
    std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
    return v[v.size() / 2];
  };
  tune_.s_two = median(tune_.two);
  tune_.s_more = median(tune_.more);
  tune_.best = tune_.s_more < tune_.s_two ? most : 2;
  tune_.chosen_at = pair_stats_.swept_steps;
  ++tune_.tunings;
  tune_.two.clear();
  tune_.more.clear();
  tune_.more_next = true;
}

bool System::serial_blocks_by_env() {
  static const bool on = [] {
    const char* e = std::getenv("COHDEM_SERIAL_BLOCKS");
    return e != nullptr && std::string(e) == "1";
  }();
  return on;
}

bool System::pairs_fit_size() const {
  // pair_min particles per thread: on the development VM, two threads gained about 4 %
  // at 10^6 particles and lost about 11 % at 10^5 (docs/performance-history.md, thirty-fifth round).
  const long n = long(particles.size()), nt = n > cfg.parallel_min ? long(omp_get_max_threads()) : 1;
  return cfg.pair_min >= 0 && n >= cfg.pair_min * nt;
}

bool System::replayable() const {
  if (dirty_ || thermal || !pours.empty() || cfg.record_contacts || !nl.attached.empty() || nl.tracks_radii())
    return false;
  // Walls that stay where they are (a snapshot holds no wall; in a sweep, the second step's
  // wall contacts are evaluated with the walls of the first).
  for (const Wall& W : walls)
    if (W.control != WallControl::Prescribed || !(W.velocity == Vec3{}) || W.vn != 0 || W.osc_amplitude != 0 ||
        !(W.omega == Vec3{}))
      return false;
  return true;
}

bool System::pairs_allowed() const {
  if (!pairs_fit_size() || !opened_ || !nl.has_reference(particles.size()) || !replayable()) return false;
  return !pairs_off_by_env() && !serial_blocks();
}

void System::SparseHistory::take(const HistoryArray& h, const int threads) {
  const size_t st = h.stride, n = h.live.size();
  const std::byte* const d = h.data.data();
  // Whether record r holds a non-zero byte: eight at a time where the records are whole
  // words (all the laws' are; byte by byte this scan took most of a snapshot's time).
  const bool words = st % 8 == 0;
  auto nonzero = [&](const std::byte* r) {
    if (words) {
      uint64_t acc = 0;
      for (size_t b = 0; b < st; b += 8) {
        uint64_t w;
        std::memcpy(&w, r + b, 8);
        acc |= w;
      }
      return acc != 0;
    }
    for (size_t b = 0; b < st; ++b)
      if (r[b] != std::byte{0}) return true;
    return false;
  };
  // Entries [lo, hi) into `out` (appended in entry order).
  auto scan = [&](const size_t lo, const size_t hi, SparseHistory& out) {
    for (size_t e = lo; e < hi; ++e) {
      const std::byte* const r = d + e * st;
      if (h.live[e] == 0 && !nonzero(r)) continue;
      out.k.push_back(uint32_t(e));
      out.live.push_back(h.live[e]);
      out.rec.insert(out.rec.end(), r, r + st);
    }
  };
  k.clear();
  live.clear();
  rec.clear();
  if (threads <= 1) {
    scan(0, n, *this);
    return;
  }
  // The scan reads every record (hundreds of MB at 10^6 particles, a few ms a thread); the
  // kept ones (live contacts: about 0.1-0.5 a particle) are few, and joined in order.
  std::vector<SparseHistory> parts(static_cast<size_t>(threads));
#pragma omp parallel num_threads(threads)
  {
    const size_t nt = size_t(omp_get_num_threads()), t = size_t(omp_get_thread_num());
    scan(n * t / nt, n * (t + 1) / nt, parts[t]);
  }
  for (const SparseHistory& part : parts) {
    k.insert(k.end(), part.k.begin(), part.k.end());
    live.insert(live.end(), part.live.begin(), part.live.end());
    rec.insert(rec.end(), part.rec.begin(), part.rec.end());
  }
}

void System::SparseHistory::restore(HistoryArray& h) const {
  const size_t st = h.stride;
  std::fill(h.data.begin(), h.data.end(), std::byte{0});
  std::fill(h.live.begin(), h.live.end(), uint8_t(0));
  for (size_t q = 0; q < k.size(); ++q) {
    if (st > 0) std::memcpy(h.data.data() + size_t(k[q]) * st, rec.data() + q * st, st);
    h.live[k[q]] = live[q];
  }
}

void System::take_snapshot() {
  // On the force loop's threads (a snapshot at 10^6 particles copies 72 MB and scans the
  // history's records, 10-25 ms on one thread, while the other threads wait): the same copy.
  const size_t n = particles.size();
  const int nt = long(n) > cfg.parallel_min ? omp_get_max_threads() : 1;
  snap_.x.resize(n);
  snap_.v.resize(n);
  snap_.omega.resize(n);
  auto copy = [&](const size_t lo, const size_t hi) {
    if (hi <= lo) return;
    std::memcpy(snap_.x.data() + lo, particles.x.data() + lo, (hi - lo) * sizeof(Vec3));
    std::memcpy(snap_.v.data() + lo, particles.v.data() + lo, (hi - lo) * sizeof(Vec3));
    std::memcpy(snap_.omega.data() + lo, particles.omega.data() + lo, (hi - lo) * sizeof(Vec3));
  };
  if (nt > 1) {
#pragma omp parallel num_threads(nt)
    {
      const size_t t = size_t(omp_get_thread_num()), m = size_t(omp_get_num_threads());
      copy(n * t / m, n * (t + 1) / m);
    }
  } else {
    copy(0, n);
  }
  snap_.hist.take(nl.hist, nt);
  snap_.whist.take(nl.whist, long(nl.whist.live.size()) > cfg.parallel_min ? nt : 1);
  snap_.time = time;
  snap_.step = step;
  snap_.builds = nl.epoch;
  snap_.dt = cfg.dt;
  snap_.gravity = cfg.gravity;
  snap_.swept = 0;
  snap_.valid = true;
  ++pair_stats_.snapshots;
}

void System::Trend::note(const double m_now, const uint64_t step_now, const uint64_t builds_now) {
  if (builds_now != builds) {
    *this = Trend{};
    builds = builds_now;
  } else if (step_now > step) {
    rate_before = rate;
    rate = std::max(0.0, (m_now - m) / double(step_now - step));
  }
  m = m_now;
  step = step_now;
}

double System::Trend::growth() const { return rate < 0 || rate_before < 0 ? -1.0 : std::max(rate, rate_before); }

bool System::contacts_dense() {
  // Counted again after a list build and every kDenseCheckSteps steps (a pass over the live
  // flags: at 10^6 particles about 0.3 ms, against a step of 30-70 ms).
  if (nl.stats.builds != dense_builds_ || step >= dense_step_ + kDenseCheckSteps) {
    dense_ = double(nl.live_contacts()) > cfg.pair_max_contacts * double(particles.size());
    dense_step_ = step;
    dense_builds_ = nl.stats.builds;
  }
  return dense_;
}

int System::step_sweep(const int k) {
  if (k < 2 || k > 4) throw std::logic_error("System::step_sweep: 2 to 4 steps, not " + std::to_string(k));
  const bool allowed = pairs_allowed();
  if (!allowed || contacts_dense()) {
    pair_stats_.dense_plain += allowed;
    const int K = std::min(k, sweep_steps());
    for (int q = 0; q < K; ++q) step_once(true);
    return K;
  }
  // The lists' epoch: changed by a build, and by a local check that keeps them (the drift's
  // origin moves).
  const uint64_t builds = nl.epoch;
  // The choice of the steps a sweep timed again after SweepTune::kRetuneSteps steps in sweeps.
  if (tune_.best > 0 && pair_stats_.swept_steps - tune_.chosen_at >= tune_.retune_steps) tune_.best = 0;
  const int wanted = std::min(k, sweep_steps());
  int K = wanted;  // the steps of this sweep (fewer near a rebuild: below)
  begin_step();  // the first step's opening is done; the rebuild decision before it
  // Near a rebuild (the displacements since the build past SimConfig::pair_margin of what
  // triggers one): plain steps. A snapshot is taken after every list build and every
  // kSnapSteps steps since, in sweeps or in replayable plain steps (step_once); its cost: a
  // copy of the positions, velocities and spins and of the history's live records, and a
  // read of the rest: 10-18 ms at 10^6 particles, about one step; the first, whose pages
  // are new, 180 ms. Every 64 steps it
  // took 5 % of a two-thread run at 10^6; every 256, a sweep undone takes at most 256 steps
  // again (none was undone in 1000 steps of the 10^6 gas: the margin keeps it rare).
  constexpr uint64_t kSnapSteps = 256;
  // Plain steps too on several threads where a block holds fewer than two spans of rows
  // (PairSlots::chained: a block's tail and head apart; the force loop's set-up makes the
  // same split).
  auto short_blocks = [&] {
    const long n = long(particles.size()), nt = omp_get_max_threads();
    if (n <= cfg.parallel_min || nt < 2) return false;
    slots_.plan(nl, n, nt);
    return !slots_.chained;
  };
  // Past the margin, a sweep only where the measure (NeighborList::rebuild_measure) plus
  // SimConfig::pair_ahead (4) times its growth per step over the last two intervals, for
  // each step the sweep moves the particles before its last step's forces, stays below the
  // trigger (at 10^6 particles on one thread the plain steps near each rebuild were a fifth
  // of the steps). A sweep of more than two steps is taken only where the growth is known
  // and the forecast keeps its last step clear too, and cut short where it does not (below
  // the margin as well, where a pair goes without looking ahead, as it always did): a
  // sweep of four steps with the growth unknown, after each build or each sweep undone, was
  // undone again and again where lists are rebuilt every few steps (the box of
  // tests/physics/test_step_pair.cpp). Close to the trigger (within kClose steps of growth)
  // the snapshot is renewed every kCloseSnapSteps steps, so that a sweep undone there takes
  // few steps again.
  constexpr double kClose = 32;
  constexpr uint64_t kCloseSnapSteps = 16;
  bool forecast = false, close = false, near = false;
  if (nl.epoch == builds) {  // no build (or check) in begin_step: the drift is since the last one
    const double m = nl.rebuild_measure(open_drift_, walls);
    trend_.note(m, step, nl.epoch);
    const double g = trend_.growth();
    // Whether a sweep of q steps is forecast to stay clear of the rebuild.
    auto clear = [&](const int q) { return g >= 0 && m + cfg.pair_ahead * double(q - 1) * g <= cfg.skin; };
    while (K > 2 && !clear(K)) --K;
    if (m > cfg.pair_margin * cfg.skin) {
      forecast = clear(K);
      close = forecast && m + kClose * g > cfg.skin;
      near = !forecast;
    }
  } else {
    K = 2;  // a build (or a check) in begin_step: the growth since it is not known yet
  }
  if (near || short_blocks()) {
    pair_stats_.near_plain += near;
    snap_.valid = false;
    end_step(true);
    for (int q = 1; q < K; ++q) step_once(true);
    return K;
  }
  if (!snap_.valid || snap_.builds != nl.epoch || !snap_.same_config(cfg) || snap_.swept >= kSnapSteps ||
      (close && snap_.swept >= kCloseSnapSteps))
    take_snapshot();
  // All K steps in one sweep of the force loop (ForceContext::drift2, drift_more): `at[q]`
  // gets the displacements since the build of the positions step q + 1 opens with
  // (open_drift_ the second step's, ...; the last, those the step after the sweep opens with).
  const double dt = cfg.dt;
  Drift second, third, fourth;
  Drift* const at[4] = {&open_drift_, &second, &third, &fourth};
  // Timed where the choice of the steps is being made (SweepTune), for a sweep taken whole.
  const bool timed = K == wanted && sweep_timing(wanted);
  const double t0 = timed ? omp_get_wtime() : 0.0;
  compute_forces(0.5 * dt, true, &second, false, K >= 3 ? &third : nullptr, K >= 4 ? &fourth : nullptr);
  const double t_loop = timed ? (omp_get_wtime() - t0) / double(K) : -1.0;
  ++pair_stats_.pairs;
  pair_stats_.forecast += forecast;
  // The positions each of steps 2..K opened with: a step whose lists needed a rebuild undoes
  // the sweep. m: the last of them, for the forecast's trend.
  bool due = false;
  double m = 0;
  for (int q = 0; q + 1 < K; ++q) {
    m = nl.rebuild_measure(*at[q], walls);
    due = due || m > cfg.skin;  // rebuild_due
  }
  if (due) {
    // The lists needed a rebuild between two steps of the sweep: back to the snapshot, and
    // the steps since it again one at a time (the same arithmetic: the same states, the
    // rebuild where plain steps take it).
    ++pair_stats_.replays;
    const uint64_t target = step + uint64_t(K - 1);
    particles.x = snap_.x;
    particles.v = snap_.v;
    particles.omega = snap_.omega;
    snap_.hist.restore(nl.hist);
    snap_.whist.restore(nl.whist);
    slots_.refill = true;  // the pairs in contact are the snapshot's: no slot is known to hold kNoPair
    time = snap_.time;
    step = snap_.step;
    pair_stats_.replayed_steps += target - step;
    end_step(true);
    while (step < target) {
      begin_step();
      end_step(true);
    }
    snap_.valid = false;
    trend_ = Trend{};
    return K;
  }
  trend_.note(m, step + uint64_t(K - 1), nl.epoch);
  if (timed) note_sweep_time(K, t_loop);
  snap_.swept += uint64_t(K);
  pair_stats_.swept_steps += uint64_t(K);
  // What plain steps do between and after the force loops, for walls that stay where they
  // are (their loads are the last step's: the wall entries' results were overwritten).
  for (int q = 1; q < K; ++q) {
    control_walls(dt);
    move_wall_geometry(dt);
    time += dt;
    ++step;
  }
  control_walls(dt);
  open_drift_ = *at[K - 1];
  opened_ = true;
  return K;
}

void System::run(uint64_t nsteps, const std::function<void(const System&)>& after_step) {
  for (uint64_t s = 0; s < nsteps; ++s) {
    step_once();
    if (after_step) after_step(*this);
  }
}

double System::kinetic_energy() const {
  // Summed in blocks of kEnergyBlock particles, the blocks on the threads and their sums in
  // order: the same bits on any number of threads (one block, up to kEnergyBlock particles:
  // the plain sum). Every series row asks for it: at 10^6 particles a few ms on one thread.
  constexpr size_t kEnergyBlock = 8192;
  const size_t n = particles.size(), nb = (n + kEnergyBlock - 1) / kEnergyBlock;
  auto block = [&](const size_t b) {
    double e = 0;
    for (size_t i = b * kEnergyBlock, end = std::min(n, (b + 1) * kEnergyBlock); i < end; ++i) {
      if (particles.flag[i] != kFree) continue;
      e += 0.5 * particles.mass[i] * norm2(particles.v[i]) + 0.5 * particles.inertia[i] * norm2(particles.omega[i]);
    }
    return e;
  };
  if (nb <= 1) return nb == 1 ? block(0) : 0.0;
  std::vector<double> part(nb);
  // Below parallel_min without entering an OpenMP region, as check_finite and live_contacts.
  if (long(n) > cfg.parallel_min) {
#pragma omp parallel for schedule(static)
    for (long b = 0; b < long(nb); ++b) part[size_t(b)] = block(size_t(b));
  } else {
    for (size_t b = 0; b < nb; ++b) part[b] = block(b);
  }
  double e = 0;
  for (const double x : part) e += x;
  return e;
}

double System::rotational_energy() const {
  double e = 0;
  for (size_t i = 0; i < particles.size(); ++i)
    if (particles.flag[i] == kFree) e += 0.5 * particles.inertia[i] * norm2(particles.omega[i]);
  return e;
}

Vec3 System::momentum() const {
  Vec3 m;
  for (size_t i = 0; i < particles.size(); ++i)
    if (particles.flag[i] == kFree) m += particles.v[i] * particles.mass[i];
  return m;
}

size_t System::pair_contact_count() const {
  size_t c = 0;
  for (uint8_t l : nl.hist.live) c += l;
  return c;
}

size_t System::contact_count() const { return nl.live_contacts(); }

double System::max_relative_overlap() const {
  double m = 0;
  for (size_t i = 0; i + 1 < nl.start.size(); ++i)
    for (uint32_t k = nl.start[i]; k < nl.start[i + 1]; ++k) {
      if (!nl.hist.live[k]) continue;
      const uint32_t j = nl.jdx[k];
      const double d = particles.radius[i] + particles.radius[j] -
                       norm(particles.x[i] - particles.x[j] - nl.shift[nl.image[k]]);
      m = std::max(m, d / std::min(particles.radius[i], particles.radius[j]));
    }
  return m;
}

}  // namespace cohdem
