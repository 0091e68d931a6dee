// Checkpoint/restart: a run interrupted at any step (right after a neighbor-list rebuild, or
// between rebuilds, or right after a build that re-sorted the particles), written to disk and
// resumed in a fresh System, must continue bit for bit like the uninterrupted run (positions,
// velocities, spins and the tangential/rolling history all enter the comparison through the
// motion; 1500 steps span several rebuilds).
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

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

enum class StopAt { RebuildStep, BetweenRebuilds, AfterResort };

void restart_is_bitwise(StopAt where) {
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
  uint64_t builds = a->nl.stats.builds;
  switch (where) {
    case StopAt::RebuildStep:  // the end of a step with a rebuild
      while (a->nl.stats.builds == builds) a->step_once();
      break;
    case StopAt::BetweenRebuilds: {  // a step in the middle of a stretch without rebuilds
      while (a->nl.stats.builds == builds) a->step_once();
      builds = a->nl.stats.builds;
      const uint64_t s0 = a->step;
      while (a->nl.stats.builds == builds) a->step_once();
      const uint64_t gap = a->step - s0;
      ASSERT_GE(gap, 4u);
      builds = a->nl.stats.builds;
      for (uint64_t k = 0; k < gap / 2 && a->nl.stats.builds == builds; ++k) a->step_once();
      ASSERT_EQ(a->nl.stats.builds, builds) << "expected to stop between rebuilds";
      a->step_once();  // at least one step after the build
      ASSERT_EQ(a->nl.stats.builds, builds);
      break;
    }
    case StopAt::AfterResort:  // two steps after a build that re-sorted the particles
      while (a->nl.stats.builds % uint64_t(a->cfg.sort_every) != 1 || a->nl.stats.builds == builds) {
        builds = a->nl.stats.builds;
        a->step_once();
      }
      a->step_once();
      a->step_once();
      break;
  }
  ASSERT_GT(a->pair_contact_count(), 50u);
  // One file per test and process: ctest runs these tests side by side.
  const auto path = std::filesystem::temp_directory_path() /
                    ("cohdem_test_checkpoint_" + std::to_string(int(where)) + "_" + std::to_string(::getpid()) + ".bin");
  const std::string app("app\0state", 9);  // opaque bytes, zeros included
  write_checkpoint(path, *a, app);
  const uint64_t at = a->step;
  a->run(1500);

  auto b = setup();
  EXPECT_EQ(read_checkpoint(path, *b), app);
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
  EXPECT_EQ(a->nl.stats.builds, b->nl.stats.builds);
}

}  // namespace

TEST(Checkpoint, RestartAtRebuildStepIsBitwiseIdentical) { restart_is_bitwise(StopAt::RebuildStep); }
TEST(Checkpoint, RestartBetweenRebuildsIsBitwiseIdentical) { restart_is_bitwise(StopAt::BetweenRebuilds); }
TEST(Checkpoint, RestartAfterResortIsBitwiseIdentical) { restart_is_bitwise(StopAt::AfterResort); }

TEST(Checkpoint, RejectsOtherModelAndTruncation) {
  auto a = setup();
  a->add_particle(0, 5e-4, {0.005, 0, 0.001});
  a->prepare();
  const auto path = std::filesystem::temp_directory_path() / ("cohdem_test_checkpoint2_" + std::to_string(::getpid()) + ".bin");
  write_checkpoint(path, *a);
  auto other = make_system({{"glass", 2500, 1e7, 0.25}}, "linear", "none",
                           params({{"kn", 1e3}, {"e", 0.5}, {"mu", 0.5}}), 2e-6);
  EXPECT_THROW(read_checkpoint(path, *other), InputError);
  std::filesystem::resize_file(path, 100);
  auto b = setup();
  EXPECT_THROW(read_checkpoint(path, *b), InputError);
  std::filesystem::remove(path);
}

// A corrupt array length (here 2^62 particle ids, as a damaged file could hold) is reported as
// a truncated file before anything is allocated for it, not as std::bad_alloc or a crash.
TEST(Checkpoint, RejectsCorruptLengthBeforeAllocating) {
  auto a = setup();
  a->add_particle(0, 5e-4, {0.005, 0, 0.001});
  a->prepare();
  const auto path = std::filesystem::temp_directory_path() / ("cohdem_test_checkpoint3_" + std::to_string(::getpid()) + ".bin");
  write_checkpoint(path, *a);
  // The layout up to the first array (the particle ids): magic (8), version (4), model name
  // (8 + its length), history stride (8), time, step, next id, builds (8 each), the random
  // generator's state (8 + its length).
  const size_t at = 8 + 4 + 8 + a->model->name().size() + 8 + 4 * 8 + 8 + a->rng.state().size();
  {
    std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
    uint64_t n = 0;
    f.seekg(std::streamoff(at));
    f.read(reinterpret_cast<char*>(&n), sizeof n);
    ASSERT_EQ(n, 1u);  // the layout above is right: one particle
    n = uint64_t(1) << 62;
    f.seekp(std::streamoff(at));
    f.write(reinterpret_cast<const char*>(&n), sizeof n);
  }
  auto b = setup();
  try {
    read_checkpoint(path, *b);
    ADD_FAILURE() << "a corrupt length was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
  }
  std::filesystem::remove(path);
}

// Every particle is a solid sphere (sphere_inertia), which the contact lanes rely on instead
// of reading the inertias: a checkpoint whose inertia is not 2/5 m r^2 of its particle's mass
// and radius (a damaged or foreign file) is refused, naming the file and the field.
TEST(Checkpoint, RejectsInertiaThatIsNotTheSpheres) {
  auto a = setup();
  a->add_particle(0, 5e-4, {0.005, 0, 0.001});
  a->prepare();
  const double I = a->particles.inertia[0];
  ASSERT_EQ(I, sphere_inertia(a->particles.mass[0], a->particles.radius[0]));
  const auto path = std::filesystem::temp_directory_path() / ("cohdem_test_checkpoint5_" + std::to_string(::getpid()) + ".bin");
  write_checkpoint(path, *a);
  {  // the inertia's 8 bytes, found in the file, replaced by 1.5 I
    std::ifstream f(path, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    const std::string pat(reinterpret_cast<const char*>(&I), sizeof I);
    const size_t at = bytes.find(pat);
    ASSERT_NE(at, std::string::npos);
    ASSERT_EQ(bytes.find(pat, at + 1), std::string::npos) << "the inertia's bytes are not unique in the file";
    const double bad = 1.5 * I;
    bytes.replace(at, sizeof bad, reinterpret_cast<const char*>(&bad), sizeof bad);
    std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
  }
  auto b = setup();
  try {
    read_checkpoint(path, *b);
    ADD_FAILURE() << "an inertia that is not the sphere's was accepted";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("moments of inertia"), std::string::npos) << m;
    EXPECT_NE(m.find(path.filename().string()), std::string::npos) << m;
  }
  std::filesystem::remove(path);
}

// The wall indices of attached particles (ParticleStore::body) exist only once a particle is
// attached (ParticleStore::attach); they follow their particles through re-sorts, removals
// and checkpoints. A particle flagged as attached that names no wall is refused by prepare(),
// and by the checkpoint reader, instead of indexing past the walls.
TEST(Checkpoint, WallAttachmentsOnlyWithAttachedParticles) {
  const auto path = std::filesystem::temp_directory_path() / ("cohdem_test_checkpoint4_" + std::to_string(::getpid()) + ".bin");
  auto a = setup();
  for (int k = 0; k < 4; ++k) a->add_particle(0, 5e-4, {0.002 * (k + 1), 0, 0.001});
  a->prepare();
  EXPECT_TRUE(a->particles.body.empty());
  EXPECT_FALSE(a->nl.tracks_radii());  // no thermal model: the radii cannot change
  write_checkpoint(path, *a);
  auto b = setup();
  read_checkpoint(path, *b);
  EXPECT_TRUE(b->particles.body.empty());
  EXPECT_EQ(b->particles.x, a->particles.x);

  // Attached: one entry per particle, -1 for the others, also for particles added later.
  ParticleStore& P = a->particles;
  P.attach(1, 0);
  P.attach(3, 2);
  a->add_particle(0, 5e-4, {0.009, 0, 0.003});
  ASSERT_EQ(P.body.size(), 5u);
  auto wall_of = [&](const ParticleStore& s, uint64_t id) {
    for (size_t i = 0; i < s.size(); ++i)
      if (s.id[i] == id) return s.flag[i] == kAttached ? s.body[i] : -1;
    return -2;
  };
  const std::vector<int32_t> want{-1, 0, -1, 2, -1};  // by id 0..4
  std::vector<uint32_t> perm{4, 2, 0, 3, 1};
  P.permute(perm);
  std::vector<uint8_t> remove{0, 1, 0, 0, 0};  // id 2
  P.erase_if_flagged(remove);
  ASSERT_EQ(P.size(), 4u);
  for (uint64_t id : {0, 1, 3, 4}) EXPECT_EQ(wall_of(P, id), want[id]) << "id " << id;
  a->prepare();
  write_checkpoint(path, *a);
  auto c = setup();
  read_checkpoint(path, *c);
  ASSERT_EQ(c->particles.body.size(), 4u);
  for (uint64_t id : {0, 1, 3, 4}) EXPECT_EQ(wall_of(c->particles, id), want[id]) << "id " << id;

  // A wall index past the walls, in a checkpoint: refused by the reader.
  for (size_t i = 0; i < P.size(); ++i)
    if (P.flag[i] == kAttached) P.body[i] = 7;
  write_checkpoint(path, *a);
  auto d = setup();
  try {
    read_checkpoint(path, *d);
    ADD_FAILURE() << "an attachment to a missing wall was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("wall attachments"), std::string::npos) << e.what();
  }
  std::filesystem::remove(path);
  // ... and by prepare(), as is a particle flagged as attached without attach().
  EXPECT_THROW(a->prepare(), RunError);
  auto e = setup();
  e->add_particle(0, 5e-4, {0.005, 0, 0.001});
  e->particles.flag[0] = kAttached;
  EXPECT_THROW(e->prepare(), RunError);
}
