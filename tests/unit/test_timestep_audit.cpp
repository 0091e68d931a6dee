// Time-step audit against closed forms: the Rayleigh time of glass and the linear-spring
// collision time t_c = pi sqrt(m*/kn) (the audit's estimate is exact for a linear spring);
// Hertz: the audit's pi sqrt(m*/kn(delta_max)) is 2.295/2.943 = 0.780 of Hertz's duration
// 2.943 delta_max / v (Johnson 1985, Eq. 11.24), derived in timestep_audit.hpp.
#include <gtest/gtest.h>

#include <cmath>

#include "../physics/fixture.hpp"
#include "sim/timestep_audit.hpp"

using namespace cohdem;
using namespace cohdem::testing;

TEST(TimestepAudit, RayleighAndLinearCollisionTime) {
  const double r = 1e-3, rho = 2500, kn = 1e4;
  auto s = make_system({{"glass", rho, 7e10, 0.25}}, "linear", "none", params({{"kn", kn}, {"e", 0.5}, {"mu", 0.5}}),
                       1e-7);
  const auto a = audit_timestep(*s, {r}, 1.0);
  const double G = 7e10 / 2.5;
  EXPECT_NEAR(a.rayleigh, M_PI * r * std::sqrt(rho / G) / (0.1631 * 0.25 + 0.8766), 1e-15);
  const double m = rho * 4.0 / 3.0 * M_PI * r * r * r;
  EXPECT_NEAR(a.collision / (M_PI * std::sqrt(0.5 * m / kn)), 1.0, 1e-6);
  EXPECT_EQ(a.level, TimestepAudit::Ok);
}

TEST(TimestepAudit, HertzCollisionTimeAndLevels) {
  const double r = 1e-3, rho = 2500, E = 1e8, nu = 0.25, v = 1.0;
  const double Es = 1.0 / (2 * (1 - nu * nu) / E), Rs = r / 2;
  const double m = rho * 4.0 / 3.0 * M_PI * r * r * r, ms = m / 2;
  const double dmax = std::pow(15 * ms * v * v / (16 * Es * std::sqrt(Rs)), 0.4);
  const double t_est = M_PI * std::sqrt(ms / (2 * Es * std::sqrt(Rs * dmax)));
  for (double dt : {t_est / 40, t_est / 10, t_est / 5}) {
    auto s = make_system({{"g", rho, E, nu}}, "hertz_mindlin", "none", params({{"e", 0.9}, {"mu", 0.5}}), dt);
    const auto a = audit_timestep(*s, {r}, v);
    EXPECT_NEAR(a.collision / t_est, 1.0, 1e-3);  // quadrature of the loading curve: 400 steps
    const auto want = dt == t_est / 40 ? TimestepAudit::Ok : dt == t_est / 10 ? TimestepAudit::Warn : TimestepAudit::Error;
    EXPECT_EQ(a.level, want) << "dt = t_c/" << t_est / dt;
  }
}

// The rolling spring's half period against its closed form. SDS: a moment k_r R*^2 per radian
// of relative rotation (the spring acts on the rolling displacement R* theta, its force at
// the lever R*), on the relative rotation's inertia I_eff = I/2 for two equal spheres, so
// t_r = pi sqrt(I/(2 k_r R*^2)); k_r chosen for 10 steps (warning) and 5 (error), with the
// collision well resolved. EPSD with mu_r = 0.3: slower than the collision by 0.84/mu_r, no
// message. CDT has no spring: no rolling time.
TEST(TimestepAudit, RollingSpringHalfPeriod) {
  const double r = 1e-3, rho = 2500, kn = 1e4, dt = 1e-6;
  const double m = rho * 4.0 / 3.0 * M_PI * r * r * r, I = 0.4 * m * r * r, Rs = r / 2;
  const double tc = M_PI * std::sqrt(0.5 * m / kn);
  ASSERT_GT(tc / dt, 20.0);  // the collision alone passes
  for (double steps : {10.0, 5.0}) {
    const double t = steps * dt, k_r = M_PI * M_PI * I / (2 * Rs * Rs * t * t);
    auto s = make_system({{"glass", rho, 0, 0}}, "linear", "sds",
                         params({{"kn", kn}, {"e", 0.5}, {"mu", 0.5}, {"k_r", k_r}, {"gamma_r", 1e-3}, {"mu_r", 0.1}}), dt);
    const auto a = audit_timestep(*s, {r}, 1.0);
    EXPECT_NEAR(a.rolling / t, 1.0, 1e-6) << steps << " steps";
    EXPECT_EQ(a.level, steps < 8 ? TimestepAudit::Error : TimestepAudit::Warn) << steps << " steps";
  }
  auto e = make_system({{"glass", rho, 0, 0}}, "linear", "epsd", params({{"kn", kn}, {"e", 0.5}, {"mu", 0.5}, {"mu_r", 0.3}}), dt);
  const auto ae = audit_timestep(*e, {r}, 1.0);
  // EPSD: k_r = 2.25 kn mu_r^2 R*^2, so t_r / t_c = sqrt((I/2) / (2.25 mu_r^2 R*^2 m/2)) = sqrt(0.711)/mu_r.
  EXPECT_NEAR(ae.rolling / tc, std::sqrt(0.4 / 0.5625) / 0.3, 1e-3);
  EXPECT_EQ(ae.level, TimestepAudit::Ok);
  auto c = make_system({{"glass", rho, 0, 0}}, "linear", "cdt", params({{"kn", kn}, {"e", 0.5}, {"mu", 0.5}, {"mu_r", 0.3}}), dt);
  EXPECT_EQ(audit_timestep(*c, {r}, 1.0).rolling, 0.0);
}
