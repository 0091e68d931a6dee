// The force loop is written so that results do not depend on the number of OpenMP threads
// (per-pair buffers, then per-particle sums in list order; see sim/force_kernel.hpp). Check
// it: the same run on 1, 2 and 3 threads must give bit-identical particle states, whether
// or not the per-pair results are recorded (the kernel scatters the reverse sums of a
// thread's own particles and stores and gathers only those of block-boundary particles,
// unless asked to record all: several code paths, one result).
#include <gtest/gtest.h>
#include <omp.h>

#include "fixture.hpp"

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
};

State run(int threads, bool record = false) {
  const double L = 0.04;
  auto s = make_system({{"glass", 2500, 5e7, 0.25}}, "hertz_mindlin", "epsd",
                       params({{"e", 0.5}, {"mu", 0.5}, {"mu_r", 0.1}, {"eta_r", 0.3}}), 5e-6, {0, 0, -9.81}, 2e-4);
  s->cfg.threads = threads;
  s->cfg.parallel_min = 0;  // run the parallel loops even for these few particles
  s->cfg.record_contacts = record;
  // A box open at the top: floor and four sides.
  s->walls.push_back(plane({0, 0, 0}, {0, 0, 1}, 0));
  s->walls.push_back(plane({0, 0, 0}, {1, 0, 0}, 0));
  s->walls.push_back(plane({L, 0, 0}, {-1, 0, 0}, 0));
  s->walls.push_back(plane({0, 0, 0}, {0, 1, 0}, 0));
  s->walls.push_back(plane({0, L, 0}, {0, -1, 0}, 0));
  InsertSpec spec;
  spec.region.kind = Region::Kind::Box;
  spec.region.lo = {0, 0, 0};
  spec.region.hi = {L, L, 0.018};  // solids fraction ~0.23: frequent multi-contact collisions
  spec.size.kind = SizeDistribution::Kind::Uniform;
  spec.size.rmin = 1.5e-3;
  spec.size.rmax = 2.0e-3;
  spec.count = 300;
  EXPECT_EQ(s->insert(spec), 300u);
  Rng rng(3);
  for (auto& v : s->particles.v) v = {rng.normal(), rng.normal(), rng.normal()};
  s->prepare();
  State st;
  st.threads = omp_get_max_threads();
  size_t contacts = 0;
  s->run(400, [&](const System& sys) { contacts += sys.contact_count(); });
  const auto& P = s->particles;
  st.id = P.id;
  st.x = P.x;
  st.v = P.v;
  st.w = P.omega;
  st.wall_force = s->walls[0].force;
  st.builds = s->nl.stats.builds;
  st.contacts = contacts;
  return st;
}

}  // namespace

TEST(Threads, OneAndTwoThreadsGiveIdenticalStates) {
  const State a = run(1), b = run(2);
  omp_set_num_threads(1);  // what the other tests' fixture uses
  ASSERT_EQ(a.threads, 1);
  ASSERT_EQ(b.threads, 2);
  // The run must exercise contacts (particle and wall, frictional, rolling) and rebuilds
  // (with re-sorting every 20 builds, the default).
  EXPECT_GT(a.contacts, 10000u);
  EXPECT_GT(a.builds, 20u);
  ASSERT_EQ(a.id, b.id);
  size_t differ = 0;
  for (size_t i = 0; i < a.x.size(); ++i)
    differ += !(a.x[i] == b.x[i] && a.v[i] == b.v[i] && a.w[i] == b.w[i]);
  EXPECT_EQ(differ, 0u);
  EXPECT_TRUE(a.wall_force == b.wall_force);
  EXPECT_EQ(a.builds, b.builds);
  std::printf("[info] threads test: %zu contact-steps, %llu builds\n", a.contacts, (unsigned long long)a.builds);
  report("threads 1 vs 2: particles with any differing bit (300, 400 steps)", double(differ), 0.0, 0, "==");
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
