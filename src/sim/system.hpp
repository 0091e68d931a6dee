// The simulation state and its time loop (velocity Verlet, Allen & Tildesley 1987 Eq. 3.19,
// for translation and rotation of spheres).
#pragma once
#include <cstdint>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/rng.hpp"
#include "models/registry.hpp"
#include "neighbor/neighbor_list.hpp"
#include "particles/insertion.hpp"
#include "particles/particle_store.hpp"
#include "sim/force_context.hpp"
#include "walls/wall.hpp"

namespace cohdem {

/// A material: particle species have a density; wall materials may leave it 0.
struct Material {
  std::string name;
  double density = 0;  ///< kg/m^3
  double E = 0;        ///< Young's modulus, Pa (0: not given; Hertz-type models need it)
  double nu = 0;       ///< Poisson ratio
  // Thermal properties (thermal/thermal.hpp; used only when the case has [thermal]).
  double conductivity = 0;    ///< thermal conductivity k_s, W/(m K) (0: does not conduct)
  double heat_capacity = 0;   ///< specific heat c, J/(kg K)
  double expansion = 0;       ///< linear thermal expansion coefficient alpha, 1/K
  double T_ref = 0;           ///< temperature at which radii are as given, K (0: initial temperature)
  double E_conduction = 0;    ///< Young's modulus for the Hertz spot radius in conduction, Pa (0: E)
};

struct SimConfig {
  double dt = 0;            ///< s
  Vec3 gravity{0, 0, -9.81};///< m/s^2
  double skin = 0;          ///< Verlet skin, m (0: 0.2 x the largest radius, set by prepare())
  Domain domain;
  int sort_every = 20;      ///< re-sort particles by cell every N neighbor builds (0: never)
  /// Where the rebuild trigger fires, a local check first (NeighborList::recheck) over
  /// blocks of this many interaction cutoffs: a sheared flow keeps its lists while
  /// neighbours move alike (0: off, the global trigger alone; case file `[simulation]
  /// local_rebuild`).
  double local_rebuild = 2;
  int threads = 0;          ///< OpenMP threads (0: OpenMP default)
  /// Below this many particles a step runs on one thread: the OpenMP fork/join cost outweighs
  /// the work (results do not depend on the thread count either way).
  long parallel_min = 4000;
  double initial_temperature = 293.15;  ///< K, given to every new particle
  /// Record each pair contact's force and each contact's radius in the force pass, for
  /// pair_force() and the contact radii (set when the contact network is written or bed
  /// stresses are measured; always on with a thermal model). Off, the one-thread force loop
  /// writes no per-pair results at all (less memory traffic).
  bool record_contacts = false;
  /// From this many particles per thread up, System::step_sweep evaluates two steps or more in one
  /// sweep of the force loop where it may (walls at rest, no pours, thermal model or
  /// recording; on several threads, blocks of at least two planes' rows,
  /// PairSlots::chained); below, and when negative, it takes them one at a time (case file:
  /// `[simulation] pair_min`, and `pair_steps = false` for negative). The environment
  /// variable COHDEM_PAIR=0 turns it off too (for comparisons). Results are the same bits.
  long pair_min = 65536;
  /// At most this many steps (2 to 4) in one sweep where the force loop runs on one thread
  /// and the particles number sweep_min or more (System::step_sweep; otherwise two: on
  /// several threads the blocks' hand-offs follow two cursors). Each further step's cursor
  /// follows the one before a plane of cells behind, on data still in the caches. Whether
  /// that pays depends on the machine's caches as much as on the problem: the gas on one
  /// thread with four steps a sweep against two ran 1.10x at 10^6 particles but 0.955x at
  /// 3 x 10^5 on a Xeon VM with 2 MiB of L2 a core, and 1.07x at 10^6 and 1.12x at 3 x 10^5
  /// on a Zen 5 VM with 1 MiB (docs/performance-history.md, sixty-ninth and seventieth
  /// rounds). So by default (sweep_tune) the run times both and keeps the faster
  /// (System::SweepTune). Case file: `[simulation] sweep_steps`, `sweep_min`, `sweep_tune`;
  /// the environment variable COHDEM_SWEEP (2 to 4) sets the steps at any size, untimed (for
  /// comparisons). Results are the same bits whichever is taken.
  int sweep_steps = 4;
  long sweep_min = 65536;
  bool sweep_tune = true;
  /// Two steps in one sweep only while the live contacts are at most this many a particle
  /// (counted every System::kDenseCheckSteps steps and after each list build): a pair saves
  /// the second step's reads from memory, which is what a dilute problem's step waits for (the
  /// 10^6 gas, 0.1 contacts a particle: 1.15x on one thread), while a packed bed's step is
  /// the contact law's arithmetic (bench/bed.toml, 3 a particle: 0.985x on one thread and
  /// 0.94x on two at 10^6, docs/performance-history.md, sixty-seventh round). Tests raise it.
  double pair_max_contacts = 1.0;
  /// Below this fraction of what triggers a list rebuild (the displacements since the
  /// build, NeighborList::rebuild_measure), step_sweep evaluates sweeps without looking ahead;
  /// above it, only where the measure's growth over the last steps, four times over for each
  /// step the sweep looks ahead, stays below the trigger for its last step (a rebuild falling
  /// between two steps of a sweep undoes the sweep; a snapshot is taken close to the trigger so that few steps are taken
  /// again). 1: pairs up to the rebuild (tests use it to take the way back).
  double pair_margin = 0.75;
  /// Past pair_margin, how many steps of the measure's recent growth the forecast adds
  /// before comparing with the trigger, for each step a sweep looks ahead (a pair's second
  /// step: one; a sweep of four: three): 4 allows the growth
  /// to quadruple from one step to the next. Tests set it below 1 to make forecasts fail
  /// and take the way back.
  double pair_ahead = 4;
  /// Diagnostics: the force loop's blocks, split for omp_get_max_threads() threads as
  /// always, are swept one after another by the calling thread (the last block first, so
  /// that each block's head is handed over before the block before needs it), where a
  /// call ends without the barrier (PairSlots::chained). The same bits as the threads; its
  /// `thread_sweep` then gives the split's own cost with no second core (no lines moving
  /// between caches, no waits; docs/performance-history.md, forty-third round). Two steps in one
  /// sweep are off with it. The environment variable COHDEM_SERIAL_BLOCKS=1 turns it on.
  bool serial_blocks = false;
};

class ThermalModel;  // thermal/thermal.hpp

/// Pouring: inserts `spec.count` particles over time at `rate` particles per second.
struct PourSource {
  InsertSpec spec;
  double rate = 0, t_start = 0, interval = 0;
  uint64_t inserted = 0;
  double next_time = 0;
};

class System {
 public:
  SimConfig cfg;
  std::vector<Material> materials;
  ParticleStore particles;
  std::vector<Wall> walls;
  std::unique_ptr<ContactModel> model;
  NeighborList nl;
  std::vector<PourSource> pours;
  Rng rng{12345};
  double time = 0;
  uint64_t step = 0;
  uint64_t next_id = 0;
  /// Heat conduction and thermal expansion, run after every force pass (null: none).
  std::shared_ptr<ThermalModel> thermal;

  /// Sets the contact model and its per-pair parameters (pair_params[i*n+j], n = materials).
  void set_model(std::unique_ptr<ContactModel> m, const std::vector<ParamSet>& pair_params);
  /// Adds a particle with a fresh id; returns its index.
  size_t add_particle(int species, double r, const Vec3& x, const Vec3& v = {}, const Vec3& w = {});
  /// Inserts particles at random (count or solids fraction); returns how many.
  size_t insert(const InsertSpec& spec);

  /// Deletes the particles with remove[i] != 0 (trimming a bed), keeping the contact history
  /// of the others; lists and forces are rebuilt before the next step (sim/remove_particles.cpp).
  void remove_particles(const std::vector<uint8_t>& remove);

  /// Builds lists and evaluates forces at the current state (call once before stepping,
  /// and after changing particles or walls by hand). The contact springs are not advanced:
  /// no time passes (a new contact's springs stay zero, an old one's keep this instant's).
  void prepare();
  /// After a checkpoint restart: builds the lists (from `ref`, the state of the last build
  /// before the checkpoint, when given; else from the current positions) and installs the
  /// saved contacts without evaluating forces (the checkpoint carries them), so the run
  /// continues bit for bit.
  void resume_prepare(const NeighborList::Reference* ref = nullptr);
  /// One time step (velocity Verlet). open_next: the caller promises that nothing reads or
  /// changes the state before the next step_once, whose opening half-kick and drift the
  /// force loop then applies to each free particle as its force is complete (one pass over
  /// the particles fewer, bit-identical results). The state is then mid-step (mid_step()):
  /// positions a step ahead, velocities half a step; only step_once may follow.
  void step_once(bool open_next = false);
  /// True between a step_once(true) and the next step_once.
  bool mid_step() const { return opened_; }
  /// k steps (2 to 4; sweep_steps() where that is fewer), each as
  /// step_once(true), from a mid-step state (after step_once(true) or step_sweep()), with the
  /// same results bit for bit. Where pairs_allowed(), all of them are evaluated in one sweep
  /// of the force loop (ForceContext::drift2, drift_more): each step's particles are read
  /// about one plane of cells after the step before wrote them, from cache, where a whole
  /// sweep is not (two steps: about 1.15x on a one-thread 10^6-particle gas, 1.04x on two
  /// threads; four on one thread 1.11x over two). If the lists turn out to need a rebuild
  /// between two of the steps, the state goes back to the last snapshot (taken after each
  /// list build and every 256 steps since) and the steps since are taken again one at a
  /// time. A step_once between sweeps (the runner's, after which a series row, a frame or a
  /// checkpoint is written) keeps the snapshot where it can be taken again the same way
  /// (replayable(), before and after it). Near a rebuild (SimConfig::pair_margin) it takes
  /// plain steps unless the displacements' recent growth shows the sweep's last step stays
  /// clear of it.
  /// Returns the steps taken: k, or fewer where sweep_steps() is, or where the forecast cuts
  /// the sweep short near a rebuild (two at least).
  int step_sweep(int k);
  /// step_sweep(2): two steps.
  void step_pair() { step_sweep(2); }
  /// How many steps step_sweep takes in one sweep now, at most: where the force loop runs on
  /// one thread and the particles number SimConfig::sweep_min or more, SimConfig::sweep_steps,
  /// or with sweep_tune the one chosen by timing (SweepTune; while timing, the choice timed
  /// next); COHDEM_SWEEP, where set, at any size on one thread; else 2.
  int sweep_steps() const;
  /// Whether step_sweep can evaluate several steps in one sweep now (SimConfig::pair_min).
  bool pairs_allowed() const;
  /// Whether a plain step taken now from the present state could be taken again from a
  /// snapshot of it with the same result: nothing the snapshot does not hold changes in it
  /// (no thermal model, pours, contact recording or particles carried by walls, no radius
  /// growth tracked, no particles or walls changed since the last prepare, every wall at
  /// rest). pairs_allowed() asks it too.
  bool replayable() const;
  /// Whether the environment variable COHDEM_PAIR=0 switches step_sweep's sweeps off (for
  /// comparisons; the case file's `pair_steps = false` does the same).
  static bool pairs_off_by_env();
  /// SimConfig::sweep_steps from the environment variable COHDEM_SWEEP (2 to 4; 0: not set).
  static int sweep_steps_by_env();
  /// Whether the environment variable COHDEM_SERIAL_BLOCKS=1 asks for SimConfig::serial_blocks.
  static bool serial_blocks_by_env();
  /// Whether the force loop's blocks run one after another (SimConfig::serial_blocks or the
  /// environment).
  bool serial_blocks() const { return cfg.serial_blocks || serial_blocks_by_env(); }
  /// Whether the particle count reaches SimConfig::pair_min per thread (and pairs are on).
  bool pairs_fit_size() const;
  /// step_sweep's counts: sweeps of several steps evaluated (`pairs`, whatever their
  /// steps), the steps in them, of those sweeps the ones undone (a rebuild fell between two
  /// of their steps), and the steps taken again.
  struct PairStats {
    uint64_t pairs = 0, replays = 0, replayed_steps = 0;
    uint64_t swept_steps = 0;
    /// Of the pairs, those evaluated past SimConfig::pair_margin on the forecast; and the
    /// calls that took plain steps there instead.
    uint64_t forecast = 0, near_plain = 0;
    /// Calls that took plain steps because the contacts were dense (SimConfig::pair_max_contacts).
    uint64_t dense_plain = 0;
    /// Snapshots taken (step_sweep's way back).
    uint64_t snapshots = 0;
  };
  const PairStats& pair_stats() const { return pair_stats_; }
  /// How step_sweep chooses between two steps a sweep and SimConfig::sweep_steps where
  /// SimConfig::sweep_tune: it alternates the two, times the force loop of each sweep taken
  /// whole (per step: the steps' other work is the same either way), and after kSamples
  /// of each keeps the one whose median is lower; it times them again after kRetuneSteps
  /// steps taken in sweeps, as the contacts change. Results are the same bits whichever is
  /// taken, so the choice, which follows the machine's timings, changes no result.
  struct SweepTune {
    static constexpr size_t kSamples = 12;
    static constexpr uint64_t kRetuneSteps = 8192;
    uint64_t retune_steps = kRetuneSteps;  ///< (tests shorten it)
    int best = 0;         ///< the steps chosen (0: timing them)
    bool more_next = true;  ///< while timing: the next sweep takes sweep_steps (else two)
    uint64_t chosen_at = 0;  ///< PairStats::swept_steps at the choice
    uint64_t tunings = 0;    ///< choices made
    std::vector<double> two, more;  ///< seconds a step of the sweeps timed, per choice
    double s_two = 0, s_more = 0;   ///< the last choice's medians, seconds a step
  };
  const SweepTune& sweep_tune() const { return tune_; }
  /// A sweep of K steps taken whole while timing (SweepTune), its force loop `seconds` a
  /// step: counted where K is one of the two choices, and the choice made once both have
  /// SweepTune::kSamples. Called by step_sweep (public for tests).
  void note_sweep_time(int K, double seconds);
  /// Whether step_sweep is timing the choices (SweepTune) for a sweep of `wanted` steps.
  bool sweep_timing(int wanted) const;
  /// The timing's record, writable (tests only).
  SweepTune& tune_for_tests() { return tune_; }
  void run(uint64_t nsteps, const std::function<void(const System&)>& after_step = {});

  // Observables.
  double kinetic_energy() const;      ///< translational + rotational of free particles, J
  double rotational_energy() const;
  Vec3 momentum() const;
  size_t contact_count() const;       ///< live particle-particle and particle-wall contacts
  size_t pair_contact_count() const;
  /// Largest overlap relative to the smaller radius among live pair contacts.
  double max_relative_overlap() const;

  /// Contact history to install at the next prepare() (checkpoint restart): keys (id_i, id_j)
  /// of live pair contacts and (particle id, wall index) of live wall contacts, with
  /// state_size() bytes each.
  struct SavedContacts {
    std::vector<std::pair<uint64_t, uint64_t>> pair_keys, wall_keys;
    std::vector<std::byte> pair_data, wall_data;
  };
  /// Calls pair(id_i, id_j, record) for every live pair contact, then wall(particle id, wall
  /// index, record) for every live wall contact, in list order; each record is state_size()
  /// bytes. A checkpoint writes them from here, without a copy.
  template <class PairFn, class WallFn>
  void visit_live_contacts(PairFn&& pair, WallFn&& wall) const {
    for (size_t i = 0; i + 1 < nl.start.size(); ++i)
      for (uint32_t k = nl.start[i]; k < nl.start[i + 1]; ++k)
        if (nl.hist.live[k]) pair(particles.id[i], particles.id[nl.jdx[k]], nl.hist.data.data() + k * nl.hist.stride);
    for (size_t i = 0; i + 1 < nl.wstart.size(); ++i)
      for (uint32_t e = nl.wstart[i]; e < nl.wstart[i + 1]; ++e)
        if (nl.whist.live[e]) wall(particles.id[i], uint64_t(nl.wall[e]), nl.whist.data.data() + e * nl.whist.stride);
  }
  void restore_contacts(SavedContacts c) { pending_ = std::move(c); has_pending_ = true; dirty_ = true; }

  /// Reach (m) of the contact law for neighbor search (adhesive range).
  double reach() const { return reach_; }
  double rebuild_count() const { return double(nl.stats.builds); }

  // Per-contact results of the last force pass, indexed like nl.jdx (pairs) and nl.wall (wall
  // entries); valid where nl.hist.live / nl.whist.live. Forces act on the particle (pair: on i).
  // Recorded only with a thermal model or SimConfig::record_contacts (pair_force throws
  // std::logic_error otherwise: a caller that forgot the switch must not read stale forces).
  /// Force on i of pair entry k (zero when not live).
  Vec3 pair_force(size_t k) const {
    if (!contacts_recorded_) throw std::logic_error("System::pair_force: pair forces were not recorded (SimConfig::record_contacts)");
    return nl.hist.live[k] ? pair_[k].f : Vec3{};
  }
  const std::vector<double>& pair_contact_radii() const { return a_pair_; }
  const std::vector<Vec3>& wall_forces() const { return f_wall_; }
  const std::vector<Vec3>& wall_contact_points() const { return c_wall_; }
  const std::vector<double>& wall_contact_radii() const { return a_wall_; }
  /// The force loop's split over threads (diagnostics and tests: its blocks, the calls that
  /// ended without the barrier).
  const PairSlots& thread_split() const { return slots_; }

 private:
  /// Forces at the current state; kick_h > 0: each free particle's velocities also get the
  /// half-kick F h/m, T h/I once its force is complete (ForceContext::kick_h).
  /// second (with open_next; step_sweep): the next step too, in the same sweep, its
  /// displacements there; third and fourth (one thread): the steps after it.
  /// hold_springs: the contact laws' spring increments get dt = 0 (prepare(): a force
  /// evaluation at an instant whose increment the springs already hold, or at the start).
  void compute_forces(double kick_h = 0, bool open_next = false, Drift* second = nullptr, bool hold_springs = false,
                      Drift* third = nullptr, Drift* fourth = nullptr);
  /// step_once in two halves: the walls' motion, the opening half-kick and drift (unless
  /// the force loop did them), the clock, pours and the rebuild decision; then the force
  /// loop with the closing half-kick (and, open_next, the next opening), the thermal model
  /// and the wall control.
  void begin_step();
  void end_step(bool open_next);
  /// The entries of a contact history that are live or hold a record other than zero bytes
  /// (all others are zero and not live): what step_sweep's snapshot keeps of it.
  struct SparseHistory {
    std::vector<uint32_t> k;
    std::vector<uint8_t> live;
    std::vector<std::byte> rec;
    /// On `threads` threads (each scans a contiguous range of entries into its own part,
    /// the parts then joined in order: the same result on any number).
    void take(const HistoryArray& h, int threads = 1);
    void restore(HistoryArray& h) const;
  };
  /// step_sweep's way back: the moved state and the contact history at a step after the
  /// lists' last build, from which sweeps and replayable plain steps led to the present
  /// (`swept`: their steps).
  struct Snapshot {
    std::vector<Vec3> x, v, omega;
    SparseHistory hist, whist;
    double time = 0;
    uint64_t step = 0, builds = 0, swept = 0;
    bool valid = false;
    /// The time step and gravity the steps since were taken with: an undone sweep takes them
    /// again with the present ones, so a caller's change of either ends the snapshot.
    double dt = 0;
    Vec3 gravity{};
    bool same_config(const SimConfig& c) const { return dt == c.dt && gravity == c.gravity; }
  };
  void take_snapshot();
  Snapshot snap_;
  /// step_sweep's forecast of NeighborList::rebuild_measure: its last value, the step whose
  /// positions it measured, the lists' build it belongs to, and its growth per step over the
  /// last two intervals between measurements (negative: not known yet).
  struct Trend {
    double m = 0, rate = -1, rate_before = -1;
    uint64_t step = 0, builds = ~uint64_t(0);
    void note(double m_now, uint64_t step_now, uint64_t builds_now);
    /// The larger of the two growths (at least 0); negative while one is unknown.
    double growth() const;
  };
  Trend trend_;
  PairStats pair_stats_;
  SweepTune tune_;
  /// sweep_steps() without the timing: 2 on several threads or below sweep_min, else
  /// COHDEM_SWEEP or SimConfig::sweep_steps.
  int untimed_sweep_steps() const;
  /// The larger of the two choices SweepTune times where it applies (SimConfig::sweep_tune,
  /// one thread, sweep_min, no COHDEM_SWEEP, sweep_steps above 2), else 0.
  int timed_choice() const;
  /// step_sweep's count of the live contacts (SimConfig::pair_max_contacts): whether they were
  /// dense, at which step and after which list build it was counted.
  static constexpr uint64_t kDenseCheckSteps = 64;
  bool dense_ = false;
  uint64_t dense_step_ = 0, dense_builds_ = ~uint64_t(0);
  bool contacts_dense();
  /// Moves the walls' geometry by one step (translation, oscillation, servo/lid travel) and
  /// records each wall's translation in wall_dx_; step_once carries attached particles.
  void move_wall_geometry(double dt);
  void control_walls(double dt);
  void do_pours();
  Vec3 initial_velocity(const InsertSpec& spec);
  double reach_ = 0;
  bool dirty_ = true;
  bool opened_ = false;  ///< the last force loop applied this step's opening (step_once(true))
  Drift open_drift_;     ///< the displacements it made, for the rebuild decision
  SavedContacts pending_;
  bool has_pending_ = false;
  bool contacts_recorded_ = false;  ///< the last force pass stored pair forces and contact radii
  void install_pending();
  void prepare_reach();
  std::vector<PairResult> pair_, rev_;
  PairSlots slots_;  ///< compact per-pair results of the multi-thread gather
  std::vector<Vec3> f_wall_, tw_wall_, c_wall_;
  std::vector<Vec3> wall_part_;  ///< per block of particles: force and torque on each wall
  std::vector<Vec3> wall_dx_;    ///< translation of each wall in the current step (move_wall_geometry)
  std::vector<double> a_pair_, a_wall_;  ///< contact radii (conduction, contact network)
};

}  // namespace cohdem
