// Ring shear evaluation (ASTM D6773, Schulze ch. 3): expected values are derived by hand
// from a chosen Mohr circle, not from the implementation's closed form.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

#include "analysis/yield_locus.hpp"

using namespace cohdem;

namespace {
const double kSqrt3 = std::sqrt(3.0);
const double kTan30 = 1.0 / std::sqrt(3.0);

std::vector<ShearPoint> on_line(double tan_phi, double c, std::vector<double> sig) {
  std::vector<ShearPoint> p;
  for (double s : sig) p.push_back({s, tan_phi * s + c});
  return p;
}
}  // namespace

// Locus tau = tan(30 deg) sigma + 2000 Pa: sin = 1/2, cos = sqrt(3)/2.
// Choose the steady-state circle first: centre s = 20000 Pa; tangency needs
//   r = s sin + c cos = 10000 + 1000 sqrt(3) = 11732.05 Pa,
// so sigma_1 = 30000 + 1000 sqrt(3) = 31732.05, sigma_2 = 10000 - 1000 sqrt(3) = 8267.95,
// tangent point at sigma = s - r sin = 15000 - 500 sqrt(3) = 14133.97.
// Pre-shear point: the top of that circle, (20000, 11732.05) (right of the tangent point, and
// below the locus there: 20000/sqrt(3) + 2000 = 13547 Pa).
// sigma_c = 2 c cos/(1 - sin) = 2*2000*(sqrt(3)/2)/(1/2) = 4000 sqrt(3) = 6928.20 Pa.
// ffc = (30000 + 1000 sqrt 3)/(4000 sqrt 3) = 7.5/sqrt(3) + 1/4 = 4.580127.
// sin(phi_e) = r/s = 1/2 + sqrt(3)/20;  tan(phi_sf) = r/s (top of circle) as well.
TEST(YieldLocus, CohesiveHandDerived) {
  const double s = 20000, r = 10000 + 1000 * kSqrt3;
  const auto pts = on_line(kTan30, 2000, {4000, 8000, 12000, 16000});
  const auto res = evaluate_yield_locus({s, r}, pts, 1450.0);
  EXPECT_NEAR(to_degrees(res.phi_lin), 30.0, 1e-10);
  EXPECT_NEAR(res.cohesion, 2000.0, 1e-8);
  EXPECT_NEAR(res.r_squared, 1.0, 1e-14);
  EXPECT_EQ(res.n_points, 4u);
  EXPECT_NEAR(res.sigma_c, 4000 * kSqrt3, 1e-7);
  EXPECT_NEAR(res.sigma_1, 30000 + 1000 * kSqrt3, 1e-7);
  EXPECT_NEAR(res.sigma_2, 10000 - 1000 * kSqrt3, 1e-7);
  EXPECT_NEAR(res.sigma_tangent, 15000 - 500 * kSqrt3, 1e-7);
  EXPECT_FALSE(res.ffc_infinite);
  EXPECT_NEAR(res.ffc, 7.5 / kSqrt3 + 0.25, 1e-12);
  EXPECT_NEAR(res.phi_e, std::asin(0.5 + kSqrt3 / 20), 1e-12);
  EXPECT_NEAR(to_degrees(res.phi_e), 35.91628, 1e-5);
  EXPECT_NEAR(res.phi_sf, std::atan(0.5 + kSqrt3 / 20), 1e-12);
  ASSERT_TRUE(res.bulk_density.has_value());
  EXPECT_EQ(*res.bulk_density, 1450.0);
}

// Same circle, pre-shear point at 105 deg on it (between the tangent point at 120 deg and the
// top): the evaluation must find the same circle (the root that touches left of sigma_pre).
TEST(YieldLocus, PreShearPointAnywhereRightOfTangency) {
  const double s = 20000, r = 10000 + 1000 * kSqrt3;
  const auto pts = on_line(kTan30, 2000, {3000, 6000, 9000});
  for (double deg : {60.0, 90.0, 105.0, 119.0}) {
    const double a = deg * M_PI / 180;
    const auto res = evaluate_yield_locus({s + r * std::cos(a), r * std::sin(a)}, pts);
    EXPECT_NEAR(res.sigma_1, s + r, 1e-6) << deg;
    EXPECT_NEAR(res.sigma_2, s - r, 1e-6) << deg;
    EXPECT_NEAR(res.phi_sf, std::atan2(r * std::sin(a), s + r * std::cos(a)), 1e-12);
  }
}

// Pre-shear point exactly on the locus: the circle is tangent at that point, its centre is
// where the normal to the locus through P meets the axis: s = A + T tan(phi), r = T/cos(phi).
// Here the circle depends on sqrt(tau_YL(A) - T), so a rounding-level 1e-16 misfit of the
// locus moves sigma_1 by ~sqrt(1e-16) relative: tolerance 1e-7 relative (4 mPa at 43 kPa).
TEST(YieldLocus, PreShearPointOnLocus) {
  const double A = 20000, T = kTan30 * A + 2000;
  const auto res = evaluate_yield_locus({A, T}, on_line(kTan30, 2000, {5000, 10000}));
  const double s = A + T * kTan30, r = T / (kSqrt3 / 2);
  EXPECT_NEAR(res.sigma_1, s + r, 1e-7 * (s + r));
  EXPECT_NEAR(res.sigma_2, s - r, 1e-7 * (s + r));
  EXPECT_NEAR(res.sigma_tangent, A, 1e-7 * (s + r));
}

// c = 0: sigma_c = 0, ffc infinite (flag, no NaN), phi_e = phi_lin. Circle s = 10 kPa,
// r = s sin(35 deg), pre-shear point at its top: sigma_1 = s (1 + sin 35 deg).
TEST(YieldLocus, Cohesionless) {
  const double phi = 35 * M_PI / 180, s = 10000, r = s * std::sin(phi);
  const auto res = evaluate_yield_locus({s, r}, on_line(std::tan(phi), 0, {2000, 5000, 8000}));
  EXPECT_NEAR(res.cohesion, 0.0, 1e-9);
  EXPECT_EQ(res.sigma_c, 0.0);
  EXPECT_TRUE(res.ffc_infinite);
  EXPECT_TRUE(std::isinf(res.ffc));
  EXPECT_FALSE(std::isnan(res.ffc));
  EXPECT_NEAR(res.phi_e, phi, 1e-9);
  EXPECT_NEAR(res.sigma_1, s * (1 + std::sin(phi)), 1e-7);
}

// Residuals +e, -e, -e, +e at sigma = 2, 4, 6, 8 kPa are orthogonal to 1 and to sigma, so
// least squares returns the generating line exactly. SS_res = 4 e^2 and
// SS_tot = tan^2 * sum (sigma - 5000)^2 + SS_res = (1/3) 20e6 + 4e4 for e = 100 Pa:
// R^2 = 1 - 4e4/(2e7/3 + 4e4) = 0.99403579.
TEST(YieldLocus, NoisyPointsKnownLeastSquares) {
  const double e = 100;
  std::vector<ShearPoint> pts = on_line(kTan30, 1500, {2000, 4000, 6000, 8000});
  pts[0].tau += e;
  pts[1].tau -= e;
  pts[2].tau -= e;
  pts[3].tau += e;
  const auto res = evaluate_yield_locus({12000, 7000}, pts);
  EXPECT_NEAR(std::tan(res.phi_lin), kTan30, 1e-13);
  EXPECT_NEAR(res.cohesion, 1500, 1e-9);
  EXPECT_NEAR(res.r_squared, 1 - 4e4 / (2e7 / 3 + 4e4), 1e-13);
  EXPECT_NEAR(res.r_squared, 0.99403579, 1e-8);
}

// Noisy, non-orthogonal: compare with the normal equations solved by hand.
// sigma = {1,2,3} kPa, tau = {1.6, 2.0, 2.9} kPa: mean sigma = 2000, mean tau = 2166.67,
// Sxy = (-1000)(-566.67) + 0 + 1000*733.33 = 1.3e6, Sxx = 2e6 -> slope 0.65,
// c = 2166.67 - 0.65*2000 = 866.67 Pa.
TEST(YieldLocus, NormalEquations) {
  const auto res = evaluate_yield_locus({4000, 3400}, std::vector<ShearPoint>{{1000, 1600},
                                                                              {2000, 2000},
                                                                              {3000, 2900}});
  EXPECT_NEAR(std::tan(res.phi_lin), 0.65, 1e-13);
  EXPECT_NEAR(res.cohesion, 2600.0 / 3.0, 1e-9);
}

// Pre-shear point above the locus, allowed: the steady-state circle touches the line of slope
// tan(phi) through P = (A, T) at P itself. Its centre lies on the normal to that line through
// P: s = A + T tan(phi), radius r = T / cos(phi), so sigma_1 = A + T tan(phi) + T / cos(phi).
// Locus tan30 sigma + 2000; P = (20000, 14000): s = 20000 + 14000 tan30 = 28082.90 Pa,
// r = 14000 / cos30 = 16165.81 Pa, sigma_1 = 44248.71 Pa, sigma_2 = 11917.09 Pa.
TEST(YieldLocus, PreShearAboveLocusAllowed) {
  const auto good = on_line(kTan30, 2000, {4000, 8000});
  const YieldLocusResult r = evaluate_yield_locus({20000, 14000}, good, std::nullopt, true);
  EXPECT_TRUE(r.preshear_above_locus);
  const double s = 20000 + 14000 * kTan30, rad = 14000 / std::cos(std::atan(kTan30));
  EXPECT_NEAR(r.sigma_1, s + rad, 1e-9 * (s + rad));
  EXPECT_NEAR(r.sigma_2, s - rad, 1e-9 * (s + rad));
  EXPECT_NEAR(r.sigma_1, 44248.71, 0.01);
  // The unconfined circle still uses the fitted locus (c = 2000).
  EXPECT_NEAR(r.cohesion, 2000, 1e-9);
  // A point below the locus is not affected by the flag.
  EXPECT_FALSE(evaluate_yield_locus({20000, 11000}, good, std::nullopt, true).preshear_above_locus);
}

// A very cohesive locus, tau = tan30 sigma + 20 kPa, pre-sheared at only (10, 25) kPa (below
// the locus's 25.77 kPa there): the circle through the pre-shear point tangent to the locus
// has centre s = [A + c sin cos - cos sqrt(tau_YL^2 - T^2)] / cos^2 = 17644.0 Pa and radius
// r = s sin + c cos = 26142.5 Pa (docs/analysis.md), so sigma_2 = s - r = -8498.5 Pa: no
// compressive consolidation state. sigma_1, sigma_2, sigma_tangent, phi_e and ffc are NaN and
// say why; the locus, sigma_c = 2 c cos30 / (1 - sin30) = 69282.03 Pa and phi_sf =
// atan(25/10) are still given (they do not use that circle).
TEST(YieldLocus, SteadyStateCircleInTensionKeepsTheLocus) {
  const auto pts = on_line(kTan30, 20000, {2000, 5000, 8000});
  const YieldLocusResult r = evaluate_yield_locus({10000, 25000}, pts, 1400.0, true);
  EXPECT_FALSE(r.steady_state);
  EXPECT_NE(r.steady_state_error.find("sigma_2 = -8498.5"), std::string::npos) << r.steady_state_error;
  EXPECT_NE(r.steady_state_error.find("not evaluated"), std::string::npos) << r.steady_state_error;
  EXPECT_NEAR(r.phi_lin, M_PI / 6, 1e-12);
  EXPECT_NEAR(r.cohesion, 20000, 1e-8);
  EXPECT_NEAR(r.sigma_c, 40000 * std::cos(M_PI / 6) / (1 - std::sin(M_PI / 6)), 1e-7);
  EXPECT_NEAR(r.phi_sf, std::atan2(25000.0, 10000.0), 1e-15);
  EXPECT_TRUE(std::isnan(r.sigma_1));
  EXPECT_TRUE(std::isnan(r.sigma_2));
  EXPECT_TRUE(std::isnan(r.sigma_tangent));
  EXPECT_TRUE(std::isnan(r.phi_e));
  EXPECT_TRUE(std::isnan(r.ffc));
  EXPECT_FALSE(r.ffc_infinite);
  EXPECT_FALSE(r.preshear_above_locus);
  // The same locus pre-sheared at a higher stress has its circle in compression: evaluated.
  const YieldLocusResult ok = evaluate_yield_locus({60000, 50000}, pts);
  EXPECT_TRUE(ok.steady_state);
  EXPECT_TRUE(ok.steady_state_error.empty());
  EXPECT_GE(ok.sigma_2, 0.0);
  EXPECT_NEAR(ok.ffc, ok.sigma_1 / ok.sigma_c, 1e-12);
}

TEST(YieldLocus, Errors) {
  const auto good = on_line(kTan30, 2000, {4000, 8000});
  EXPECT_THROW(evaluate_yield_locus({20000, 11000}, on_line(kTan30, 2000, {4000})),
               std::invalid_argument);
  EXPECT_THROW(evaluate_yield_locus({20000, 11000}, std::vector<ShearPoint>{{5000, 4000},
                                                                            {5000, 4100}}),
               std::invalid_argument);
  // Locus at 20 kPa is 13547 Pa: a pre-shear point above it has no tangent circle.
  try {
    evaluate_yield_locus({20000, 14000}, good);
    FAIL() << "expected invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("above the linearized yield locus"), std::string::npos);
  }
  EXPECT_THROW(evaluate_yield_locus({0, 0}, good), std::invalid_argument);
  // Decreasing locus.
  EXPECT_THROW(evaluate_yield_locus({20000, 1000}, std::vector<ShearPoint>{{4000, 3000},
                                                                           {8000, 2000}}),
               std::invalid_argument);
}

TEST(ShearSeries, PeakWithinPhase) {
  std::vector<double> t, tau;
  for (int i = 0; i <= 100; ++i) {
    t.push_back(i / 100.0);
    // Peak of 5000 Pa at t = 0.40 inside the phase [0.2, 0.8]; a larger value at t = 0.9
    // lies outside it.
    const double x = t.back();
    tau.push_back(x > 0.85 ? 9000 : 5000 - 20000 * (x - 0.4) * (x - 0.4));
  }
  const auto p = shear_peak(t, tau, 0.2, 0.8);
  EXPECT_EQ(p.index, 40u);
  EXPECT_NEAR(p.t, 0.40, 1e-12);
  EXPECT_NEAR(p.tau, 5000, 1e-9);
  EXPECT_THROW(shear_peak(t, tau, 2.0, 3.0), std::invalid_argument);
  EXPECT_THROW(shear_peak(t, std::vector<double>(3), 0.0, 1.0), std::invalid_argument);
}

TEST(ShearSeries, SteadyStatePreShear) {
  std::vector<double> t, tau;
  for (int i = 0; i <= 100; ++i) {
    t.push_back(i / 100.0);
    // +-10 Pa alternating ripple on 8000 Pa after a transient: mean of the last quarter
    // (t = 0.75 .. 1.00, 26 samples, 13 of each sign) is exactly 8000.
    tau.push_back(t.back() < 0.3 ? 20000 * t.back() : 8000 + (i % 2 ? 10 : -10));
  }
  const auto st = steady_state_value(t, tau, 0.0, 1.0, 0.25, 0.01);
  EXPECT_EQ(st.n_used, 26u);
  EXPECT_NEAR(st.mean, 8000, 1e-9);
  EXPECT_TRUE(st.steady);
  EXPECT_LT(st.relative_drift, 1e-3);

  // A ramp tau = 8000 + 4000 t: last quarter mean = 8000 + 4000*0.875 = 11500,
  // drift = 4000 * 0.25 / 11500 = 0.0870 -> not steady.
  for (std::size_t i = 0; i < t.size(); ++i) tau[i] = 8000 + 4000 * t[i];
  const auto ramp = steady_state_value(t, tau, 0.0, 1.0, 0.25, 0.01);
  EXPECT_NEAR(ramp.mean, 11500, 1e-8);
  EXPECT_NEAR(ramp.slope, 4000, 1e-7);
  EXPECT_NEAR(ramp.relative_drift, 1000.0 / 11500.0, 1e-10);
  EXPECT_FALSE(ramp.steady);
  EXPECT_THROW(steady_state_value(t, tau, 0.0, 1.0, 0.001), std::invalid_argument);
}
