// Packed-bed mechanics that the validation runs rely on: the floating spring-loaded lid and
// trimming a bed (removing particles) without losing the contact history of the rest.
#include <gtest/gtest.h>

#include "physics/fixture.hpp"

using namespace cohdem;
using namespace cohdem::testing;

// A lid (mass m_L, spring k, preload P, normal -z) comes to rest on one sphere lying on a floor.
// Linear springs: delta_lid = F/kn, delta_floor = (F + m g)/kn; the lid sits at
// z = 2 r - delta_floor - delta_lid after travelling z0 - z, and the spring gives
// F = P + m_L g - k travel. Solving: F (1 + 2 k/kn) = P + m_L g - k (z0 - 2 r) - k m g / kn.
TEST(SpringLid, FloatsToTheForceBalance) {
  const double r = 1e-3, kn = 1e4, g = 9.81, mL = 2e-3, k = 50, P = 0.05, z0 = 2 * r + 2e-4;
  auto s = make_system({{"glass", 2500, 0, 0}}, "linear", "none", params({{"kn", kn}, {"e", 0.2}, {"mu", 0.5}}), 2e-6,
                       {0, 0, -g});
  s->walls.push_back(plane({0, 0, 0}, {0, 0, 1}, 0));
  Wall lid = plane({0, 0, z0}, {0, 0, -1}, 0);
  lid.name = "lid";
  lid.control = WallControl::Spring;
  lid.mass = mL;
  lid.spring_k = k;
  lid.spring_preload = P;
  s->walls.push_back(lid);
  s->add_particle(0, r, {0, 0, r});
  s->cfg.threads = 1;  // two bodies: threads only add overhead
  s->prepare();
  s->run(300000);  // 0.6 s: the lid bounces, the contacts damp it
  const double m = s->particles.mass[0];
  const double F = (P + mL * g - k * (z0 - 2 * r) - k * m * g / kn) / (1 + 2 * k / kn);
  const Wall& W = s->walls[1];
  EXPECT_NEAR(W.force.z, F, 1e-4 * F);
  EXPECT_NEAR(W.travel, z0 - (2 * r - (2 * F + m * g) / kn), 1e-9);
  EXPECT_NEAR(std::fabs(W.vn), 0.0, 1e-6);
}

// Removing the top sphere of a resting column keeps the other contacts and their history.
TEST(RemoveParticles, TrimsAColumnAndKeepsHistory) {
  const double r = 1e-3, kn = 1e4, g = 9.81;
  auto s = make_system({{"glass", 2500, 0, 0}}, "linear", "none", params({{"kn", kn}, {"e", 0.3}, {"mu", 0.5}}), 5e-6,
                       {0, 0, -g});
  s->walls.push_back(plane({0, 0, 0}, {0, 0, 1}, 0));
  for (int k = 0; k < 4; ++k) s->add_particle(0, r, {0, 0, r + 2 * r * k});
  s->cfg.threads = 1;
  s->prepare();
  s->run(40000);
  ASSERT_EQ(s->contact_count(), 4u);
  std::vector<uint8_t> remove(4, 0);
  for (size_t i = 0; i < 4; ++i) remove[i] = s->particles.x[i].z > 6 * r;
  s->remove_particles(remove);
  ASSERT_EQ(s->particles.size(), 3u);
  EXPECT_EQ(s->contact_count(), 3u);  // still live, before any rebuild
  s->run(40000);
  const double m = s->particles.mass[0];
  EXPECT_NEAR(-s->walls[0].force.z, 3 * m * g, 1e-6 * m * g);
  EXPECT_EQ(s->nl.stats.lost_contacts, 0u);
  EXPECT_EQ(s->contact_count(), 3u);
}
