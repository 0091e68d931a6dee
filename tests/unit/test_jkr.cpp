// JKR and DMT adhesion (presets `jkr`, `dmt`) against the closed forms of
// src/models/normal/jkr.hpp and dmt.hpp.
//
// JKR, parametric in the contact radius a (R = R*, E = E*, w work of adhesion):
//   P(a) = 4 E a^3 / (3 R) - sqrt(8 pi w E a^3),  alpha(a) = a^2 / R - sqrt(2 pi w a / E).
//  - dP/da = 0 at a_c^3 = 9 pi w R^2 / (8 E): P = 3/2 pi w R - 3 pi w R = -(3/2) pi w R (pull-off
//    Pc), at alpha_c = -(3^(1/3)/4) (pi^2 w^2 R / E^2)^(1/3).
//  - d alpha/da = 0 at a_s^3 = pi w R^2 / (8 E): alpha_s = (1/4 - 1) (pi^2 w^2 R / E^2)^(1/3),
//    P = pi w R / 6 - pi w R = -(5/9) Pc; the contact separates there.
//  - alpha = 0 at a_0^3 = 2 pi w R^2 / E: P = 8/3 pi w R - 4 pi w R = -(8/9) Pc (snap-in).
// DMT: f = 4/3 E sqrt(R) delta^(3/2) - 2 pi w R for delta > 0, nothing otherwise.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "contact_fixture.hpp"

using namespace cohdem;
using namespace cohdem::testing;

namespace {

constexpr double R = 1e-5, E = 1e9, nu = 0.3, w = 0.05, mu = 0.4;
const double Rs = R / 2, Es = E / (2 * (1 - nu * nu));
const double Pc = 1.5 * M_PI * w * Rs;
const double scale = std::cbrt(M_PI * M_PI * w * w * Rs / (Es * Es));
const double alpha_s = -0.75 * scale;

double P_of(double a) { return 4 * Es * a * a * a / (3 * Rs) - std::sqrt(8 * M_PI * w * Es * a * a * a); }
double alpha_of(double a) { return a * a / Rs - std::sqrt(2 * M_PI * w * a / Es); }

DriverSetup spheres() {
  DriverSetup s;
  s.ri = s.rj = R;
  return s;
}

}  // namespace

TEST(Jkr, CurvePullOffSnapInAndSeparation) {
  auto m = one_pair_model("jkr", "none", pset({{"w", w}, {"e", 0.5}, {"mu", mu}}), E, nu);
  const int cf = column(*m, "fn"), ca = column(*m, "a"), cc = column(*m, "contact");
  const double as = std::cbrt(M_PI * w * Rs * Rs / (8 * Es)), ac = std::cbrt(9 * M_PI * w * Rs * Rs / (8 * Es));
  const double a0 = std::cbrt(2 * M_PI * w * Rs * Rs / Es);
  ASSERT_NEAR(alpha_of(as), alpha_s, 1e-12 * scale);
  ASSERT_NEAR(P_of(ac), -Pc, 1e-12 * Pc);
  const double alpha_c = alpha_of(ac);
  EXPECT_NEAR(alpha_c, -std::cbrt(3.0) / 4 * scale, 1e-12 * scale);

  PathBuilder pb;
  pb.at(0.5 * alpha_s);          // 0: apart, not touched yet: no contact
  pb.at(1e-9 * scale);           // 1: touch: snap-in
  const double as_list[] = {3 * a0, 2 * a0, a0, ac, 1.1 * as, 1.01 * as};
  for (double a : as_list) pb.at(alpha_of(a));  // 2..7: points of the curve
  pb.at(alpha_s * (1 - 1e-6));   // 8: just before separation
  pb.at(alpha_s * (1 + 1e-6));   // 9: separated
  pb.at(0.5 * alpha_s);          // 10: apart again: no contact (needs a new touch)
  const Rows r = drive_contact(*m, 0, 0, spheres(), pb.table());

  EXPECT_EQ(r[0][cc], 0);
  EXPECT_EQ(r[1][cc], 1);
  // Snap-in: the curve at alpha = 1e-9 scale differs from P(a0) by ~ slope x alpha ~1e-9 Pc.
  EXPECT_NEAR(r[1][cf], -8.0 / 9.0 * Pc, 1e-6 * Pc);
  for (int i = 0; i < 6; ++i) {
    // Newton converges to rounding; 1e-10 Pc allows the conditioning near a_s.
    EXPECT_NEAR(r[2 + i][cf], P_of(as_list[i]), 1e-10 * Pc) << "a = " << as_list[i];
    EXPECT_NEAR(r[2 + i][ca], as_list[i], 1e-6 * as_list[i]) << "a = " << as_list[i];
  }
  EXPECT_NEAR(r[5][cf], -Pc, 1e-10 * Pc);  // the pull-off point a_c
  double fmin = 0;
  for (const auto& row : r) fmin = std::min(fmin, row[cf]);
  EXPECT_NEAR(fmin, -Pc, 1e-10 * Pc);
  // Near alpha_s, a - a_s ~ sqrt(alpha - alpha_s): 1e-6 in alpha moves P by ~1e-3 of Pc.
  EXPECT_EQ(r[8][cc], 1);
  EXPECT_NEAR(r[8][cf], -5.0 / 9.0 * Pc, 5e-3 * Pc);
  EXPECT_EQ(r[9][cc], 0);
  EXPECT_EQ(r[10][cc], 0);
  EXPECT_NEAR(m->reach(0, 0, Rs), -alpha_s, 1e-15 * scale);
  std::printf("JKR: Pc = %.6e N (min seen %.6e), alpha_s = %.6e m, snap-in %.6e N (exp %.6e)\n", Pc, -fmin, alpha_s,
              r[1][cf], -8.0 / 9.0 * Pc);
}

// Fine displacement-controlled unloading: the sampled minimum approaches -Pc from above
// and the contact ends at the first row at or beyond alpha_s.
TEST(Jkr, DisplacementControlledUnloading) {
  auto m = one_pair_model("jkr", "none", pset({{"w", w}, {"e", 0.5}, {"mu", mu}}), E, nu);
  const int cd = column(*m, "delta"), cf = column(*m, "fn"), cc = column(*m, "contact");
  PathBuilder pb;
  pb.at(0.0).to(2 * scale, 1000).to(-2 * scale, 20000);
  const Rows r = drive_contact(*m, 0, 0, spheres(), pb.table());
  double fmin = 0;
  size_t last = 0;
  for (size_t i = 0; i < r.size(); ++i) {
    fmin = std::min(fmin, r[i][cf]);
    if (r[i][cc] == 1) last = i;
  }
  // Step h = 2e-4 scale; near the minimum P is quadratic in alpha, so the sampled minimum
  // is within ~P'' h^2 of -Pc: 1e-6 Pc is ample.
  EXPECT_NEAR(fmin, -Pc, 1e-6 * Pc);
  EXPECT_GT(r[last][cd], alpha_s);
  EXPECT_LE(r[last + 1][cd], alpha_s);
  EXPECT_EQ(r[last + 1][cc], 0);
}

TEST(Jkr, FrictionBaseThorntonOffset) {
  auto m = one_pair_model("jkr", "none", pset({{"w", w}, {"e", 0.5}, {"mu", mu}}), E, nu);
  const int cf = column(*m, "fn"), cft = column(*m, "ft");
  PathBuilder pb;
  pb.at(0.0).to(0.2 * scale, 10).go(PathBuilder::Xi, 1e-3, 20);  // far past sliding
  const Rows r = drive_contact(*m, 0, 0, spheres(), pb.table());
  EXPECT_NEAR(r.back()[cft], mu * (r.back()[cf] + 2 * Pc), 1e-12 * Pc);
}

TEST(Dmt, HertzPlusConstantAdhesion) {
  auto m = one_pair_model("dmt", "none", pset({{"w", w}, {"e", 0.5}, {"mu", mu}}), E, nu);
  const int cf = column(*m, "fn"), cc = column(*m, "contact"), cft = column(*m, "ft");
  const double F0 = 2 * M_PI * w * Rs;
  PathBuilder pb;
  pb.at(-1e-9).at(1e-15).at(1e-8).at(2e-8).at(0.0);
  const Rows r = drive_contact(*m, 0, 0, spheres(), pb.table());
  EXPECT_EQ(r[0][cc], 0);
  EXPECT_NEAR(r[1][cf], -F0, 1e-9 * F0);  // snap-in at the DMT pull-off force
  for (int i : {2, 3}) {
    const double d = r[i][0];
    EXPECT_NEAR(r[i][cf], 4.0 / 3.0 * Es * std::sqrt(Rs) * std::pow(d, 1.5) - F0, 1e-12 * F0);
  }
  EXPECT_EQ(r[4][cc], 0);
  EXPECT_EQ(m->reach(0, 0, Rs), 0.0);
  // Friction base: the Hertz repulsion f + F0.
  PathBuilder pt;
  pt.at(0.0).to(1e-8, 10).go(PathBuilder::Xi, 1e-3, 20);
  const Rows q = drive_contact(*m, 0, 0, spheres(), pt.table());
  EXPECT_NEAR(q.back()[cft], mu * (q.back()[cf] + F0), 1e-12 * F0);
}
