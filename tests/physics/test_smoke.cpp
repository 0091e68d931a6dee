#include <gtest/gtest.h>

#include "fixture.hpp"

using namespace cohdem;
using namespace cohdem::testing;

TEST(Smoke, SphereBouncesOnPlaneWithRestitution) {
  const double e = 0.5, kn = 1e5, r = 0.01, rho = 2500;
  auto s = make_system({{"glass", rho, 0, 0}}, "linear", "none", params({{"kn", kn}, {"e", e}, {"mu", 0.0}}),
                       1e-6);
  s->walls.push_back(plane({0, 0, 0}, {0, 0, 1}, 0));
  s->add_particle(0, r, {0, 0, r + 1e-4}, {0, 0, -1.0});
  s->prepare();
  s->run(20000);
  EXPECT_NEAR(s->particles.v[0].z, e * 1.0, 1e-3);
}
