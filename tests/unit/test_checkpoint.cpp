// Checkpoint/restart: a run interrupted after a rebuild step, written to disk and resumed in a
// fresh System, must continue bit for bit like the uninterrupted run (positions, velocities,
// spins and the tangential/rolling history all enter the comparison through the motion).
#include <gtest/gtest.h>

#include <filesystem>

#include "../physics/fixture.hpp"
#include "io/checkpoint.hpp"

using namespace cohdem;
using namespace cohdem::testing;

namespace {
std::unique_ptr<System> setup() {
  auto s = make_system({{"glass", 2500, 1e7, 0.25}}, "hertz_mindlin", "epsd",
                       params({{"e", 0.5}, {"mu", 0.5}, {"mu_r", 0.1}}), 2e-6, {0, 0, -9.81}, 1e-4);
  s->walls.push_back(plane({0, 0, 0}, {0, 0, 1}, 0));
  s->walls.push_back(plane({0, 0, 0}, {1, 0, 0}, 0));
  s->walls.push_back(plane({0.01, 0, 0}, {-1, 0, 0}, 0));
  s->cfg.sort_every = 3;
  return s;
}
}  // namespace

TEST(Checkpoint, RestartIsBitwiseIdentical) {
  auto a = setup();
  InsertSpec spec;
  spec.region.kind = Region::Kind::Box;
  spec.region.lo = {0, -0.005, 0};
  spec.region.hi = {0.01, 0.005, 0.01};
  spec.size.kind = SizeDistribution::Kind::Uniform;
  spec.size.rmin = 4e-4;
  spec.size.rmax = 6e-4;
  spec.count = 250;
  spec.velocity_jitter = 0.05;
  spec.velocity = {0, 0, -0.3};
  a->insert(spec);
  a->prepare();
  a->run(20000);  // particles fall and collide (40 ms)
  // Stop at the end of a step with a rebuild.
  uint64_t builds = a->nl.stats.builds;
  while (a->nl.stats.builds == builds) a->step_once();
  ASSERT_GT(a->pair_contact_count(), 50u);
  const auto path = std::filesystem::temp_directory_path() / "cohdem_test_checkpoint.bin";
  write_checkpoint(path, *a);
  const uint64_t at = a->step;
  a->run(1500);

  auto b = setup();
  read_checkpoint(path, *b);
  EXPECT_EQ(b->step, at);
  b->run(1500);
  std::filesystem::remove(path);

  ASSERT_EQ(a->particles.size(), b->particles.size());
  size_t differ = 0;
  for (size_t i = 0; i < a->particles.size(); ++i)
    differ += !(a->particles.id[i] == b->particles.id[i] && a->particles.x[i] == b->particles.x[i] &&
                a->particles.v[i] == b->particles.v[i] && a->particles.omega[i] == b->particles.omega[i]);
  EXPECT_EQ(differ, 0u) << "particles differing after restart";
  EXPECT_EQ(a->walls[0].force, b->walls[0].force);
}

TEST(Checkpoint, RejectsOtherModelAndTruncation) {
  auto a = setup();
  a->add_particle(0, 5e-4, {0.005, 0, 0.001});
  a->prepare();
  const auto path = std::filesystem::temp_directory_path() / "cohdem_test_checkpoint2.bin";
  write_checkpoint(path, *a);
  auto other = make_system({{"glass", 2500, 1e7, 0.25}}, "linear", "none",
                           params({{"kn", 1e3}, {"e", 0.5}, {"mu", 0.5}}), 2e-6);
  EXPECT_THROW(read_checkpoint(path, *other), InputError);
  std::filesystem::resize_file(path, 100);
  auto b = setup();
  EXPECT_THROW(read_checkpoint(path, *b), InputError);
  std::filesystem::remove(path);
}
