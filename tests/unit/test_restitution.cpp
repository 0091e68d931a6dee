// Damping calibration: the numerical restitution map must reproduce the closed form for the
// linear spring-dashpot (Schwager & Poeschel 2008: e = exp(-beta pi / sqrt(1 - beta^2))).
#include <gtest/gtest.h>

#include <cmath>

#include "models/damping/restitution.hpp"

using namespace cohdem;

TEST(Restitution, LinearClosedFormMatchesIntegration) {
  for (double e : {0.1, 0.3, 0.5, 0.7, 0.9}) {
    const double l = std::log(e);
    const double beta = -l / std::sqrt(M_PI * M_PI + l * l);
    // RK4 with h = 1e-4 over a unit-frequency contact: error far below 1e-6.
    EXPECT_NEAR(restitution_of_beta(beta, 1.0, false), e, 1e-6) << "e=" << e;
    EXPECT_NEAR(beta_for_restitution(e, 1.0, false), beta, 1e-6) << "e=" << e;
  }
}

TEST(Restitution, HertzMapIsInverse) {
  for (double e : {0.2, 0.5, 0.8}) {
    const double b = beta_for_restitution(e, 1.5, false);
    EXPECT_NEAR(restitution_of_beta(b, 1.5, false), e, 1e-6);
  }
}
