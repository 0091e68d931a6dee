// Janssen silo / piston solutions (Walton, seed 001, Eqs. 13 and 16) and the mu_k fit.
// Setup of Walton's test: 3 mm glass beads in a 4 cm pipe (R = 0.02 m), mu k = 0.232.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "analysis/janssen.hpp"

using namespace cohdem;

namespace {

const JanssenSetup kSetup{1500.0, 9.81, 0.02};  // rho (kg/m^3), g, R (m)

// Eqs. 13/16 written out directly (not through the implementation's expm1 form).
double force_formula(JanssenMode m, double K, double y) {
  const double R = kSetup.radius, scale = kSetup.rho * kSetup.g * R / (2 * K);
  const double sig = m == JanssenMode::Silo ? scale * (1 - std::exp(-2 * K * y / R))
                                            : scale * (std::exp(2 * K * y / R) - 1);
  return sig * M_PI * R * R;
}

std::vector<double> heights() {
  std::vector<double> y;
  for (int i = 1; i <= 40; ++i) y.push_back(0.005 * i);  // 5 mm .. 0.2 m (5 diameters)
  return y;
}

// Deterministic standard normal deviates (64-bit LCG + Box-Muller), platform independent.
struct Normal {
  std::uint64_t s = 12345;
  double uniform() {
    s = s * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double(s >> 11) + 0.5) / 9007199254740992.0;
  }
  double operator()() {
    return std::sqrt(-2 * std::log(uniform())) * std::cos(2 * M_PI * uniform());
  }
};

}  // namespace

TEST(Janssen, StressMatchesEquations) {
  for (auto m : {JanssenMode::Silo, JanssenMode::Piston})
    for (double y : {0.001, 0.02, 0.1, 0.3}) {
      const double f = force_formula(m, 0.232, y);
      EXPECT_NEAR(janssen_force(m, 0.232, y, kSetup), f, 1e-12 * f);
      EXPECT_NEAR(janssen_stress(m, 0.232, y, kSetup) * M_PI * 0.02 * 0.02, f, 1e-12 * f);
    }
}

// Small y: sigma = rho g y (1 -/+ x/2 + ...), x = 2 mu_k y/R: relative deviation from the
// hydrostatic rho g y is mu_k y/R to first order.
TEST(Janssen, HydrostaticLimit) {
  const double A = M_PI * 0.02 * 0.02, hyd_per_m = 1500 * 9.81 * A;
  for (auto m : {JanssenMode::Silo, JanssenMode::Piston}) {
    const double y = 1e-5;  // mu_k y/R = 1.16e-4
    const double f = janssen_force(m, 0.232, y, kSetup);
    const double rel = (f - hyd_per_m * y) / (hyd_per_m * y);
    const double first_order = (m == JanssenMode::Silo ? -1 : 1) * 0.232 * y / 0.02;
    EXPECT_NEAR(rel, first_order, 2e-8);  // next term x^2/6 = 9e-9
    // mu_k -> 0 is exactly hydrostatic, no 0/0.
    EXPECT_DOUBLE_EQ(janssen_force(m, 0.0, 0.1, kSetup), hyd_per_m * 0.1);
    EXPECT_NEAR(janssen_force(m, 1e-12, 0.1, kSetup), hyd_per_m * 0.1, 1e-9 * hyd_per_m * 0.1);
  }
  // Deep silo bed reaches the asymptote rho g R/(2 mu_k) pi R^2.
  EXPECT_NEAR(janssen_force(JanssenMode::Silo, 0.232, 10.0, kSetup),
              1500 * 9.81 * 0.02 / (2 * 0.232) * A, 1e-12);
}

TEST(Janssen, FitRecoversExactMuK) {
  const auto y = heights();
  for (auto m : {JanssenMode::Silo, JanssenMode::Piston}) {
    std::vector<double> f;
    for (double h : y) f.push_back(force_formula(m, 0.232, h));
    const auto fit = fit_janssen_mu_k(m, y, f, kSetup);
    EXPECT_NEAR(fit.mu_k, 0.232, 1e-6);
    EXPECT_NEAR(fit.mu_k, 0.232, 1e-9);  // in fact far better than the 1e-6 required
    EXPECT_LT(fit.rms_residual, 1e-9);
    EXPECT_FALSE(fit.at_bound);
    EXPECT_EQ(fit.n, y.size());
    EXPECT_NEAR(fit.asymptote_stress, 1500 * 9.81 * 0.02 / (2 * 0.232), 1e-3);
    EXPECT_NEAR(fit.asymptote_force, fit.asymptote_stress * M_PI * 0.02 * 0.02, 1e-12);
  }
}

// Gaussian noise of sd s on each force. Linearising F about the true mu_k, the least-squares
// estimate has sd s / sqrt(sum J_i^2) with J_i = dF/dmu_k(y_i); we require 4 sd, and the rms
// residual to be within 25% of s (40 points).
TEST(Janssen, FitNoisyWithinDerivedTolerance) {
  const auto y = heights();
  for (auto m : {JanssenMode::Silo, JanssenMode::Piston}) {
    Normal rnd;
    double s = 0, sjj = 0;
    std::vector<double> f;
    for (double h : y) s = std::max(s, 0.02 * force_formula(m, 0.232, h));  // 2% of max force
    for (double h : y) {
      const double dk = 1e-6;
      const double j = (force_formula(m, 0.232 + dk, h) - force_formula(m, 0.232 - dk, h)) / (2 * dk);
      sjj += j * j;
      f.push_back(force_formula(m, 0.232, h) + s * rnd());
    }
    const double sd = s / std::sqrt(sjj);
    const auto fit = fit_janssen_mu_k(m, y, f, kSetup);
    EXPECT_NEAR(fit.mu_k, 0.232, 4 * sd) << "sd = " << sd;
    EXPECT_NEAR(fit.rms_residual, s, 0.25 * s);
    EXPECT_FALSE(fit.at_bound);
  }
}

TEST(Janssen, FitFlagsBoundAndRejectsBadInput) {
  const auto y = heights();
  std::vector<double> f;
  for (double h : y) f.push_back(force_formula(JanssenMode::Silo, 20.0, h));  // outside (1e-4, 5)
  EXPECT_TRUE(fit_janssen_mu_k(JanssenMode::Silo, y, f, kSetup).at_bound);
  EXPECT_THROW(fit_janssen_mu_k(JanssenMode::Silo, y, std::vector<double>(3), kSetup),
               std::invalid_argument);
  EXPECT_THROW(fit_janssen_mu_k(JanssenMode::Silo, y, f, JanssenSetup{1500, 9.81, 0}),
               std::invalid_argument);
}

// k = sum(sh sv)/sum(sv^2): sv = {1000, 2000}, sh = {500, 700} -> 1.9e6/5e6 = 0.38;
// residuals 500 - 380 = 120 and 700 - 760 = -60 -> rms sqrt((14400 + 3600)/2) = 94.87 Pa.
TEST(StressRatio, LeastSquaresThroughOrigin) {
  const std::vector<double> sv{0.0, 1000.0, 2000.0}, sh{10.0, 500.0, 700.0};
  const auto k = fit_stress_ratio(sv, sh);  // the empty top bin (sv = 0) is skipped
  EXPECT_EQ(k.n_used, 2u);
  EXPECT_NEAR(k.value, 0.38, 1e-15);
  EXPECT_NEAR(k.rms_residual, std::sqrt(9000.0), 1e-10);
  EXPECT_FALSE(k.per_bin[0].has_value());
  EXPECT_NEAR(*k.per_bin[1], 0.5, 1e-15);
  EXPECT_NEAR(*k.per_bin[2], 0.35, 1e-15);
  EXPECT_THROW(fit_stress_ratio(std::vector<double>{0.0}, std::vector<double>{1.0}),
               std::invalid_argument);
  EXPECT_THROW(fit_stress_ratio(sv, std::vector<double>{1.0}), std::invalid_argument);
}

TEST(WallFriction, MobilisedRatio) {
  std::vector<double> sh, tw;
  for (int i = 1; i <= 10; ++i) {
    sh.push_back(300.0 * i);
    tw.push_back(0.3 * 300.0 * i);
  }
  const auto mu = fit_wall_friction(sh, tw);
  EXPECT_NEAR(mu.value, 0.3, 1e-14);
  EXPECT_NEAR(mu.rms_residual, 0.0, 1e-10);
  for (const auto& b : mu.per_bin) EXPECT_NEAR(*b, 0.3, 1e-14);
}
