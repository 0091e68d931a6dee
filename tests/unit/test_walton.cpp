// Walton's plastic-cohesive model with bending and twisting (preset `walton`) against
// closed forms derived from its definition (src/models/normal/walton.hpp,
// src/models/walton/*.hpp).
//
// Derivations (equal spheres of radius R, R* = R/2, so 2R* = R):
//  - Loading (new maximum): F_R = K'_R alpha, K'_R = sf 2 pi Y R; with build-up the pull-off
//    grows with it, Fc = Fc0 + cf K'_R alpha, so f = (1 - cf) K'_R alpha - Fc0.
//  - Unloading from alpha_max: F_R = K2 (alpha - ap), ap = alpha_max (1 - K'_R / K2), then
//    F_R = 0 below ap: f = -Fc = -(Fc0 + cf K'_R alpha_max), the pull-off force, until
//    alpha <= -gap_c where the contact breaks. Two contacts loaded to a1 < a2 have pull-off
//    forces differing by cf K'_R (a2 - a1).
//  - Hertz unloading (K2 = 0): K2 = max(K'_R, 2 E* (3 F_Rmax flat R* / (4 E*))^(1/3)),
//    times 2/3 for the average slope.
//  - Bending spot: a'_b^2 = bf^2 (2R*) Fc / K'_R, B_max = Fc a'_b / 2 = bf sqrt(Fc^3/(8 pi sf Y)),
//    K_theta = c_theta K'_R a'_b^2 (= bf^2 R* Fc / 2 for c_theta = 1/4).
//  - An elastic-perfectly-plastic moment-angle spring cycled between +theta_a and -theta_a
//    (theta_a > theta_y = B_max / K_theta) traces a parallelogram of height 2 B_max and
//    width 2 (theta_a - theta_y): loop energy 4 B_max (theta_a - theta_y). Twisting: the same
//    with T_max = tf B_max and K_phi = K_theta.
//  - Tangential: K_f = kf_ratio K'_R (0.8), limit mu F_R with F_R = f + Fc the repulsion.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "contact_fixture.hpp"

using namespace cohdem;
using namespace cohdem::testing;

namespace {

constexpr double R = 1e-6, E = 1e10, nu = 0.3, Y = 1e8, Fc0 = 1e-8, mu = 0.3;

struct W {
  double sf = 1, cf = 0.1, bf = 1, tf = 1, K2 = 0, gap_c = 2e-11, k2_slope = 0;
  double KR() const { return sf * 2 * M_PI * Y * R; }
  ParamSet params() const {
    return pset({{"Y", Y}, {"sf", sf}, {"Fc0", Fc0}, {"cf", cf}, {"bf", bf}, {"tf", tf}, {"K2", K2},
                 {"gap_c", gap_c}, {"mu", mu}, {"k2_slope", k2_slope}});
  }
  std::unique_ptr<ContactModel> model(bool wall = false) const {
    return one_pair_model("walton", "none", params(), E, nu, wall);
  }
};

struct Cols {
  int d, fn, ft, mb, mt, amax, ap, Fc, contact, th, ph, xi;
  explicit Cols(const ContactModel& m)
      : d(column(m, "delta")), fn(column(m, "fn")), ft(column(m, "ft")), mb(column(m, "mb")),
        mt(column(m, "mt")), amax(column(m, "amax")), ap(column(m, "ap")), Fc(column(m, "Fc")),
        contact(column(m, "contact")), th(column(m, "theta")), ph(column(m, "phi")), xi(column(m, "xi")) {}
};

DriverSetup spheres() {
  DriverSetup s;
  s.ri = s.rj = R;
  return s;
}

}  // namespace

TEST(WaltonNormal, PlasticLoadingElasticUnloadingPullOff) {
  W w;
  w.K2 = 5 * w.KR();
  auto m = w.model();
  const Cols k(*m);
  const double amax = 1e-10, KR = w.KR();
  PathBuilder pb;
  pb.at(0.0).to(amax, 1000);
  const size_t i_max = pb.size() - 1;
  pb.to(-2 * w.gap_c, 4000);
  const Rows r = drive_contact(*m, 0, 0, spheres(), pb.table());
  const double fs = KR * amax;  // force scale; tolerances 1e-12 of it are rounding
  for (size_t i = 1; i <= i_max; ++i)
    ASSERT_NEAR(r[i][k.fn], (1 - w.cf) * KR * r[i][k.d] - Fc0, 1e-12 * fs) << "loading row " << i;
  const double Fc = Fc0 + w.cf * KR * amax, ap = amax * (1 - KR / w.K2);
  EXPECT_NEAR(r[i_max][k.Fc], Fc, 1e-12 * Fc);
  EXPECT_NEAR(r[i_max][k.ap], ap, 1e-12 * amax);
  bool saw_plateau = false;
  for (size_t i = i_max + 1; i < r.size(); ++i) {
    const double d = r[i][k.d];
    if (d <= -w.gap_c) {
      EXPECT_EQ(r[i][k.contact], 0) << "row " << i;
      EXPECT_EQ(r[i][k.fn], 0);
    } else if (d > ap) {
      EXPECT_NEAR(r[i][k.fn], w.K2 * (d - ap) - Fc, 1e-12 * fs) << "row " << i;
    } else {
      EXPECT_NEAR(r[i][k.fn], -Fc, 1e-12 * fs) << "row " << i;  // pull-off plateau
      saw_plateau = true;
    }
  }
  EXPECT_TRUE(saw_plateau);
  EXPECT_EQ(m->reach(0, 0, R / 2), w.gap_c);
}

TEST(WaltonNormal, PullOffGrowsWithLargestLoad) {
  W w;
  w.K2 = 5 * w.KR();
  auto m = w.model();
  const Cols k(*m);
  double pull[2];
  const double am[2] = {1e-10, 3e-10};
  for (int c = 0; c < 2; ++c) {
    PathBuilder pb;
    pb.at(0.0).to(am[c], 100).to(-0.5 * w.gap_c, 1000);
    const Rows r = drive_contact(*m, 0, 0, spheres(), pb.table());
    pull[c] = 0;
    for (const auto& row : r) pull[c] = std::min(pull[c], row[k.fn]);
    EXPECT_NEAR(-pull[c], Fc0 + w.cf * w.KR() * am[c], 1e-12 * Fc0);
  }
  EXPECT_NEAR(pull[0] - pull[1], w.cf * w.KR() * (am[1] - am[0]), 1e-12 * Fc0);
  std::printf("pull-off %.6e N -> %.6e N (cf K'_R d alpha = %.6e N)\n", -pull[0], -pull[1],
              w.cf * w.KR() * (am[1] - am[0]));
}

TEST(WaltonNormal, HertzianUnloadingSlopeAndWallRadius) {
  const double Es = E / (2 * (1 - nu * nu));
  for (double slope : {0.0, 1.0}) {
    W w;
    w.k2_slope = slope;
    auto m = w.model();
    const Cols k(*m);
    const double KR = w.KR();
    for (double amax : {1e-8, 1e-10}) {
      const double k2h = 2 * Es * std::cbrt(3 * KR * amax * 2 * (R / 2) / (4 * Es)) * (slope ? 2.0 / 3.0 : 1.0);
      const double K2 = std::max(k2h, KR);
      PathBuilder pb;
      pb.at(0.0).to(amax, 10).at(0.99 * amax);
      const Rows r = drive_contact(*m, 0, 0, spheres(), pb.table());
      const double s = (r[11][k.fn] - r[10][k.fn]) / (r[11][k.d] - r[10][k.d]);
      EXPECT_NEAR(s, K2, 1e-9 * K2) << "amax " << amax << " slope " << slope;
      std::printf("amax=%.0e k2_slope=%g: K2 = %.6e N/m (Hertz %.6e, K'_R %.6e)\n", amax, slope, s, k2h, KR);
    }
  }
  // Sphere on a wall: R* = R, truncation radius a^2 = 2 R alpha, K'_R = 4 pi Y R.
  W w;
  auto m = w.model(true);
  const Cols k(*m);
  DriverSetup s;
  s.ri = R;
  s.rj = 0;
  PathBuilder pb;
  pb.at(1e-10);
  const Rows r = drive_contact(*m, 0, 0, s, pb.table());
  EXPECT_NEAR(r[0][k.fn], (1 - w.cf) * 4 * M_PI * Y * R * 1e-10 - Fc0, 1e-12 * Fc0);
}

namespace {

// Drives a moment-angle cycle 0 -> +a -> -a -> +a on `col` at a fixed overlap and returns
// the rows with the index where the closed loop starts (the first +a).
Rows angle_cycle(const ContactModel& m, PathBuilder::Col col, double a, int N, double amax, size_t& i_loop,
                 size_t& i_start) {
  PathBuilder pb;
  pb.at(0.0).to(amax, 100).to(0.9 * amax, 10);
  i_start = pb.size() - 1;
  pb.go(col, a, N);
  i_loop = pb.size() - 1;
  pb.go(col, -a, 2 * N).go(col, a, 2 * N);
  return drive_contact(m, 0, 0, spheres(), pb.table());
}

}  // namespace

TEST(WaltonModes, BendingMomentAngleLoop) {
  W w;
  w.K2 = 5 * w.KR();
  w.sf = 0.5;  // factors off 1 so that their placement is tested
  w.bf = 2.0;
  auto m = w.model();
  const Cols k(*m);
  const double amax = 1e-10, KRp = w.KR(), Fc = Fc0 + w.cf * KRp * amax;
  const double ab = w.bf * std::sqrt(2 * (R / 2) * Fc / KRp);
  const double Bmax = Fc * ab / 2, Kth = 0.25 * KRp * ab * ab;
  EXPECT_NEAR(Bmax, w.bf * std::sqrt(Fc * Fc * Fc / (8 * M_PI * w.sf * Y)), 1e-12 * Bmax);  // paper's form
  EXPECT_NEAR(Kth, w.bf * w.bf * (R / 2) * Fc / 2, 1e-12 * Kth);
  const double thy = Bmax / Kth, tha = 3 * thy;
  const int N = 2000;
  size_t i_loop, i0;
  const Rows r = angle_cycle(*m, PathBuilder::Theta, tha, N, amax, i_loop, i0);
  // Elastic slope (first step), plastic limit, elastic unloading slope at the reversal.
  EXPECT_NEAR(r[i0 + 1][k.mb] / r[i0 + 1][k.th], Kth, 1e-9 * Kth);
  EXPECT_NEAR(r[i_loop][k.mb], Bmax, 1e-12 * Bmax);
  EXPECT_NEAR((r[i_loop][k.mb] - r[i_loop + 1][k.mb]) / (r[i_loop][k.th] - r[i_loop + 1][k.th]), Kth, 1e-9 * Kth);
  double mmin = 0;
  for (const auto& row : r) {
    mmin = std::min(mmin, row[k.mb]);
    ASSERT_EQ(row[k.mt], 0.0);  // bending does not twist
  }
  EXPECT_NEAR(mmin, -Bmax, 1e-12 * Bmax);
  // Loop energy; the trapezoid rule is exact on the straight pieces and errs by at most
  // h^2 K_theta / 8 at each of the two yield corners between rows: ~2e-8 of the loop here.
  const double Wl = path_work(r, k.th, k.mb, i_loop, r.size() - 1), We = 4 * Bmax * (tha - thy);
  EXPECT_NEAR(Wl, We, 1e-6 * We);
  std::printf("bending: K_theta = %.6e N m/rad, B_max = %.6e N m, loop W = %.10e J (exp %.10e, rel %.1e)\n", Kth, Bmax, Wl, We,
              Wl / We - 1);
}

TEST(WaltonModes, TwistingMomentAngleLoop) {
  W w;
  w.K2 = 5 * w.KR();
  w.tf = 0.5;
  auto m = w.model();
  const Cols k(*m);
  const double amax = 1e-10, KRp = w.KR(), Fc = Fc0 + w.cf * KRp * amax;
  const double ab = w.bf * std::sqrt(2 * (R / 2) * Fc / KRp);
  const double Tmax = w.tf * Fc * ab / 2, Kphi = 0.25 * KRp * ab * ab;
  const double phy = Tmax / Kphi, pha = 4 * phy;
  const int N = 2000;
  size_t i_loop, i0;
  const Rows r = angle_cycle(*m, PathBuilder::Phi, pha, N, amax, i_loop, i0);
  EXPECT_NEAR(r[i0 + 1][k.mt] / r[i0 + 1][k.ph], Kphi, 1e-9 * Kphi);
  EXPECT_NEAR(r[i_loop][k.mt], Tmax, 1e-12 * Tmax);
  EXPECT_NEAR((r[i_loop][k.mt] - r[i_loop + 1][k.mt]) / (r[i_loop][k.ph] - r[i_loop + 1][k.ph]), Kphi, 1e-9 * Kphi);
  for (const auto& row : r) ASSERT_EQ(row[k.mb], 0.0);  // twisting does not bend
  const double Wl = path_work(r, k.ph, k.mt, i_loop, r.size() - 1), We = 4 * Tmax * (pha - phy);
  EXPECT_NEAR(Wl, We, 1e-6 * We);
  std::printf("twisting: K_phi = %.6e N m/rad, T_max = %.6e N m, loop W = %.10e J (exp %.10e, rel %.1e)\n", Kphi, Tmax, Wl,
              We, Wl / We - 1);
}

// bf = 0 (a point contact) switches bending and twisting off: along a path that bends,
// twists and slides, both moments stay exactly zero while the normal and tangential forces
// are those of the default bf = 1 (the moments do not feed back on them).
TEST(WaltonModes, ZeroWidenFactorRemovesMoments) {
  W on, off;
  on.K2 = off.K2 = 5 * on.KR();
  off.bf = 0;
  const auto m_on = on.model(), m_off = off.model();
  const Cols k(*m_on);
  const double amax = 1e-10;
  PathBuilder pb;
  pb.at(0.0).to(amax, 100).to(0.9 * amax, 10);
  pb.go(PathBuilder::Theta, 1e-2, 200).go(PathBuilder::Phi, 1e-2, 200).go(PathBuilder::Xi, 1e-10, 100);
  pb.go(PathBuilder::Theta, -1e-2, 200).go(PathBuilder::Phi, -1e-2, 200).to(-2 * on.gap_c, 100);
  const Rows a = drive_contact(*m_on, 0, 0, spheres(), pb.table());
  const Rows b = drive_contact(*m_off, 0, 0, spheres(), pb.table());
  ASSERT_EQ(a.size(), b.size());
  double mb_on = 0, mt_on = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(b[i][k.mb], 0.0) << "row " << i;
    ASSERT_EQ(b[i][k.mt], 0.0) << "row " << i;
    ASSERT_EQ(b[i][k.fn], a[i][k.fn]) << "row " << i;
    ASSERT_EQ(b[i][k.ft], a[i][k.ft]) << "row " << i;
    ASSERT_EQ(b[i][k.contact], a[i][k.contact]) << "row " << i;
    mb_on = std::max(mb_on, std::abs(a[i][k.mb]));
    mt_on = std::max(mt_on, std::abs(a[i][k.mt]));
  }
  EXPECT_GT(mb_on, 0.0);  // the path does bend and twist the bf = 1 contact
  EXPECT_GT(mt_on, 0.0);
}

TEST(WaltonModes, TangentialStiffnessAndFrictionLimit) {
  W w;
  w.K2 = 5 * w.KR();
  auto m = w.model();
  const Cols k(*m);
  const double amax = 1e-10, KR = w.KR(), Kf = 0.8 * KR, xi1 = 1e-14;
  PathBuilder pb;
  pb.at(0.0).to(amax, 100).to(0.9 * amax, 10).go(PathBuilder::Xi, xi1, 10);
  const size_t i_el = pb.size() - 1;
  pb.go(PathBuilder::Xi, 1e-9, 100);
  const Rows r = drive_contact(*m, 0, 0, spheres(), pb.table());
  EXPECT_NEAR(r[i_el][k.ft] / xi1, Kf, 1e-9 * Kf);
  const double FR = w.K2 * (0.9 * amax - amax * (1 - KR / w.K2));  // repulsion at 0.9 amax
  EXPECT_NEAR(r[i_el][k.fn] + r[i_el][k.Fc], FR, 1e-12 * FR);
  EXPECT_NEAR(r.back()[k.ft], mu * FR, 1e-12 * FR);
}

// The bending spring moment turns with the contact: rigid rotation of the pair (w_i = w_j)
// by 90 degrees about the tangent keeps it in the tangent plane with its magnitude.
TEST(WaltonModes, BendingHistoryRotatesWithContact) {
  W w;
  w.K2 = 5 * w.KR();
  auto m = w.model();
  std::vector<std::byte> st(m->state_size(), std::byte{0});
  PairGeom g;
  g.n = {0, 0, 1};
  g.ri = g.rj = R;
  g.rstar = R / 2;
  g.mi = g.mj = 1e-15;
  g.mstar = 0.5e-15;
  g.Ii = g.Ij = 1e-27;
  g.dt = 1.0;
  g.delta = 1e-10;
  PairForce out;
  ASSERT_TRUE(m->evaluate(0, 0, g, st.data(), out));
  g.wrel = {0, 1e-4, 0};  // small bending about e_y (elastic)
  ASSERT_TRUE(m->evaluate(0, 0, g, st.data(), out));
  const double M0 = norm(out.mr);
  ASSERT_GT(M0, 0);
  ASSERT_NEAR(out.mr.y / M0, -1.0, 1e-14);
  g.wrel = {};
  const int steps = 900;
  for (int s = 1; s <= steps; ++s) {
    const double psi = 0.5 * M_PI * s / steps;
    g.n = {0, -std::sin(psi), std::cos(psi)};
    ASSERT_TRUE(m->evaluate(0, 0, g, st.data(), out));
  }
  EXPECT_NEAR(norm(out.mr), M0, 1e-12 * M0);
  EXPECT_NEAR(dot(out.mr, g.n), 0.0, 1e-12 * M0);
  EXPECT_NEAR(out.mr.z, -M0, 1e-9 * M0);  // e_y turned into e_z
}

TEST(WaltonRegistry, RollingSlotIsBending) {
  try {
    make_contact_model("walton", "epsd", "case.toml", 7);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "contact.rolling");
  }
  auto m = make_contact_model("walton", "none");
  std::vector<std::string> keys;
  for (const auto& s : m->specs()) keys.push_back(s.name);
  for (const char* want : {"Fc0", "Y", "mu", "cf", "sf", "bf", "tf", "K2", "c_theta"})
    EXPECT_NE(std::find(keys.begin(), keys.end(), want), keys.end()) << want;
  EXPECT_EQ(m->state_names(), (std::vector<std::string>{"amax", "ap", "Fc"}));
}
