// The single-contact driver (src/contact/driver.hpp): columns, kinematics and signs,
// quasi-static rates, walls, rolling, input checks.
#include <gtest/gtest.h>

#include <cmath>

#include "contact_fixture.hpp"

using namespace cohdem;
using namespace cohdem::testing;

TEST(ContactDriver, ColumnsIncludeModelState) {
  auto m = one_pair_model("mepa", "none", pset({{"k1", 1e5}, {"k2", 5e5}, {"mu", 0.3}}));
  EXPECT_EQ(driver_columns(*m), (std::vector<std::string>{"delta", "xi", "theta", "phi", "fn", "ft", "mb", "mt", "a",
                                                          "contact", "dmax", "dp", "branch"}));
  auto h = one_pair_model("hertz_mindlin", "none", pset({{"e", 0.5}, {"mu", 0.3}}));
  EXPECT_EQ(driver_columns(*h).size(), 10u);
  PathBuilder pb;
  pb.to(1e-5, 7);
  EXPECT_EQ(drive_contact(*m, 0, 0, DriverSetup{}, pb.table()).size(), 7u);
}

// Quasi-static by default: damping has no effect; with real rates it adds gamma d(delta)/dt.
TEST(ContactDriver, QuasiStaticRatesAndViscousDamping) {
  const double k1 = 1e5, gamma = 10.0, d = 1e-5, steps = 10;
  auto m = one_pair_model("mepa", "none", pset({{"k1", k1}, {"k2", 5e5}, {"n", 1}, {"mu", 0.3}, {"gamma_n", gamma}}));
  const int cf = column(*m, "fn");
  PathBuilder pb;
  pb.at(0.0).to(d, int(steps));
  DriverSetup s;
  const Rows q = drive_contact(*m, 0, 0, s, pb.table());
  EXPECT_NEAR(q.back()[cf], k1 * d, 1e-15 * k1 * d);
  s.quasi_static = false;
  s.dt = 1e-6;
  const Rows v = drive_contact(*m, 0, 0, s, pb.table());
  // v_n = -(d/steps)/dt (approaching), f_d = -gamma v_n.
  EXPECT_NEAR(v.back()[cf], k1 * d + gamma * (d / steps) / s.dt, 1e-12 * k1 * d);
}

// A wall is j with r_j = 0: R* = r_i (Hertz force with sqrt(r_i)).
TEST(ContactDriver, WallUsesParticleRadius) {
  const double E = 1e9, nu = 0.3, Es = E / (2 * (1 - nu * nu)), ri = 2e-3, d = 1e-6;
  auto m = one_pair_model("hertz_mindlin", "none", pset({{"e", 0.9}, {"mu", 0.3}}), E, nu, true);
  DriverSetup s;
  s.ri = ri;
  s.rj = 0;
  PathBuilder pb;
  pb.at(d);
  const Rows r = drive_contact(*m, 0, 0, s, pb.table());
  EXPECT_NEAR(r[0][column(*m, "fn")], 4.0 / 3.0 * Es * std::sqrt(ri) * std::pow(d, 1.5), 1e-12);
}

// Signs: ft, mb, mt resist the imposed xi, theta, phi (positive elastic slopes). Linear
// tangential spring kt = kt_ratio kn; EPSD rolling k_r = 2.25 kn mu_r^2 R*^2 (Ai et al. 2011).
TEST(ContactDriver, TangentialAndRollingKinematics) {
  const double kn = 1e5, d = 1e-5, mu_r = 0.3, Rs = 0.5e-3;
  auto m = one_pair_model("linear", "epsd", pset({{"kn", kn}, {"e", 0.5}, {"mu", 0.5}, {"mu_r", mu_r}}));
  const int cft = column(*m, "ft"), cmb = column(*m, "mb"), cmt = column(*m, "mt");
  PathBuilder pb;
  pb.at(d).go(PathBuilder::Xi, 1e-8, 5).go(PathBuilder::Theta, 1e-6, 5).go(PathBuilder::Phi, 1e-3, 5);
  const Rows r = drive_contact(*m, 0, 0, DriverSetup{}, pb.table());
  EXPECT_NEAR(r.back()[cft], 2.0 / 7.0 * kn * 1e-8, 1e-12 * kn * 1e-8);
  const double kr = 2.25 * kn * mu_r * mu_r * Rs * Rs;
  EXPECT_NEAR(r.back()[cmb], kr * 1e-6, 1e-12 * kr * 1e-6);
  EXPECT_EQ(r.back()[cmt], 0.0);  // no twisting model in this law
}

TEST(ContactDriver, RejectsBadPathAndSetup) {
  auto m = one_pair_model("mepa", "none", pset({{"k1", 1e5}, {"k2", 5e5}, {"mu", 0.3}}));
  PathTable p;
  p.delta = {0, 1e-6, 2e-6};
  p.xi = {0, 1e-9};
  EXPECT_THROW(drive_contact(*m, 0, 0, DriverSetup{}, p), InputError);
  p.xi.clear();
  DriverSetup s;
  s.ri = 0;
  EXPECT_THROW(drive_contact(*m, 0, 0, s, p), InputError);
}
