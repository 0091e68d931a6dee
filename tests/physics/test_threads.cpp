// The force loop is written so that results do not depend on the number of OpenMP threads
// (per-pair buffers, then per-particle sums in list order; see sim/force_kernel.hpp). Check
// it: the same run on 1 and 2 threads must give bit-identical particle states.
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

State run(int threads) {
  const double L = 0.04;
  auto s = make_system({{"glass", 2500, 5e7, 0.25}}, "hertz_mindlin", "epsd",
                       params({{"e", 0.5}, {"mu", 0.5}, {"mu_r", 0.1}, {"eta_r", 0.3}}), 5e-6, {0, 0, -9.81}, 2e-4);
  s->cfg.threads = threads;
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
