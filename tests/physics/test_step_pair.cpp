// System::step_pair evaluates two time steps in one sweep of the force loop (the second
// step's rows a plane of cells behind the first's: ForceContext::drift2), System::step_sweep
// up to four on one thread (ForceContext::drift_more). Each particle's arithmetic, and its
// order, is that of plain steps, and when the neighbor lists turn out to need a rebuild
// between two of them, the state goes back to a snapshot and the steps since are taken
// again one at a time. So a run of sweeps must end in the same state, bit for bit,
// as the same run of plain steps (step_once(true)): checked here on a box of colliding
// spheres with a small skin, so that rebuilds fall between the two steps of a pair again and
// again (the way back is taken) and also at pair boundaries, with frozen particles, wall
// contacts and three contact laws, on the AVX2 and the scalar paths; and on two and three
// threads, whose blocks are swept in two pieces each.
#include <gtest/gtest.h>
#include <omp.h>

#include "fixture.hpp"
#include "sim/force_kernel.hpp"
#include "sim/screen.hpp"

using namespace cohdem;
using namespace cohdem::testing;

namespace {

struct Law {
  const char* model;
  const char* rolling;
  ParamSet p;
};

std::vector<Law> laws() {
  return {
      {"linear", "none", params({{"kn", 2e4}, {"e", 0.5}, {"mu", 0.5}})},
      {"hertz_mindlin", "epsd", params({{"e", 0.5}, {"mu", 0.5}, {"mu_r", 0.1}, {"eta_r", 0.3}})},
      {"mepa", "epsd",
       params({{"k1", 2e6},
               {"k2", 1e7},
               {"kadh", 1e6},
               {"n", 1.5},
               {"mu", 0.5},
               {"gamma_n", 0.2},
               {"mu_r", 0.1},
               {"eta_r", 0.3}})},
  };
}

// 3000 spheres of 1.5-2 mm in a box open at the top (floor and four sides at rest), with
// random velocities of about 1 m/s and a skin of 0.1 mm: lists rebuilt every few steps, and
// a sweep of about ten batches (sim/screen.hpp, kBatch), so that the second step's cursor
// waits for the first's again and again.
constexpr size_t kCount = 3000;
std::unique_ptr<System> make_box(const Law& law, int threads = 1, bool column = false, double skin = 1e-4) {
  auto s =
      make_system({{"glass", 2500, 5e7, 0.25}}, law.model, law.rolling, law.p, 5e-6, {0, 0, -9.81}, skin);
  // column: a box of the same volume ten times as tall, for several threads: the lists'
  // rows run plane by plane up the box, and a block must hold two planes' rows
  // (PairSlots::chained) for pairs.
  const double L = column ? 0.04 : 0.04 * std::sqrt(10.0), H = column ? 0.18 : 0.018;
  s->walls.push_back(plane({0, 0, 0}, {0, 0, 1}, 0));
  s->walls.push_back(plane({0, 0, 0}, {1, 0, 0}, 0));
  s->walls.push_back(plane({L, 0, 0}, {-1, 0, 0}, 0));
  s->walls.push_back(plane({0, 0, 0}, {0, 1, 0}, 0));
  s->walls.push_back(plane({0, L, 0}, {0, -1, 0}, 0));
  EXPECT_EQ(s->insert(box_fill({0, 0, 0}, {L, L, H}, 1.5e-3, 2.0e-3, kCount)), kCount);
  Rng rng(7);
  for (auto& v : s->particles.v) v = {rng.normal(), rng.normal(), rng.normal()};
  for (size_t i = 0; i < 5; ++i) {  // frozen in place: they only mark the displacements' box
    s->particles.flag[i] = kFrozen;
    s->particles.v[i] = s->particles.omega[i] = Vec3{};
  }
  s->cfg.pair_min = 0;    // pairs for these few particles too
  s->cfg.sweep_min = 0;   // and sweeps of up to SimConfig::sweep_steps
  s->cfg.sweep_tune = false;  // always (the choice by timing: SweepTuneKeepsTheFasterChoice)
  s->cfg.pair_max_contacts = 1e9;  // and however dense their contacts
  if (threads > 1) {
    s->cfg.threads = threads;
    s->cfg.parallel_min = 0;  // the force loop on `threads` threads for these few particles
  }
  s->prepare();
  return s;
}

struct End {
  std::vector<uint64_t> id;
  std::vector<Vec3> x, v, w;
  Vec3 floor;
  uint64_t builds = 0, step = 0;
  double time = 0;
  size_t contacts = 0;
  System::PairStats pairs;
};

// `steps` steps (sweeps near a rebuild only below `margin`, SimConfig::pair_margin): plain
// (step_once(true), the last one closed), or in sweeps of `sweep` steps where it can. With
// `plain_every`, a closed step (step_once(false), as the runner takes before it writes a
// series row) once every that many steps, and an opened one after it, as between sweeps.
End run(const Law& law, bool pairs, int steps, double margin, int threads = 1, bool column = false, int sweep = 2,
        double ahead = 4, double skin = 1e-4, int plain_every = 0) {
  auto s = make_box(law, threads, column, skin);
  s->cfg.pair_margin = margin;
  s->cfg.pair_ahead = ahead;
  int k = 0;
  s->step_once(true);
  ++k;
  int next_plain = plain_every;
  while (k < steps - 1) {
    if (plain_every > 0 && k >= next_plain) {
      s->step_once(false);
      ++k;
      next_plain += plain_every;
    } else if (pairs && s->mid_step() && k + sweep < steps) {
      k += s->step_sweep(sweep);
    } else {
      s->step_once(true);
      ++k;
    }
  }
  s->step_once(false);
  End e;
  e.id = s->particles.id;
  e.x = s->particles.x;
  e.v = s->particles.v;
  e.w = s->particles.omega;
  e.floor = s->walls[0].force;
  e.builds = s->nl.stats.builds;
  e.step = s->step;
  e.time = s->time;
  e.contacts = s->contact_count();
  e.pairs = s->pair_stats();
  return e;
}

size_t differing(const End& a, const End& b) {
  if (a.id != b.id) return a.id.size();
  size_t d = 0;
  for (size_t i = 0; i < a.x.size(); ++i) d += !(a.x[i] == b.x[i] && a.v[i] == b.v[i] && a.w[i] == b.w[i]);
  return d;
}

// Runs check(law, simd, label) for every law, on the AVX2 path (where the CPU has it) and
// on the scalar one.
template <class F>
void each_law_and_path(F&& check) {
  const bool had_avx2 = screen_avx2_enabled();
  for (bool simd : {true, false}) {
    if (simd && !avx2_available()) continue;
    set_screen_avx2(simd);
    for (const Law& law : laws()) check(law, std::string(law.model) + (simd ? " (AVX2)" : " (scalar)"));
  }
  set_screen_avx2(had_avx2);
}

// The same end, bit for bit: step, time, every particle's state, the floor's force, the
// list builds and the contacts.
void expect_same(const End& a, const End& b, const std::string& what) {
  EXPECT_EQ(b.step, a.step) << what;
  EXPECT_EQ(b.time, a.time) << what;
  EXPECT_EQ(differing(a, b), 0u) << what;
  EXPECT_TRUE(a.floor == b.floor) << what;
  EXPECT_EQ(a.builds, b.builds) << what;
  EXPECT_EQ(a.contacts, b.contacts) << what;
}

}  // namespace

TEST(StepPair, PairsEndInTheStateOfPlainStepsBitForBit) {
  omp_set_num_threads(1);
  constexpr int kSteps = 401;
  each_law_and_path([&](const Law& law, const std::string& path) {
    for (double margin : {0.75, 1.0}) {
      const End a = run(law, false, kSteps, margin), b = run(law, true, kSteps, margin);
      const std::string what = path + ", margin " + std::to_string(margin);
      EXPECT_EQ(a.step, uint64_t(kSteps)) << what;
      expect_same(a, b, what);
      EXPECT_GT(a.contacts, 10u) << what;  // spheres in contact with each other and the walls
      EXPECT_GT(a.builds, 20u) << what;    // many rebuilds...
      EXPECT_EQ(a.pairs.pairs, 0u) << what;
      EXPECT_GT(b.pairs.pairs, 20u) << what;  // ...pairs in one sweep...
      if (margin == 1.0) {
        EXPECT_GT(b.pairs.replays, 0u) << what;  // ...some undone and taken again
      }
      EXPECT_LT(b.pairs.replays, b.pairs.pairs) << what;
      std::printf("[info] %s: %llu builds, %llu pairs in one sweep (%llu on the forecast past the margin), %llu undone "
                  "(%llu steps taken again)\n",
                  what.c_str(), (unsigned long long)a.builds, (unsigned long long)b.pairs.pairs,
                  (unsigned long long)b.pairs.forecast, (unsigned long long)b.pairs.replays,
                  (unsigned long long)b.pairs.replayed_steps);
    }
  });
}

// Three and four steps in one sweep on one thread (each step's cursor following the one
// before it): the same end as plain steps, bit for bit. With the box's skin of 0.1 mm its
// lists are rebuilt every few steps, too often for the growth of the displacements to be
// known before the next build, and sweeps stay pairs (step_sweep); with 0.4 mm they last
// some tens of steps, and sweeps of three and four steps run: with the default forecast
// (margin 0.75, four times the growth for each step ahead), and with one that lets every
// sweep start (margin 1, pair_ahead -1), whose sweeps across a rebuild are undone and
// taken again (the way back).
TEST(StepPair, SweepsOfThreeAndFourStepsEndInTheStateOfPlainSteps) {
  omp_set_num_threads(1);
  constexpr int kSteps = 401;
  constexpr double kSkin = 4e-4;
  each_law_and_path([&](const Law& law, const std::string& path) {
    const End a = run(law, false, kSteps, 1.0, 1, false, 2, 4, kSkin);
    EXPECT_GT(a.builds, 5u) << path;
    for (int sweep : {3, 4}) {
      for (double margin : {0.75, 1.0}) {
        const End b = run(law, true, kSteps, margin, 1, false, sweep, margin == 1.0 ? -1.0 : 4.0, kSkin);
        const std::string what = path + ", " + std::to_string(sweep) + " steps a sweep, margin " + std::to_string(margin);
        expect_same(a, b, what);
        EXPECT_GT(b.pairs.pairs, 10u) << what;
        // Sweeps cut short near a rebuild take two steps at least; some take all of theirs.
        const uint64_t kept = b.pairs.pairs - b.pairs.replays;
        EXPECT_GE(b.pairs.swept_steps, 2 * kept) << what;
        EXPECT_LE(b.pairs.swept_steps, uint64_t(sweep) * kept) << what;
        EXPECT_GT(b.pairs.swept_steps, 2 * kept) << what;
        if (margin == 1.0) {
          EXPECT_GT(b.pairs.replays, 0u) << what;
        }
        std::printf("[info] %s: %llu sweeps, %llu steps in those kept, %llu undone (%llu steps taken again)\n",
                    what.c_str(), (unsigned long long)b.pairs.pairs, (unsigned long long)b.pairs.swept_steps,
                    (unsigned long long)b.pairs.replays, (unsigned long long)b.pairs.replayed_steps);
      }
    }
  });
}

// The runner's plain steps between sweeps (a series row written after them): the snapshot
// an undone sweep goes back to outlasts them where they can be taken again from it
// (System::replayable), and the undoing takes them again with the sweep's steps. The box
// with a skin of 0.4 mm, a closed plain step every 6 steps, sweeps of four with every one
// let start (margin 1, pair_ahead -1): many undone across such steps. The same end as plain
// steps, bit for bit, with fewer snapshots than closed steps (each closed step took a new
// one before).
TEST(StepPair, PlainStepsBetweenSweepsKeepTheSnapshot) {
  omp_set_num_threads(1);
  constexpr int kSteps = 401, kEvery = 6;
  constexpr double kSkin = 4e-4;
  each_law_and_path([&](const Law& law, const std::string& path) {
    const End a = run(law, false, kSteps, 1.0, 1, false, 2, 4, kSkin, kEvery);
    const End b = run(law, true, kSteps, 1.0, 1, false, 4, -1.0, kSkin, kEvery);
    expect_same(a, b, path);
    EXPECT_GT(b.pairs.pairs, 10u) << path;
    EXPECT_GT(b.pairs.replays, 0u) << path;
    const uint64_t closed = uint64_t(kSteps / kEvery);
    EXPECT_LT(b.pairs.snapshots, closed) << path;
    EXPECT_LE(b.pairs.snapshots, b.builds + 2) << path;  // after each build (and the first), and rarely more
    std::printf("[info] %s: %llu builds, %llu closed plain steps, %llu sweeps, %llu undone (%llu steps taken again), "
                "%llu snapshots\n",
                path.c_str(), (unsigned long long)b.builds, (unsigned long long)closed,
                (unsigned long long)b.pairs.pairs, (unsigned long long)b.pairs.replays,
                (unsigned long long)b.pairs.replayed_steps, (unsigned long long)b.pairs.snapshots);
  });
}

// What the snapshot cannot hold ends it: a plain step with a wall in motion (its position
// is not in the snapshot) makes the next sweep take a new one, and so does gravity changed
// between steps; a plain step with every wall at rest does not. The box with a skin of 1.5
// mm, whose lists outlast these steps.
TEST(StepPair, APlainStepWithAWallInMotionEndsTheSnapshot) {
  omp_set_num_threads(1);
  auto s = make_box(laws()[0], 1, false, 1.5e-3);
  s->cfg.pair_margin = 1.0;
  s->cfg.pair_ahead = 0;
  s->step_once(true);
  s->step_sweep(2);
  const uint64_t builds = s->nl.stats.builds, first = s->pair_stats().snapshots;
  EXPECT_EQ(first, 1u);
  EXPECT_TRUE(s->replayable());
  s->step_once(false);  // at rest: kept
  s->step_once(true);
  s->step_sweep(2);
  EXPECT_EQ(s->pair_stats().snapshots, first);
  s->walls[1].velocity = {1e-3, 0, 0};  // a side wall moving
  EXPECT_FALSE(s->replayable());
  s->step_once(true);
  s->walls[1].velocity = {};
  s->step_once(true);
  s->step_sweep(2);
  EXPECT_EQ(s->pair_stats().snapshots, first + 1);
  // So does a change of gravity (or of the time step) between the steps: taken again from
  // the snapshot, the steps before it would see the new one.
  s->cfg.gravity = {0, 0, -9.0};
  s->step_once(false);
  s->step_once(true);
  s->step_sweep(2);
  EXPECT_EQ(s->pair_stats().snapshots, first + 2);
  s->cfg.gravity = {0, 0, -9.81};  // changed back before a sweep, with no plain step between
  s->step_sweep(2);
  EXPECT_EQ(s->pair_stats().snapshots, first + 3);
  EXPECT_EQ(s->pair_stats().pairs, 5u);
  EXPECT_EQ(s->nl.stats.builds, builds);  // (no build between: the snapshots are the steps')
}

// How many steps a sweep takes: SimConfig::sweep_steps on one thread from sweep_min
// particles on (at most; step_sweep returns the count), two below it and where the force
// loop runs on several threads. The box with a skin of 1.5 mm, whose lists outlast these
// 19 steps, after three pairs (the displacements' growth is then known) and with pair_ahead
// 0 (no sweep cut short on the forecast).
TEST(StepPair, SweepStepsFollowTheConfigurationAndTheThreads) {
  const Law law = laws()[0];
  omp_set_num_threads(1);
  auto s = make_box(law, 1, false, 1.5e-3);
  s->cfg.pair_ahead = 0;
  EXPECT_EQ(s->sweep_steps(), 4);
  s->step_once(true);
  for (int q = 0; q < 3; ++q) s->step_pair();
  const uint64_t builds = s->nl.stats.builds;
  EXPECT_EQ(s->step_sweep(4), 4);
  EXPECT_EQ(s->step_sweep(3), 3);
  s->cfg.sweep_steps = 3;
  EXPECT_EQ(s->sweep_steps(), 3);
  EXPECT_EQ(s->step_sweep(4), 3);
  s->cfg.sweep_steps = 2;
  EXPECT_EQ(s->step_sweep(4), 2);
  EXPECT_EQ(s->step, 19u);
  EXPECT_EQ(s->nl.stats.builds, builds);  // no build fell among these sweeps
  s->cfg.sweep_steps = 4;
  s->cfg.sweep_min = long(kCount) + 1;  // fewer particles than sweep_min: pairs
  EXPECT_EQ(s->sweep_steps(), 2);
  EXPECT_EQ(s->step_sweep(4), 2);
  EXPECT_THROW(s->step_sweep(5), std::logic_error);
  EXPECT_THROW(s->step_sweep(1), std::logic_error);
  auto t = make_box(law, 2, true);  // the force loop on two threads
  EXPECT_EQ(t->sweep_steps(), 2);
  t->step_once(true);
  EXPECT_EQ(t->step_sweep(4), 2);
  omp_set_num_threads(1);
}

// The choice between two steps a sweep and sweep_steps by timing (SimConfig::sweep_tune,
// System::SweepTune), fed timings whose medians are known: while timing, the two choices
// alternate; once both have kSamples, the one with the lower median is kept (whichever it
// is), until kRetuneSteps steps in sweeps later, when they are timed again. A timing of
// another count of steps (a sweep cut short) is not counted, and nothing is timed on
// several threads or with the environment's COHDEM_SWEEP. A real run that times them gives
// the same bits as plain steps (tests/cli/pair_steps.sh, the run `tuned`).
TEST(StepPair, SweepTuneKeepsTheFasterChoice) {
  if (System::sweep_steps_by_env() != 0) GTEST_SKIP() << "COHDEM_SWEEP is set: the steps are fixed, untimed";
  const Law law = laws()[0];
  omp_set_num_threads(1);
  auto s = make_box(law, 1, false, 1.5e-3);
  s->cfg.sweep_tune = true;
  using T = System::SweepTune;
  // Medians 1.0 (four steps) against 1.2 (two): four kept; samples spread around them, the
  // larger choice's with outliers (an interrupted sweep) that a mean would follow.
  auto feed = [&](const double more, const double two) {
    for (size_t q = 0; q < T::kSamples; ++q) {
      EXPECT_EQ(s->sweep_steps(), 4) << "sample " << q;  // alternated: the larger first
      EXPECT_TRUE(s->sweep_timing(4));
      s->note_sweep_time(4, q % 4 == 3 ? 50.0 * more : more * (1.0 + 0.01 * double(q % 3)));
      if (q + 1 < T::kSamples) EXPECT_EQ(s->sweep_steps(), 2);
      s->note_sweep_time(3, 1e-9);  // a sweep cut short: not counted
      s->note_sweep_time(2, two * (1.0 - 0.01 * double(q % 2)));
    }
  };
  EXPECT_EQ(s->sweep_tune().best, 0);
  feed(1.0, 1.2);
  EXPECT_EQ(s->sweep_tune().best, 4);
  EXPECT_EQ(s->sweep_tune().tunings, 1u);
  EXPECT_EQ(s->sweep_steps(), 4);
  EXPECT_FALSE(s->sweep_timing(4));
  EXPECT_DOUBLE_EQ(s->sweep_tune().s_more, 1.02);  // the median of 12, outliers and all
  EXPECT_DOUBLE_EQ(s->sweep_tune().s_two, 1.2);
  // Timed again only after kRetuneSteps steps in sweeps: the box's sweeps (its lists outlast
  // them) keep the choice until then.
  EXPECT_EQ(s->sweep_tune().retune_steps, T::kRetuneSteps);
  s->step_once(true);
  for (int q = 0; q < 3; ++q) s->step_pair();
  EXPECT_EQ(s->sweep_tune().best, 4);
  EXPECT_EQ(s->step_sweep(4), 4);
  // Past retune_steps: timed again (the real sweeps' timings join the fed ones), and this
  // time two steps are faster.
  s->cfg.pair_ahead = 0;
  s->tune_for_tests().retune_steps = 1;  // (kRetuneSteps in runs)
  s->step_sweep(4);
  EXPECT_EQ(s->sweep_tune().best, 0);
  const size_t had = s->sweep_tune().two.size() + s->sweep_tune().more.size();
  EXPECT_LE(had, 1u);  // the sweep just taken, where it was taken whole
  s->tune_for_tests().two.clear();
  s->tune_for_tests().more.clear();
  s->tune_for_tests().more_next = true;
  feed(1.3, 1.1);
  EXPECT_EQ(s->sweep_tune().best, 2);
  EXPECT_EQ(s->sweep_steps(), 2);
  EXPECT_EQ(s->sweep_tune().tunings, 2u);
  // Untimed: sweep_tune off (sweep_steps itself), or the force loop on several threads.
  s->cfg.sweep_tune = false;
  EXPECT_EQ(s->sweep_steps(), 4);
  auto t = make_box(law, 2, true);
  t->cfg.sweep_tune = true;
  EXPECT_FALSE(t->sweep_timing(2));
  EXPECT_EQ(t->sweep_steps(), 2);
  omp_set_num_threads(1);
}

// On several threads each block is swept in two pieces (its tail first for the first step,
// last for the second) and the threads wait for each other's stages (PairSlots::Stage); the
// results must still be those of plain steps on one thread, bit for bit: on two threads, and
// on three (the middle block has both a head and a tail; more threads than this machine may
// have cores, so the waits sleep as well as spin).
TEST(StepPair, PairsOnSeveralThreadsEndInTheStateOfPlainStepsOnOne) {
  constexpr int kSteps = 201;
  each_law_and_path([&](const Law& law, const std::string& path) {
    omp_set_num_threads(1);
    const End a = run(law, false, kSteps, 1.0, 1, true);
    for (int threads : {2, 3}) {
      const End b = run(law, true, kSteps, 1.0, threads, true);
      omp_set_num_threads(1);
      const std::string what = path + ", " + std::to_string(threads) + " threads";
      expect_same(a, b, what);
      EXPECT_GT(b.pairs.pairs, 10u) << what;   // pairs in one sweep on several threads...
      EXPECT_GT(b.pairs.replays, 0u) << what;  // ...some undone (margin 1)
      std::printf("[info] %s: %llu pairs in one sweep, %llu undone\n", what.c_str(),
                  (unsigned long long)b.pairs.pairs, (unsigned long long)b.pairs.replays);
    }
  });
}

// Where two steps cannot share a sweep (a wall that moves, recording, fewer particles than
// SimConfig::pair_min, or than pair_min per thread; several threads whose blocks are shorter
// than two planes of rows),
// step_pair takes two plain steps: the same state, and no pair counted.
TEST(StepPair, FallsBackToPlainStepsWhereASweepCannotHoldTwo) {
  const Law law = laws()[0];
  auto plain = [&](auto&& edit) {
    auto s = make_box(law);
    edit(*s);
    s->prepare();
    s->step_once(true);
    // short blocks: known in step_pair only
    EXPECT_TRUE(s->pairs_allowed() == (s->cfg.threads > 1 && s->cfg.pair_min == 0));
    s->step_pair();
    s->step_pair();
    s->step_once(false);  // six steps
    EXPECT_EQ(s->pair_stats().pairs, 0u);
    return s->particles.x;
  };
  auto reference = [&](auto&& edit) {
    auto s = make_box(law);
    edit(*s);
    s->prepare();
    for (int k = 0; k < 6; ++k) s->step_once(k + 1 < 6);
    return s->particles.x;
  };
  auto moving = [](System& s) { s.walls[0].velocity = {0, 0, 0.01}; };
  auto recording = [](System& s) { s.cfg.record_contacts = true; };
  auto few = [](System& s) { s.cfg.pair_min = long(kCount) + 1; };
  auto threads = [](System& s) {  // the wide box: blocks of 1500 rows, planes of about 900
    s.cfg.threads = 2;
    s.cfg.parallel_min = 0;
  };
  EXPECT_TRUE(plain(moving) == reference(moving)) << "moving";
  EXPECT_TRUE(plain(recording) == reference(recording)) << "recording";
  EXPECT_TRUE(plain(few) == reference(few)) << "few";
  auto per_thread = [](System& s) {  // 3000 particles, 2 threads, 2000 a thread needed
    s.cfg.threads = 2;
    s.cfg.parallel_min = 0;
    s.cfg.pair_min = 2000;
  };
  EXPECT_TRUE(plain(threads) == reference(threads)) << "threads";
  EXPECT_TRUE(plain(per_thread) == reference(per_thread)) << "per thread";
  omp_set_num_threads(1);
}

// The force loop refuses a second step where it cannot run one: with the pairs' results
// recorded, or without the fused opening.
TEST(StepPair, ForceLoopRefusesASecondStepItCannotRun) {
  auto s = make_box(laws()[0]);
  const size_t n = s->particles.size();
  std::vector<PairResult> pair(s->nl.pair_count()), rev(n);
  std::vector<Vec3> fw(s->nl.wall_entry_count()), tw(fw.size()), cw(fw.size());
  Drift d1, d2;
  ForceContext c{s->particles, s->nl, s->walls, s->cfg.dt, s->time, pair, rev, fw, tw, cw, s->cfg.gravity};
  c.kick_h = 0.5 * s->cfg.dt;
  c.open_dt = s->cfg.dt;
  c.drift = &d1;
  c.drift2 = &d2;
  c.keep_pair = true;  // recording
  EXPECT_THROW(s->model->compute(c), std::logic_error);
  c.keep_pair = false;
  c.open_dt = 0;  // no fused opening
  EXPECT_THROW(s->model->compute(c), std::logic_error);
  // A third step without a second, and a third on several threads.
  Drift d3;
  c.open_dt = s->cfg.dt;
  c.drift2 = nullptr;
  c.drift_more[0] = &d3;
  EXPECT_THROW(s->model->compute(c), std::logic_error);
  c.drift2 = &d2;
  c.parallel_min = 0;
  omp_set_num_threads(2);
  EXPECT_THROW(s->model->compute(c), std::logic_error);
  omp_set_num_threads(1);
}

// Near a rebuild, step_pair looks ahead instead of stopping at SimConfig::pair_margin: a
// gas of 1000 spheres that never touch, drifting at constant velocities (no gravity, no
// walls), whose rebuild measure grows exactly linearly. Particles 0 and 1 move at +0.1 and
// -0.1 m/s along x, all others slower (under 0.052 m/s), so the bound on two particles'
// relative displacement is 2 x 0.1 m/s x t (the displacements' box is at least as long in
// x) and the lists of skin 1 mm are due for a rebuild once 0.2 m/s x k dt > 1 mm: after
// k* = 500 steps of 10 us (analytic; the last bit of rounding can move it by one step).
// With the margin alone, every step from 0.75 k* = 375 on would be plain (125 steps); with
// the forecast (the measure plus four steps of its growth below the trigger) only the last
// few are. The states stay those of plain steps, bit for bit, and no pair is undone.
TEST(StepPair, NearARebuildPairsFollowTheDisplacementsForecast) {
  omp_set_num_threads(1);
  auto make = [](const double ahead) {
    auto s = make_system({{"glass", 2500, 5e7, 0.25}}, "linear", "none",
                         params({{"kn", 2e4}, {"e", 0.5}, {"mu", 0.5}}), 1e-5, {0, 0, 0}, 1e-3);
    Rng rng(11);
    for (int a = 0; a < 10; ++a)
      for (int b = 0; b < 10; ++b)
        for (int c = 0; c < 10; ++c) {
          const size_t i = size_t(100 * a + 10 * b + c);
          // 4 mm apart, 2 mm gaps: in 600 steps no particle moves 0.6 mm
          Vec3 v{0.03 * (2 * rng.uniform() - 1), 0.03 * (2 * rng.uniform() - 1), 0.03 * (2 * rng.uniform() - 1)};
          if (i == 0) v = {0.1, 0, 0};
          if (i == 1) v = {-0.1, 0, 0};
          s->add_particle(0, 1e-3, {4e-3 * a, 4e-3 * b, 4e-3 * c}, v);
        }
    s->cfg.pair_min = 0;
    s->cfg.pair_ahead = ahead;
    s->prepare();
    return s;
  };
  constexpr int kSteps = 601;
  // kSteps steps: `lead` plain ones, then pairs, the rest plain (the last one closed); the
  // step after the call in which the lists were first rebuilt.
  auto drive = [](System& s, const int lead) {
    const uint64_t builds0 = s.nl.stats.builds;
    uint64_t first_build_step = 0;
    int k = 0;
    while (k < lead) s.step_once(++k < kSteps);
    while (k + 2 < kSteps) {
      s.step_pair();
      k += 2;
      if (first_build_step == 0 && s.nl.stats.builds > builds0) first_build_step = s.step;
    }
    while (k < kSteps) s.step_once(++k < kSteps);
    return first_build_step;
  };
  auto plain = make(4), paired = make(4);
  for (int k = 0; k < kSteps; ++k) plain->step_once(k + 1 < kSteps);
  const uint64_t builds0 = paired->nl.stats.builds;
  const uint64_t first_build_step = drive(*paired, 1);
  const System::PairStats& st = paired->pair_stats();
  EXPECT_EQ(paired->step, plain->step);
  EXPECT_TRUE(paired->particles.x == plain->particles.x);
  EXPECT_TRUE(paired->particles.v == plain->particles.v);
  EXPECT_EQ(paired->nl.stats.builds, plain->nl.stats.builds);
  EXPECT_EQ(paired->nl.stats.builds, builds0 + 1);  // one rebuild, near step 500
  EXPECT_GE(first_build_step, 499u);
  EXPECT_LE(first_build_step, 503u);  // seen at the end of the pair that crossed it
  EXPECT_EQ(paired->contact_count(), 0u);
  EXPECT_EQ(st.replays, 0u);
  // Past the margin (steps 375-500) the pairs went on: about 62 of them on the forecast,
  // and at most the last two calls (four steps of growth) took plain steps.
  EXPECT_GE(st.forecast, 55u);
  EXPECT_LE(st.near_plain, 3u);
  std::printf("[info] %llu pairs, %llu on the forecast, %llu calls plain near the rebuild (step %llu)\n",
              (unsigned long long)st.pairs, (unsigned long long)st.forecast, (unsigned long long)st.near_plain,
              (unsigned long long)first_build_step);

  // Forecasts that fail: with pair_ahead -1 the forecast lets every pair past the margin
  // start (the measure less a step's growth is always below the trigger), so the pair
  // whose second step's positions cross it is undone and its steps taken again from the
  // snapshot, which close to the trigger (within 32 steps of growth) is renewed every 8
  // pairs: at most 16 steps since it, and the two of the undone pair. Which step crosses
  // (the 501st, or one either side with rounding) and which steps the pairs start on (one
  // plain step first, or two) decide whether a pair straddles it: both starts are run, and
  // one at least must take the way back. The states are still those of plain steps, bit
  // for bit.
  uint64_t undone = 0;
  for (const int lead : {1, 2}) {
    auto failing = make(-1);
    drive(*failing, lead);
    const System::PairStats& sf = failing->pair_stats();
    const std::string what = "lead " + std::to_string(lead);
    EXPECT_TRUE(failing->particles.x == plain->particles.x) << what;
    EXPECT_TRUE(failing->particles.v == plain->particles.v) << what;
    EXPECT_EQ(failing->nl.stats.builds, plain->nl.stats.builds) << what;
    EXPECT_LE(sf.replayed_steps, 18u * sf.replays) << what;
    EXPECT_GE(sf.forecast, 55u) << what;
    undone += sf.replays;
    std::printf("[info] pair_ahead -1, %s: %llu pairs, %llu on the forecast, %llu undone (%llu steps taken again)\n",
                what.c_str(), (unsigned long long)sf.pairs, (unsigned long long)sf.forecast,
                (unsigned long long)sf.replays, (unsigned long long)sf.replayed_steps);
  }
  EXPECT_GE(undone, 1u);
}

// SimConfig::pair_max_contacts: a packed bed's step is the contact law's arithmetic, which a
// pair does not save, so step_pair takes plain steps while the live contacts exceed one a
// particle. A periodic 8 x 8 x 8 lattice of d = 2 mm spheres at a spacing of 0.999 d holds 3
// contacts a particle by construction (each sphere presses on its six neighbours, and the
// small velocities keep them there): with the default bound every call takes plain steps
// (counted as dense_plain, no pair); with the bound raised to 4 the same run takes pairs, and
// both end in the same state, bit for bit (pairs change when, not what).
TEST(StepPair, DenseContactsTakePlainSteps) {
  auto make = [](double max_contacts) {
    auto s = make_system({{"glass", 2500, 0, 0}}, "linear", "none", params({{"kn", 2e4}, {"e", 0.5}, {"mu", 0.5}}),
                         5e-6, {0, 0, 0}, 2e-4);
    fill_periodic_lattice(*s, 8, 8, 1e-3, 1e-3, 9);
    s->cfg.pair_min = 0;
    s->cfg.pair_max_contacts = max_contacts;
    s->prepare();
    for (int k = 0; k < 100; ++k) s->step_pair();
    s->step_once(false);
    return s;
  };
  auto dense = make(1.0), raised = make(4.0);
  const size_t n = dense->particles.size();
  EXPECT_EQ(dense->pair_contact_count(), 3 * n);
  EXPECT_EQ(dense->pair_stats().pairs, 0u);
  EXPECT_GE(dense->pair_stats().dense_plain, 99u);  // (not the first call: no step opened yet, pairs_allowed)
  EXPECT_GE(raised->pair_stats().pairs, 90u);  // (the first pairs wait for a snapshot and the forecast)
  EXPECT_EQ(raised->pair_stats().dense_plain, 0u);
  EXPECT_EQ(raised->pair_contact_count(), 3 * n);
  EXPECT_TRUE(dense->particles.x == raised->particles.x);
  EXPECT_TRUE(dense->particles.v == raised->particles.v);
  EXPECT_TRUE(dense->particles.omega == raised->particles.omega);
  EXPECT_EQ(dense->step, 201u);
}
