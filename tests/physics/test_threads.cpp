// The force loop is written so that results do not depend on the number of OpenMP threads
// (per-pair buffers, then per-particle sums in list order; see sim/force_kernel.hpp). Check
// it: the same run on 1, 2 and 3 threads must give bit-identical particle states, whether
// or not the per-pair results are recorded (the kernel scatters the reverse sums of a
// thread's own particles and stores and gathers only those of block-boundary particles,
// unless asked to record all: several code paths, one result).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <functional>
#include <omp.h>

#include "fixture.hpp"
#include "io/checkpoint.hpp"
#include "sim/force_kernel.hpp"
#include "sim/screen.hpp"

using namespace cohdem;
using namespace cohdem::testing;

namespace {

struct State {
  std::vector<uint64_t> id;
  std::vector<Vec3> x, v, w;
  Vec3 wall_force;
  uint64_t builds = 0;
  size_t contacts = 0;
  int threads = 0;
  uint64_t chained_calls = 0;  ///< force calls that ended without the barrier
  uint64_t serial = 0;         ///< force calls whose blocks ran one after another (SimConfig::serial_blocks)
  uint64_t timed_calls = 0;    ///< force calls on several threads (PairSlots' totals)
  std::vector<double> busy;    ///< per thread, seconds of its sweeps
  std::vector<uint64_t> handed;  ///< per thread, particles it handed to the thread before
  std::vector<double> head;      ///< per thread, seconds of its sweeps finishing the next block's head
  double longest = 0, balanced = 0;  ///< summed over the calls: the longest sweep, the balanced one
};

// 300 spheres in a box open at the top (Hertz-Mindlin with EPSD rolling), prepared to run:
// of glass alone, or of species `sp` among the materials `mats`, with walls of material `wm`;
// L x L wide, filled to height H.
std::unique_ptr<System> make_box(int threads, bool record, std::vector<Material> mats = {{"glass", 2500, 5e7, 0.25}},
                                 int sp = 0, int wm = 0, double L = 0.04, double H = 0.018) {
  auto s = make_system(std::move(mats), "hertz_mindlin", "epsd",
                       params({{"e", 0.5}, {"mu", 0.5}, {"mu_r", 0.1}, {"eta_r", 0.3}}), 5e-6, {0, 0, -9.81}, 2e-4);
  s->cfg.threads = threads;
  s->cfg.parallel_min = 0;  // run the parallel loops even for these few particles
  s->cfg.record_contacts = record;
  // A box open at the top: floor and four sides.
  s->walls.push_back(plane({0, 0, 0}, {0, 0, 1}, wm));
  s->walls.push_back(plane({0, 0, 0}, {1, 0, 0}, wm));
  s->walls.push_back(plane({L, 0, 0}, {-1, 0, 0}, wm));
  s->walls.push_back(plane({0, 0, 0}, {0, 1, 0}, wm));
  s->walls.push_back(plane({0, L, 0}, {0, -1, 0}, wm));
  InsertSpec spec;
  spec.region.kind = Region::Kind::Box;
  spec.region.lo = {0, 0, 0};
  spec.region.hi = {L, L, H};  // solids fraction ~0.23 (L, H as given): frequent multi-contact collisions
  spec.size.kind = SizeDistribution::Kind::Uniform;
  spec.size.rmin = 1.5e-3;
  spec.size.rmax = 2.0e-3;
  spec.count = 300;
  spec.species = sp;
  EXPECT_EQ(s->insert(spec), 300u);
  Rng rng(3);
  for (auto& v : s->particles.v) v = {rng.normal(), rng.normal(), rng.normal()};
  s->prepare();
  return s;
}

// The particles, the floor's force and the build count of a system after its run.
State state_of(const System& s) {
  State st;
  st.threads = omp_get_max_threads();
  const auto& P = s.particles;
  st.id = P.id;
  st.x = P.x;
  st.v = P.v;
  st.w = P.omega;
  st.wall_force = s.walls[0].force;
  st.builds = s.nl.stats.builds;
  return st;
}

// 400 steps of make_box's box, or of a column of the same solids fraction (column: its force
// loop on several threads ends without the barrier, PairSlots::chained); serial: the blocks
// swept one after another (SimConfig::serial_blocks) after the first force evaluation.
State run(int threads, bool record = false, bool column = false, bool serial = false) {
  auto s = column ? make_box(threads, record, {{"glass", 2500, 5e7, 0.25}}, 0, 0, 0.016, 0.1125)
                  : make_box(threads, record);
  s->cfg.serial_blocks = serial;
  size_t contacts = 0;
  s->run(400, [&](const System& sys) { contacts += sys.contact_count(); });
  State st = state_of(*s);
  st.contacts = contacts;
  st.chained_calls = s->thread_split().chained_calls;
  st.timed_calls = s->thread_split().timed_calls;
  st.busy = s->thread_split().busy_total;
  st.handed = s->thread_split().handed_total;
  st.head = s->thread_split().head_total;
  st.serial = s->thread_split().serial_calls;
  st.longest = s->thread_split().longest_total;
  st.balanced = s->thread_split().balanced_total;
  return st;
}

// The contact history of a list, saved so that several force evaluations start from it.
struct SavedHistory {
  std::vector<std::byte> hist, whist;
  std::vector<uint8_t> live, wlive;
  explicit SavedHistory(const NeighborList& nl)
      : hist(nl.hist.data), whist(nl.whist.data), live(nl.hist.live), wlive(nl.whist.live) {}
  void restore(NeighborList& nl) const {
    nl.hist.data = hist; nl.whist.data = whist;
    nl.hist.live = live; nl.whist.live = wlive;
  }
};

// One force evaluation of s's force loop without recording, with the compact per-pair
// buffers of `ps` (null: per-entry buffers) and the closing half-kick kick_h (0: none).
void force_call(System& s, PairSlots* ps, double kick_h) {
  const size_t n = s.particles.size();
  std::vector<PairResult> pair(s.nl.pair_count()), rev(n);
  std::vector<Vec3> fw(s.nl.wall_entry_count()), tw(fw.size()), cw(fw.size());
  ForceContext c{s.particles, s.nl, s.walls, s.cfg.dt, s.time, pair, rev, fw, tw, cw, s.cfg.gravity};
  c.keep_pair = false;
  c.slots = ps;
  c.kick_h = kick_h;
  if (ps != nullptr) ps->refill = true;  // a new buffer, and callers restore the history between calls
  s.model->compute(c);
}

// Checks that two runs of make_box's problem ended in the same state, bit for bit; returns
// the number of particles with any differing bit. The runs must exercise contacts (particle
// and wall, frictional, rolling) and rebuilds (with re-sorting every 20 builds, the default).
size_t expect_identical(const State& a, const State& b) {
  EXPECT_GT(a.contacts, 10000u);
  EXPECT_GT(a.builds, 20u);
  EXPECT_EQ(a.id, b.id);
  if (a.id != b.id) return a.id.size();
  size_t differ = 0;
  for (size_t i = 0; i < a.x.size(); ++i)
    differ += !(a.x[i] == b.x[i] && a.v[i] == b.v[i] && a.w[i] == b.w[i]);
  EXPECT_EQ(differ, 0u);
  EXPECT_TRUE(a.wall_force == b.wall_force);
  EXPECT_EQ(a.builds, b.builds);
  return differ;
}

}  // namespace

TEST(Threads, OneAndTwoThreadsGiveIdenticalStates) {
  const State a = run(1), b = run(2);
  omp_set_num_threads(1);  // what the other tests' fixture uses
  ASSERT_EQ(a.threads, 1);
  ASSERT_EQ(b.threads, 2);
  const size_t differ = expect_identical(a, b);
  std::printf("[info] threads test: %zu contact-steps, %llu builds\n", a.contacts, (unsigned long long)a.builds);
  report("threads 1 vs 2: particles with any differing bit (300, 400 steps)", double(differ), 0.0, 0, "==");
}

// The same in a column, where the two threads' force loop ends without the barrier: block 1's
// particles that depend on block 0 are handed to thread 0 (PairSlots::HandOff), which
// finishes them after its own sweep, kicks and drift included.
TEST(Threads, OneAndTwoThreadsGiveIdenticalStatesWithoutTheBarrier) {
  const State a = run(1, false, true), b = run(2, false, true);
  // Recording every pair's result (conduction, contact output): results stored by list
  // entry rather than in compact slots, the same hand-off.
  const State r = run(2, true, true);
  omp_set_num_threads(1);
  ASSERT_EQ(b.threads, 2);
  EXPECT_EQ(a.chained_calls, 0u);
  EXPECT_GT(b.chained_calls, 300u);  // of 400 steps' force calls (a skewed split may take the barrier)
  EXPECT_GT(r.chained_calls, 300u);
  expect_identical(a, b);
  expect_identical(a, r);
  // The totals behind summary.json's thread_sweep: every call on two threads timed (the
  // chained ones among them), both threads' sweeps timed, and only thread 1 hands particles
  // over (to thread 0), fewer a call than the particles.
  EXPECT_EQ(a.timed_calls, 0u);
  EXPECT_GE(b.timed_calls, b.chained_calls);
  EXPECT_LE(b.timed_calls, 401u);  // 400 steps and the first force evaluation
  EXPECT_GE(b.timed_calls, 400u);  // every one of them counted (none lost to the other thread)
  ASSERT_EQ(b.busy.size(), 2u);
  ASSERT_EQ(b.handed.size(), 2u);
  EXPECT_GT(b.busy[0], 0.0);
  EXPECT_GT(b.busy[1], 0.0);
  EXPECT_EQ(b.handed[0], 0u);
  EXPECT_GT(b.handed[1], 0u);
  EXPECT_LT(b.handed[1], b.timed_calls * uint64_t(b.x.size()));
  // Thread 0 finishes block 1's head within its sweep time; thread 1 has no block after it.
  ASSERT_EQ(b.head.size(), 2u);
  EXPECT_GT(b.head[0], 0.0);
  EXPECT_LT(b.head[0], b.busy[0]);
  EXPECT_EQ(b.head[1], 0.0);
  EXPECT_EQ(b.serial, 0u);  // the threads, not the diagnostic (SimConfig::serial_blocks)
  // Call by call the longest sweep is at least each thread's and at most their sum, and the
  // balanced sweep (the call's work over the sum of the threads' rates) is at most the
  // longest, so the totals keep the same order; none are kept on one thread.
  EXPECT_EQ(a.longest, 0.0);
  EXPECT_GE(b.longest, std::max(b.busy[0], b.busy[1]));
  EXPECT_LE(b.longest, b.busy[0] + b.busy[1]);
  EXPECT_GT(b.balanced, 0.0);
  EXPECT_LE(b.balanced, b.longest);
  std::printf("[info] column: longest sweeps %.3f s, balanced %.3f s\n", b.longest, b.balanced);
  std::printf("[info] column: %zu contact-steps, %llu builds, %llu of the two-thread calls chained\n", a.contacts,
              (unsigned long long)a.builds, (unsigned long long)b.chained_calls);
}

// More threads than the development machines have cores: four and six blocks along the
// column (three to five block boundaries, each handing its head to the thread before) must
// end in the one-thread state bit for bit, as two and three do. The benchmarks show the same
// on 4, 8 and 16 threads of a 16-core machine for the gases and the chute
// (docs/performance.md, fifty-eighth round); this is the check CI can run.
TEST(Threads, FourAndSixThreadsGiveIdenticalStates) {
  const State a = run(1, false, true);
  for (const int t : {4, 6}) {
    const State b = run(t, false, true);
    omp_set_num_threads(1);
    ASSERT_EQ(b.threads, t);
    expect_identical(a, b);
    // every block swept, and every block after the first handed its head over
    ASSERT_EQ(b.busy.size(), size_t(t));
    ASSERT_EQ(b.handed.size(), size_t(t));
    for (int k = 0; k < t; ++k) EXPECT_GT(b.busy[size_t(k)], 0.0) << t << " threads, block " << k;
    EXPECT_EQ(b.handed[0], 0u);
    for (int k = 1; k < t; ++k) EXPECT_GT(b.handed[size_t(k)], 0u) << t << " threads, block " << k;
  }
}

// SimConfig::serial_blocks (the diagnostic behind COHDEM_SERIAL_BLOCKS=1): the two threads'
// blocks swept one after another on one thread, the last first, must give the threads' bits
// (the same sums in the same order) and time both blocks, with the hand-off made.
TEST(Threads, BlocksSweptInSeriesGiveTheThreadsStates) {
  const State a = run(1, false, true), b = run(2, false, true, true);
  omp_set_num_threads(1);
  expect_identical(a, b);
  EXPECT_GT(b.chained_calls, 300u);  // of 400 steps' force calls, as with the threads
  // each of them in series but the first evaluation (make_box's prepare(), before the switch)
  EXPECT_EQ(b.serial + 1, b.chained_calls);
  ASSERT_EQ(b.busy.size(), 2u);
  EXPECT_GT(b.busy[0], 0.0);
  EXPECT_GT(b.busy[1], 0.0);
  ASSERT_EQ(b.handed.size(), 2u);
  EXPECT_GT(b.handed[1], 0u);  // block 1's head finished by block 0's pass
  ASSERT_EQ(b.head.size(), 2u);
  EXPECT_GT(b.head[0], 0.0);
}

namespace {
// Runs the box on one and on two threads with `off` and then `on` applied (two screening
// paths), and checks that the four runs end in the same state bit for bit, per thread count.
void expect_screenings_identical(const std::function<void()>& off, const std::function<void()>& on,
                                 const char* what) {
  off();
  const State a = run(1), c = run(2);
  on();
  const State b = run(1), d = run(2);
  omp_set_num_threads(1);
  ASSERT_EQ(a.id, b.id);
  ASSERT_EQ(c.id, d.id);
  EXPECT_GT(a.contacts, 10000u);
  size_t differ = 0;
  for (size_t i = 0; i < a.x.size(); ++i) {
    differ += !(a.x[i] == b.x[i] && a.v[i] == b.v[i] && a.w[i] == b.w[i]);
    differ += !(c.x[i] == d.x[i] && c.v[i] == d.v[i] && c.w[i] == d.w[i]);
  }
  EXPECT_EQ(differ, 0u);
  EXPECT_TRUE(a.wall_force == b.wall_force);
  EXPECT_EQ(a.builds, b.builds);
  report((std::string(what) + ": particles with any differing bit (300, 400 steps, 1 and 2 threads)").c_str(),
         double(differ), 0.0, 0, "==");
}
}  // namespace

// The AVX2 screening (four list entries at a time) and the scalar one pick the same entries
// with the same pair vectors (tests/unit/test_screen.cpp checks them entry by entry): the
// whole run, on one and on two threads, must not see which one ran.
TEST(Threads, ScalarAndAvx2ScreeningGiveIdenticalStates) {
  const bool was = screen_avx2_enabled();  // as the environment set it (COHDEM_SIMD)
  set_screen_avx2(true);
  if (!screen_avx2_enabled()) GTEST_SKIP() << "no AVX2 screening on this CPU or build";
  const bool was512 = screen_avx512_enabled();
  set_screen_avx512(false);  // the AVX2 screening itself, where AVX-512 is there too
  expect_screenings_identical([] { set_screen_avx2(false); }, [] { set_screen_avx2(true); },
                              "scalar vs AVX2 screening");
  set_screen_avx2(was);
  set_screen_avx512(was512);
}

// The AVX-512 screening (eight entries at a time) against the AVX2 one, the same way.
TEST(Threads, Avx2AndAvx512ScreeningGiveIdenticalStates) {
  const bool was2 = screen_avx2_enabled(), was512 = screen_avx512_enabled();
  set_screen_avx2(true);
  set_screen_avx512(true);
  if (screen_avx512_enabled())
    expect_screenings_identical([] { set_screen_avx512(false); }, [] { set_screen_avx512(true); },
                                "AVX2 vs AVX-512 screening");
  set_screen_avx2(was2);
  set_screen_avx512(was512);
  if (!avx512_available()) GTEST_SKIP() << "no AVX-512 screening on this CPU, operating system or build";
}

namespace {
// The box of spheres of one species, `sp`, among the materials `mats` (walls of material
// `wm`): the force loop's one-species path (NeighborList::one_species) reads the pair
// (sp, sp) without any species.
State run_species(std::vector<Material> mats, int sp, int wm, int threads) {
  auto s = make_box(threads, false, std::move(mats), sp, wm);
  EXPECT_EQ(s->nl.one_species, sp);
  size_t contacts = 0;
  s->run(300, [&](const System& sys) { contacts += sys.contact_count(); });
  State st = state_of(*s);
  st.contacts = contacts;
  return st;
}
}  // namespace

// Particles all of one species among several materials take the one-species path, which
// reads the parameters of the pair (s, s) once instead of each pair's species: the run must
// be bit-identical to the same particles with that material alone (where the pair is the
// only one), in the lanes and in the scalar law, on one and two threads; and must differ
// from the other material's run (the path did pick the pair (s, s), not the first one).
TEST(Threads, OneSpeciesAmongSeveralMaterialsReadsItsOwnPair) {
  const Material glass{"glass", 2500, 5e7, 0.25}, steel{"steel", 7800, 2e8, 0.3};
  const bool was = screen_avx2_enabled();
  for (const bool simd : {true, false}) {
    set_screen_avx2(simd);
    for (const int threads : {1, 2}) {
      const State alone = run_species({steel}, 0, 0, threads);
      const State among = run_species({glass, steel}, 1, 1, threads);
      const State other = run_species({glass}, 0, 0, threads);
      EXPECT_GT(alone.contacts, 5000u);
      ASSERT_EQ(alone.id, among.id);
      size_t differ = 0, differ_other = 0;
      for (size_t i = 0; i < alone.x.size(); ++i) {
        differ += !(alone.x[i] == among.x[i] && alone.v[i] == among.v[i] && alone.w[i] == among.w[i]);
        differ_other += !(alone.x[i] == other.x[i] && alone.v[i] == other.v[i]);
      }
      EXPECT_EQ(differ, 0u) << "simd " << simd << ", " << threads << " threads";
      EXPECT_TRUE(alone.wall_force == among.wall_force);
      EXPECT_GT(differ_other, alone.x.size() / 2);
    }
  }
  set_screen_avx2(was);
  omp_set_num_threads(1);
}

TEST(Threads, ThreeThreadsAndRecordedContactsGiveIdenticalStates) {
  const State a = run(1), b = run(3), c = run(2, true), d = run(1, true);
  omp_set_num_threads(1);
  ASSERT_EQ(b.threads, 3);
  for (const State* o : {&b, &c, &d}) {
    ASSERT_EQ(a.id, o->id);
    size_t differ = 0;
    for (size_t i = 0; i < a.x.size(); ++i)
      differ += !(a.x[i] == o->x[i] && a.v[i] == o->v[i] && a.w[i] == o->w[i]);
    EXPECT_EQ(differ, 0u) << o->threads << " threads";
    EXPECT_TRUE(a.wall_force == o->wall_force);
  }
}

// A step applies velocity Verlet's closing half-kick inside the force kernel, to each
// particle as soon as its force is complete (ForceContext::kick_h), instead of in a pass of
// its own. That is exact only if no pair evaluated later reads the particle's velocities.
// Check it against the definition: on the same state (same history), the kernel with the
// kick must give the same forces as without, and velocities equal, bit for bit, to
// v + F h/m and omega + T h/I computed afterwards, on 1, 2 and 3 threads, with and without
// the compact per-pair buffers (PairSlots).
TEST(Threads, ClosingHalfKickInTheKernelEqualsASeparatePass) {
  for (int threads : {1, 2, 3}) {
    for (bool slots : {false, true}) {
      auto s = make_box(threads, false);
      s->run(150);  // a settled, collision-rich state with history
      ParticleStore& P = s->particles;
      const size_t n = P.size();
      const double h = 0.5 * s->cfg.dt;
      const SavedHistory saved(s->nl);
      const std::vector<Vec3> v0 = P.v, w0 = P.omega;
      auto forces = [&](double kick_h) {
        saved.restore(s->nl);
        P.v = v0; P.omega = w0;
        PairSlots ps;
        force_call(*s, slots ? &ps : nullptr, kick_h);
      };
      forces(0);
      const std::vector<Vec3> F = P.force, T = P.torque;
      forces(h);
      EXPECT_EQ(omp_get_max_threads(), threads);
      size_t bad_f = 0, bad_v = 0, moved = 0;
      for (size_t i = 0; i < n; ++i) {
        bad_f += !(P.force[i] == F[i] && P.torque[i] == T[i]);
        const bool fr = P.flag[i] == kFree;
        const Vec3 v = fr ? v0[i] + F[i] * (h / P.mass[i]) : v0[i];
        const Vec3 w = fr ? w0[i] + T[i] * (h / P.inertia[i]) : w0[i];
        bad_v += !(P.v[i] == v && P.omega[i] == w);
        moved += !(P.v[i] == v0[i]);
      }
      EXPECT_EQ(bad_f, 0u) << threads << " threads, slots " << slots;
      EXPECT_EQ(bad_v, 0u) << threads << " threads, slots " << slots;
      EXPECT_EQ(moved, n);  // every particle was kicked (gravity at least)
    }
  }
  omp_set_num_threads(1);
}

// A step may leave the next step's opening half-kick and drift to its force loop, applied
// to each free particle as soon as its force is complete (System::step_once(true),
// ForceContext::open_dt), instead of a pass of its own at the start of the next step. It is
// the same arithmetic in the same order, so the states must agree bit for bit with plain
// steps, on 1, 2 and 3 threads, with frozen particles (which only mark the displacement
// set) and particles attached to a moving wall (which the next step's pass still carries)
// and neighbor rebuilds decided from the displacements the loop reduced. A fused call does
// not store a free particle's force and torque (ForceContext::open_dt); the unfused step
// that ends the run must, so the particles' forces and torques after it agree too.
TEST(Threads, FusedOpeningOfTheNextStepEqualsTheSeparatePass) {
  constexpr int kSteps = 400;
  for (int threads : {1, 2, 3}) {
    std::vector<Vec3> force[2], torque[2];
    size_t free_n = 0, free_loaded = 0;  // of the fused run: free particles, those with a force
    auto run_steps = [&](bool fuse) {
      auto s = make_box(threads, false);
      ParticleStore& P = s->particles;
      for (size_t i = 0; i < 6; ++i) {  // frozen in place
        P.flag[i] = kFrozen;
        P.v[i] = P.omega[i] = Vec3{};
      }
      for (size_t i = 6; i < 10; ++i) {  // glued to the floor, which rises slowly
        P.attach(i, 0);
      }
      s->walls[0].velocity = {0, 0, 0.02};
      s->prepare();
      size_t mid = 0;
      for (int k = 0; k < kSteps; ++k) {
        s->step_once(fuse && k + 1 < kSteps);
        mid += s->mid_step();
      }
      EXPECT_EQ(mid, fuse ? size_t(kSteps - 1) : 0u);
      EXPECT_FALSE(s->mid_step());
      force[fuse] = P.force;
      torque[fuse] = P.torque;
      if (fuse)
        for (size_t i = 0; i < P.size(); ++i)
          if (P.flag[i] == kFree) {
            ++free_n;
            free_loaded += norm(P.force[i]) > 0;  // gravity at least: not an array left unwritten
          }
      return state_of(*s);
    };
    const State a = run_steps(false), b = run_steps(true);
    EXPECT_EQ(omp_get_max_threads(), threads);
    EXPECT_GT(a.builds, 20u);  // rebuilds (and re-sorts) decided from the fused displacements
    ASSERT_EQ(a.id, b.id);
    size_t differ = 0;
    for (size_t i = 0; i < a.x.size(); ++i) differ += !(a.x[i] == b.x[i] && a.v[i] == b.v[i] && a.w[i] == b.w[i]);
    EXPECT_EQ(differ, 0u) << threads << " threads";
    size_t forces_differ = 0;
    for (size_t i = 0; i < a.x.size(); ++i)
      forces_differ += !(force[0][i] == force[1][i] && torque[0][i] == torque[1][i]);
    EXPECT_EQ(forces_differ, 0u) << threads << " threads";
    EXPECT_GT(free_n, 0u);
    EXPECT_EQ(free_loaded, free_n) << threads << " threads";
    EXPECT_TRUE(a.wall_force == b.wall_force) << threads << " threads";
    EXPECT_EQ(a.builds, b.builds) << threads << " threads";
    if (threads == 2)
      report("fused opening vs separate pass, 2 threads: particles with any differing bit", double(differ), 0.0, 0, "==");
  }
  omp_set_num_threads(1);
}

// Between step_once(true) and the next step the state is mid-step (positions a step ahead,
// velocities half a step): what would read or change it must refuse, not save or use a
// state that belongs to no time.
TEST(Threads, MidStepStateRefusesCheckpointsAndEdits) {
  auto s = make_box(1, false);
  s->step_once(true);
  ASSERT_TRUE(s->mid_step());
  EXPECT_THROW(write_checkpoint(std::filesystem::temp_directory_path() / "cohdem_midstep.bin", *s), std::logic_error);
  EXPECT_THROW(s->remove_particles(std::vector<uint8_t>(s->particles.size(), 0)), std::logic_error);
  EXPECT_THROW(s->prepare(), std::logic_error);
  s->step_once();
  EXPECT_FALSE(s->mid_step());
  EXPECT_NO_THROW(s->prepare());
  omp_set_num_threads(1);
}

// Pair forces are kept only on request (SimConfig::record_contacts); reading them otherwise
// is a programming error that must not return stale numbers. Recorded, the force of a
// two-sphere contact starting at rest is the linear spring's kn delta along the normal
// (undamped, e = 1; no tangential motion, so no friction), on one thread and on two.
TEST(Threads, PairForcesAreRecordedOnRequest) {
  for (int threads : {1, 2}) {
    for (bool record : {false, true}) {
      const double kn = 1e4, r = 1e-3, delta = 1e-6;
      auto s = make_system({{"glass", 2500, 0, 0}}, "linear", "none", params({{"kn", kn}, {"e", 1.0}, {"mu", 0.5}}),
                           1e-7, {0, 0, 0});
      s->cfg.threads = threads;
      s->cfg.parallel_min = 0;
      s->cfg.record_contacts = record;
      s->add_particle(0, r, {0.01, 0.01, 0.01}, {}, {});
      s->add_particle(0, r, {0.01 + 2 * r - delta, 0.01, 0.01}, {}, {});
      s->prepare();
      s->run(1);
      size_t live = 0;
      for (size_t i = 0; i < s->particles.size(); ++i)
        for (uint32_t k = s->nl.start[i]; k < s->nl.start[i + 1]; ++k) {
          if (!s->nl.hist.live[k]) continue;
          ++live;
          if (!record) {
            EXPECT_THROW(s->pair_force(k), std::logic_error);
            continue;
          }
          // After one step of 1e-7 s the spheres have moved apart by ~5e-12 m (a = kn delta/m
          // ~ 1e3 m/s^2), 5e-6 of delta: the force is kn delta within 1e-5 relative.
          const Vec3 dx = s->particles.x[i] - s->particles.x[s->nl.jdx[k]];
          const Vec3 f = s->pair_force(k);
          EXPECT_NEAR(std::abs(f.x), kn * delta, 1e-5 * kn * delta) << threads << " threads";
          EXPECT_EQ(f.y, 0.0);
          EXPECT_EQ(f.z, 0.0);
          EXPECT_GT(dot(f, dx), 0.0);  // repulsive: the force on i points away from j
        }
      EXPECT_EQ(live, 1u);
    }
  }
  omp_set_num_threads(1);
}

// The force loop screens and evaluates the list in batches of kBatch entries; a row longer
// than a batch (a large particle among small ones) is split over several, and its sums must
// start from zero once and take every entry once. One sphere of radius 15 mm (the first
// added: the lowest id, so its row holds all its neighbours) in a cubic lattice of spheres of
// radius 1 mm at spacing 1.9 mm (each overlaps its lattice neighbours by 0.1 mm; those
// within 0.05 mm of the large sphere's surface are left out, so every contact carries at
// least 0.5 N), all at rest, linear springs, no gravity: every contact force is kn delta
// along the normal (no damping at rest, no tangential motion), so each particle's force is
// the sum of kn delta n over the spheres it overlaps, computed here pair by pair. Reference
// and kernel differ only in the order of the sums and in the normal's rounding: about 1e-15
// N per term and a few dozen terms of 0.5 to 3 N each; 1e-9 N is far below a missed or
// doubled contact (>= 0.5 N).
TEST(Threads, RowsLongerThanABatchSumEveryEntryOnce) {
  const double kn = 1e4, R = 15e-3, r = 1e-3, a = 1.9e-3;
  for (int threads : {1, 2, 3}) {
    auto s = make_system({{"glass", 2500, 0, 0}}, "linear", "none",
                         params({{"kn", kn}, {"e", 1.0}, {"mu", 0.5}}), 1e-7, {0, 0, 0}, 2e-3);
    s->cfg.threads = threads;
    s->cfg.parallel_min = 0;
    s->add_particle(0, R, {0, 0, 0});
    for (int ix = -10; ix <= 10; ++ix)
      for (int iy = -10; iy <= 10; ++iy)
        for (int iz = -10; iz <= 10; ++iz) {
          const Vec3 q{ix * a, iy * a, iz * a};
          const double gap = norm(q) - (R + r);
          if ((gap >= -0.2e-3 && gap <= -0.05e-3) || (gap >= 0.05e-3 && norm(q) <= R + 4e-3))
            s->add_particle(0, r, q);
        }
    s->prepare();
    const ParticleStore& P = s->particles;
    const size_t n = P.size();
    size_t longest = 0;
    for (size_t i = 0; i < n; ++i) longest = std::max<size_t>(longest, s->nl.start[i + 1] - s->nl.start[i]);
    EXPECT_GT(longest, size_t(kBatch)) << "the test needs a row longer than one batch";
    std::vector<Vec3> ref(n);
    size_t contacts = 0;
    for (size_t i = 0; i < n; ++i)
      for (size_t j = i + 1; j < n; ++j) {
        const Vec3 d = P.x[i] - P.x[j];
        const double dist = norm(d), delta = P.radius[i] + P.radius[j] - dist;
        if (delta <= 0) continue;
        const Vec3 f = d * (kn * delta / dist);
        ref[i] += f;
        ref[j] -= f;
        ++contacts;
      }
    EXPECT_GT(contacts, size_t(kBatch));
    size_t bad = 0;
    double worst = 0;
    for (size_t i = 0; i < n; ++i) {
      const double e = norm(P.force[i] - ref[i]);
      worst = std::max(worst, e);
      bad += !(e <= 1e-9);
    }
    EXPECT_EQ(bad, 0u) << threads << " threads, worst difference " << worst << " N";
  }
  omp_set_num_threads(1);
}

// The force loop's blocks (PairSlots::plan) hold about equal work, not equal counts: with
// each particle's work (PairSlots::work_of: per particle, per list entry, per live contact),
// the split's running sums equal work_of's, each block's work is within one particle's work
// of total/nt (the split is made between particles), and the blocks are contiguous and
// cover every particle once. In the settling box the rows differ
// in length and contacts, so a split into equal counts fails this (checked).
TEST(Threads, BlocksOfTheForceLoopHoldEqualWork) {
  auto s = make_box(1, false);
  s->run(150);
  const NeighborList& nl = s->nl;
  const long n = long(s->particles.size());
  std::vector<uint64_t> w(static_cast<size_t>(n));
  uint64_t total = 0, wmax = 0;
  for (long i = 0; i < n; ++i) {
    w[size_t(i)] = PairSlots::work_of(nl, i);
    total += w[size_t(i)];
    wmax = std::max(wmax, w[size_t(i)]);
  }
  for (long nt : {2L, 3L, 4L}) {
    PairSlots ps;
    ps.plan(nl, n, nt);
    // The split's work sums (counted from the live flags a word at a time) are work_of's.
    ASSERT_EQ(ps.prefix.size(), size_t(n + 1));
    uint64_t sum = 0;
    size_t off = 0;
    for (long i = 0; i < n; ++i) {
      off += ps.prefix[size_t(i)] != sum;
      sum += w[size_t(i)];
    }
    EXPECT_EQ(off, 0u);
    EXPECT_EQ(ps.prefix[size_t(n)], total);
    ASSERT_EQ(ps.bound.size(), size_t(nt + 1));
    EXPECT_EQ(ps.bound.front(), 0);
    EXPECT_EQ(ps.bound.back(), n);
    for (long t = 0; t < nt; ++t) {
      EXPECT_LE(ps.bound[size_t(t)], ps.bound[size_t(t + 1)]);
      uint64_t bw = 0;
      for (long i = ps.bound[size_t(t)]; i < ps.bound[size_t(t + 1)]; ++i) bw += w[size_t(i)];
      const double target = double(total) / double(nt);
      EXPECT_LE(std::abs(double(bw) - target), double(wmax)) << nt << " threads, block " << t;
    }
  }
}

// The slots of the pairs gathered across block boundaries (PairSlots::update): a pair has
// one exactly when its partner j is not local to the piece of its row (as the force loop
// decides, put()); the slots are numbered by partner, so that each particle whose pairs are
// gathered finds them in one run of consecutive slots, in the order of its transposed list
// (the order its sums take), the runs ascending with the particle and covering every slot
// once. For plain calls (the blocks) and two-step calls (the blocks cut at their tails).
TEST(Threads, GatheredPairsOfAParticleTakeOneRunOfSlots) {
  auto s = make_box(1, false);  // flat: wide boundaries between the blocks
  s->run(150);
  const NeighborList& nl = s->nl;
  const long n = long(s->particles.size());
  size_t all_stored = 0, all_runs = 0;
  for (long nt : {2L, 3L}) {
    for (bool tails : {false, true}) {
      PairSlots ps;  // fresh: every entry of the map is set
      ps.update(nl, n, nt, tails);
      std::vector<long> cut{0};  // the pieces, as update() cuts them
      for (long t = 0; t < nt; ++t) {
        if (tails && ps.tail(t) > cut.back()) cut.push_back(ps.tail(t));
        if (ps.bound[size_t(t + 1)] > cut.back()) cut.push_back(ps.bound[size_t(t + 1)]);
      }
      auto piece_of = [&](long i) { return size_t(std::upper_bound(cut.begin(), cut.end(), i) - cut.begin() - 1); };
      size_t stored = 0, wrong = 0;
      for (long i = 0; i < n; ++i) {
        const size_t u = piece_of(i);
        for (uint32_t k = nl.start[size_t(i)]; k < nl.start[size_t(i) + 1]; ++k) {
          const bool gathered = !local_to_block(nl.dep_lo.data(), nl.jdx[k], cut[u], cut[u + 1]);
          stored += gathered;
          wrong += gathered != (ps.of[k] != PairSlots::kNone);
        }
      }
      EXPECT_EQ(wrong, 0u) << nt << " threads, tails " << tails;
      EXPECT_EQ(ps.count, stored) << nt << " threads, tails " << tails;
      all_stored += stored;
      uint32_t next = 0;  // the next slot a run must start at
      size_t runs = 0, broken = 0;
      for (long q = 0; q < n; ++q) {
        const size_t u = piece_of(q);
        if (local_to_block(nl.dep_lo.data(), uint32_t(q), cut[u], cut[u + 1])) continue;
        ++runs;
        for (uint32_t r = nl.rstart[size_t(q)]; r < nl.rstart[size_t(q) + 1]; ++r) broken += ps.of[nl.rpair[r]] != next++;
      }
      all_runs += runs;
      EXPECT_EQ(broken, 0u) << nt << " threads, tails " << tails;
      EXPECT_EQ(next, ps.count) << nt << " threads, tails " << tails;  // every slot in one run
    }
  }
  EXPECT_GT(all_stored, 100u);
  EXPECT_GT(all_runs, 20u);
  std::printf("[info] %zu pairs gathered through %zu runs of slots\n", all_stored, all_runs);
}

// The split follows measured sweep times (PairSlots::rebalance): a thread that took twice
// as long per unit of modelled work gets a smaller share. The first two rebalances (after
// 8 and 16 more calls) move the shares to their aim, the later ones (every kRebalanceCalls
// calls) halfway; between them nothing moves, and shares that already aim where they are
// keep the split.
// The hand-offs of the barrier-free force loop are matched by the call's number: never 0
// (what a fresh record holds), and at the wrap of the 32-bit counter every record is
// cleared, so that a record left from 2^32 calls ago cannot pass for the current call's.
TEST(Threads, HandOffNumbersNeverMatchAStaleRecord) {
  PairSlots ps;
  EXPECT_EQ(ps.next_epoch(2), 1u);
  ASSERT_EQ(ps.hand_n, 2u);
  EXPECT_EQ(ps.hand[1].epoch.load(), 0u);
  ps.hand[1].epoch.store(7);  // handed over in call 7, then the barrier for a long time
  ps.epoch = ~uint32_t(0);
  const uint32_t call = ps.next_epoch(2);
  EXPECT_EQ(call, 1u);
  EXPECT_EQ(ps.hand[1].epoch.load(), 0u);
  for (uint32_t c = 2; c < 8; ++c) EXPECT_EQ(ps.next_epoch(2), c);
  EXPECT_NE(ps.hand[1].epoch.load(), ps.epoch);  // call 7 again: the old record no longer matches
}

TEST(Threads, RebalanceMovesWorkToTheFasterThread) {
  auto s = make_box(1, false);
  s->run(50);
  const long n = long(s->particles.size());
  PairSlots ps;
  ps.plan(s->nl, n, 2);
  ASSERT_EQ(ps.share.size(), 2u);
  // `calls` force calls timed at u0 and u1 seconds per unit of modelled work
  auto feed = [&](const uint32_t calls, const double u0, const double u1) {
    for (uint32_t c = 0; c < calls; ++c) {
      ps.busy = {u0 * double(ps.block_work(0)), u1 * double(ps.block_work(1))};
      ps.swept = {double(ps.block_work(0)), double(ps.block_work(1))};
      ps.rebalance();
    }
  };
  // The first rebalance comes after kFirstRebalanceCalls calls and moves all the way: times
  // per unit 2 : 1 aim at 1/3 : 2/3.
  feed(PairSlots::kFirstRebalanceCalls - 1, 2.0, 1.0);
  EXPECT_FALSE(ps.stale);
  EXPECT_EQ(ps.rebalances, 0u);
  feed(1, 2.0, 1.0);
  EXPECT_TRUE(ps.stale);
  EXPECT_EQ(ps.rebalances, 1u);
  EXPECT_NEAR(ps.share[0], 1.0 / 3.0, 1e-15);
  EXPECT_NEAR(ps.share[1], 2.0 / 3.0, 1e-15);
  const long b_old = ps.bound[1];
  ps.plan(s->nl, n, 2);
  EXPECT_FALSE(ps.stale);
  EXPECT_LT(ps.bound[1], b_old);  // block 0 shrank
  const double total = double(ps.prefix.back());
  EXPECT_NEAR(double(ps.block_work(0)) / total, 1.0 / 3.0, 0.05);  // a split between particles: one holds < 1 % of the work
  // The second, twice as many calls later: times per unit in proportion to 1/share aim
  // where the shares are, and they stay put.
  for (uint32_t c = 0; c < 2 * PairSlots::kFirstRebalanceCalls; ++c) {
    ps.busy = {double(ps.block_work(0)) / ps.share[0], double(ps.block_work(1)) / ps.share[1]};
    ps.swept = {double(ps.block_work(0)), double(ps.block_work(1))};
    ps.rebalance();
  }
  EXPECT_FALSE(ps.stale);
  EXPECT_EQ(ps.rebalances, 1u);
  // From then on every kRebalanceCalls calls, halfway: equal times per unit aim at 1/2 : 1/2,
  // and the shares move from 1/3 : 2/3 to 5/12 : 7/12 (to rounding: a few ulps of the
  // divisions).
  feed(PairSlots::kRebalanceCalls - 1, 1.0, 1.0);
  EXPECT_FALSE(ps.stale);
  feed(1, 1.0, 1.0);
  EXPECT_TRUE(ps.stale);
  EXPECT_EQ(ps.rebalances, 2u);
  EXPECT_NEAR(ps.share[0], 5.0 / 12.0, 1e-15);
  EXPECT_NEAR(ps.share[1], 7.0 / 12.0, 1e-15);
  ps.plan(s->nl, n, 2);
  // a thread held up (1000x slower per unit, for many rebalances) keeps a quarter of an
  // equal share, so its block is never empty and is timed again
  for (int r = 0; r < 40; ++r)
    for (uint32_t c = 0; c < PairSlots::kRebalanceCalls; ++c) {
      ps.busy = {1000.0 * double(ps.block_work(0)), double(ps.block_work(1))};
      ps.swept = {double(ps.block_work(0)), double(ps.block_work(1))};
      ps.rebalance();
      ps.plan(s->nl, long(s->particles.size()), 2);
    }
  EXPECT_NEAR(ps.share[0], PairSlots::kMinShare / 2, 1e-12);
  EXPECT_GT(ps.bound[1], 0);
}

// Whatever the split (equal, skewed either way, changed between calls so that the slot map
// is redone only near the boundaries), the force loop on 2 and 3 threads with the compact
// per-pair buffers gives forces, torques and contact history identical to one thread, bit
// for bit.
TEST(Threads, AnySplitOfTheForceLoopGivesIdenticalResults) {
  // A column (the same solids fraction as make_box's default box): its planes of cells, and
  // so the rows a pair can reach across (PairSlots::span), are a small part of the particles,
  // so that an even split ends without the barrier (blocks of at least 2 span rows) and a
  // skewed one with it.
  auto s = make_box(1, false, {{"glass", 2500, 5e7, 0.25}}, 0, 0, 0.016, 0.1125);
  s->run(150);
  ParticleStore& P = s->particles;
  const size_t n = P.size();
  const SavedHistory saved(s->nl);
  struct Out {
    std::vector<Vec3> f, t;
    std::vector<std::byte> hist;
  };
  auto forces = [&](PairSlots* ps) {
    saved.restore(s->nl);
    force_call(*s, ps, 0);
    return Out{P.force, P.torque, s->nl.hist.data};
  };
  omp_set_num_threads(1);
  const Out ref = forces(nullptr);
  for (int threads : {2, 3}) {
    omp_set_num_threads(threads);
    PairSlots ps;  // kept across calls: later splits remap only near the boundaries
    const std::vector<std::vector<double>> splits =
        threads == 2 ? std::vector<std::vector<double>>{{0.5, 0.5}, {0.15, 0.85}, {0.8, 0.2}, {0.04, 0.96}, {0.45, 0.55}}
                     : std::vector<std::vector<double>>{{1. / 3, 1. / 3, 1. / 3}, {0.1, 0.2, 0.7}, {0.6, 0.3, 0.1}};
    size_t chained = 0, barrier = 0;  // splits that ended without and with the barrier
    for (const auto& sh : splits) {
      if (ps.share.empty()) ps.update(s->nl, long(n), threads);  // sets up the shares' vector
      ps.share = sh;
      ps.stale = true;
      const Out o = forces(&ps);
      EXPECT_EQ(ps.bound.size(), size_t(threads + 1));
      size_t bad = 0;
      for (size_t i = 0; i < n; ++i) bad += !(o.f[i] == ref.f[i] && o.t[i] == ref.t[i]);
      EXPECT_EQ(bad, 0u) << threads << " threads, share[0] " << sh[0];
      EXPECT_TRUE(o.hist == ref.hist) << threads << " threads, share[0] " << sh[0];
      const bool was_chained = ps.chained_calls > chained;
      EXPECT_EQ(was_chained, ps.chained) << threads << " threads, share[0] " << sh[0];
      (was_chained ? chained : barrier) += 1;
      std::printf("[info] %d threads, shares %.2f..: blocks %ld.., span %ld, %s\n", threads, sh[0],
                  ps.bound[1] - ps.bound[0], ps.span, was_chained ? "chained" : "barrier");
    }
    // Both ends of the force loop are exercised: handed over between neighbouring threads
    // (every block at least twice the dependency span) and shared out after the barrier.
    EXPECT_GT(chained, 0u) << threads << " threads";
    EXPECT_GT(barrier, 0u) << threads << " threads";
  }
  omp_set_num_threads(1);
}

// The kinetic energy (every series row, every summary) is summed on the threads in blocks of
// particles whose sums are added in order: the same bits on one, two and three threads, and
// the sum of 1/2 m v^2 + 1/2 I w^2 over the free particles, which a long double sum gives to
// about 1e-18 (the double sum of 30,000 positive terms is within n eps = 7e-12 of it; 1e-12
// asked). Frozen particles do not count.
TEST(Threads, KineticEnergyIsTheSameSumOnAnyThreadCount) {
  auto s = make_system({{"a", 2500, 0, 0}}, "linear", "none", params({{"kn", 1e3}, {"e", 0.5}, {"mu", 0.5}}), 1e-5);
  s->cfg.parallel_min = 0;
  Rng rng(11);
  long double exact = 0;
  for (size_t i = 0; i < 30000; ++i) {
    const double r = rng.uniform(1e-3, 2e-3);
    const Vec3 v{rng.normal(), rng.normal(), rng.normal()}, w{rng.normal() * 50, rng.normal() * 50, rng.normal() * 50};
    const size_t k = s->particles.add(i + 1, 0, r, 2500, Vec3{double(i) * 0.01, 0, 0}, v, w);
    if (i % 7 == 3) {
      s->particles.flag[k] = kFrozen;
      continue;
    }
    const long double m = s->particles.mass[k], I = s->particles.inertia[k];
    exact += 0.5L * m * (static_cast<long double>(v.x) * v.x + static_cast<long double>(v.y) * v.y +
                         static_cast<long double>(v.z) * v.z) +
             0.5L * I * (static_cast<long double>(w.x) * w.x + static_cast<long double>(w.y) * w.y +
                         static_cast<long double>(w.z) * w.z);
  }
  double e[3];
  for (int t = 1; t <= 3; ++t) {
    omp_set_num_threads(t);
    e[t - 1] = s->kinetic_energy();
  }
  omp_set_num_threads(1);
  EXPECT_EQ(std::memcmp(&e[0], &e[1], sizeof(double)), 0) << e[0] << " " << e[1];
  EXPECT_EQ(std::memcmp(&e[0], &e[2], sizeof(double)), 0) << e[0] << " " << e[2];
  EXPECT_NEAR(e[0] / double(exact), 1.0, 1e-12);
}

// The live contacts (every series row and progress line) are counted on the threads where
// the lists are long: the same count as one thread's, the flags counted here, on one, two
// and three threads (a million entries, so that threads that raced on the sum would lose
// some of it).
TEST(Threads, LiveContactsAreCountedOnAnyThreadCount) {
  NeighborList nl;
  nl.parallel_min = 0;
  Rng rng(5);
  nl.hist.live.resize(1000003);
  nl.whist.live.resize(5003);
  size_t expected = 0;
  for (auto* v : {&nl.hist.live, &nl.whist.live})
    for (uint8_t& l : *v) {
      l = rng.uniform() < 0.3 ? 1 : 0;
      expected += l;
    }
  for (int t = 1; t <= 3; ++t) {
    omp_set_num_threads(t);
    for (int repeat = 0; repeat < 5; ++repeat) EXPECT_EQ(nl.live_contacts(), expected) << t << " threads";
  }
  omp_set_num_threads(1);
}

namespace {

// A packed bed periodic in x, y and z (the representative volume of a bed, as in
// bench/bed.toml): nx * nx * nz spheres of d = 1 on a simple cubic lattice of spacing 0.999
// in a box of the lattice's size, each pressing on its six neighbours (overlap 0.001), with
// small random velocities, on `threads` threads.
std::unique_ptr<System> make_periodic_bed(int threads, int nx, int nz, double extra_z = 0) {
  auto s = make_system({{"grain", 1.0, 0, 0}}, "linear", "none",
                       params({{"kn", 2e5}, {"e", 0.9}, {"mu", 0.5}}), 1e-4, {0, 0, 0}, 0.1);
  s->cfg.threads = threads;
  s->cfg.parallel_min = 0;
  fill_periodic_lattice(*s, nx, nz, 0.5, 0.01, 11);
  s->cfg.domain.hi.z += extra_z;  // a gap of extra_z at the seam
  s->prepare();
  return s;
}

}  // namespace

// Periodic in z, the direction the cell order takes last: the bottom plane's pairs reach the
// top plane. The re-sort folds the planes (0, nz - 1, 1, nz - 2, ...: NeighborList::build,
// step 3) so that every pair's partner lies within a few planes of its row in the particle
// order, seam included. Checked on a 10 x 10 x 30 bed (27 planes of cells of 1.11, 100-200
// spheres each): the widest reach of a row (PairSlots::span) is at most three planes' worth
// of spheres (two planes apart at most, plus a row and a cell), where the plain order gives
// nearly all 3000; so two blocks of 1500 each hold two spans and the two threads' force
// loop ends without its barrier (chained) in every call, and the run ends in the one-thread
// state bit for bit, with every sphere in contact with its six neighbours throughout.
TEST(Threads, TriplyPeriodicBedKeepsItsPartnersNearInOrder) {
  const int nx = 10, nz = 30, steps = 50;
  auto one = make_periodic_bed(1, nx, nz);
  auto two = make_periodic_bed(2, nx, nz);
  const size_t n = one->particles.size();
  ASSERT_EQ(n, size_t(nx * nx * nz));
  one->run(steps);
  two->run(steps);
  omp_set_num_threads(1);
  EXPECT_EQ(one->contact_count(), 3 * n);  // by construction: six neighbours each, nothing farther
  // The widest reach of a row in the particle order, from the lists.
  const NeighborList& nl = one->nl;
  long reach = 0;
  for (size_t i = 0; i < n; ++i)
    for (uint32_t k = nl.start[i]; k < nl.start[i + 1]; ++k) reach = std::max(reach, long(nl.jdx[k]) - long(i));
  const long plane_max = 2 * nx * nx;  // a plane of cells holds one or two lattice planes (1.11 / 0.999)
  EXPECT_LE(reach, 3 * plane_max) << "a pair reaches " << reach << " of " << n << " spheres ahead";
  EXPECT_GT(reach, 0);
  // Two threads: chained in every timed call, the same bits as one.
  const PairSlots& ps = two->thread_split();
  EXPECT_LE(ps.span, 3 * plane_max);
  EXPECT_GE(ps.timed_calls, uint64_t(steps));
  EXPECT_EQ(ps.chained_calls, ps.timed_calls);
  const ParticleStore &a = one->particles, &b = two->particles;  // (no walls: not state_of)
  ASSERT_EQ(a.id, b.id);
  size_t differ = 0;
  for (size_t i = 0; i < n; ++i) differ += !(a.x[i] == b.x[i] && a.v[i] == b.v[i] && a.omega[i] == b.omega[i]);
  EXPECT_EQ(differ, 0u);
  EXPECT_EQ(two->contact_count(), 3 * n);
  std::printf("[info] periodic bed: %zu spheres, widest reach %ld, span %ld, %llu of %llu calls chained\n", n, reach,
              ps.span, (unsigned long long)ps.chained_calls, (unsigned long long)ps.timed_calls);
  // Folded, the particles' heights jump along the order between the bottom and the top of
  // the bed (about 29 d); with a gap of 2 d at the seam (more than the cutoff of 1.1 d), where
  // no pair can cross it, the order stays plain: the height falls from one particle to the
  // next only within a plane of cells (less than its 1.1 d).
  auto largest_drop = [](const System& s) {
    double d = 0;
    for (size_t i = 1; i < s.particles.size(); ++i) d = std::max(d, s.particles.x[i - 1].z - s.particles.x[i].z);
    return d;
  };
  EXPECT_GT(largest_drop(*one), 10.0);
  auto gap = make_periodic_bed(1, nx, nz, 2.0);
  EXPECT_LT(largest_drop(*gap), 1.2);
}
