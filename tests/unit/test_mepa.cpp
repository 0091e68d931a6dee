// MEPA family (mepa, luding, eepa presets) against closed forms derived from the model
// definition (src/models/normal/mepa.hpp), for n = 1 and n = 3/2.
//
// Derivations. Write D = delta^n. The branches are linear in D:
//   f1 = k1 D,  f2 = k2 (D - Dp),  f3 = -kadh D.
// (a) Loading to dmax along f1 and switching to f2 there, f2(Dmax) = f1(Dmax):
//       Dp = Dmax (1 - k1/k2),  dp = dmax (1 - k1/k2)^(1/n).
// (b) Unloading along f2 meets f3 where k2 (D - Dp) = -kadh D:
//       Dmin = k2 Dp / (k2 + kadh),  delta_min = Dmin^(1/n),
//     and since fhys = max(f2, f3) below dp, the largest tension is at that corner:
//       fmin = -kadh Dmin = -kadh k2 Dp / (k2 + kadh).
// (c) With I(a, b) = int_a^b delta^n d delta = (b^(n+1) - a^(n+1)) / (n+1), the energy
//     dissipated by load (0 -> dmax), unload and separation (-> 0, where f3 = 0) is
//       W1 = k1 I(0, dmax) - [k2 (I(dmin, dmax) - Dp (dmax - dmin)) - kadh I(0, dmin)].
// (d) Without dp_shift a reload from a point delta_a on f3 retraces f3 to delta_min and then
//     f2 up to dmax: the sub-cycle delta_a -> dmax -> delta_a dissipates nothing.
//     With dp_shift the last point on f3 sets Dmax' = Da (k2 + kadh)/(k2 - k1) (f2 through
//     (Da, -kadh Da)), Dp' = Dmax' (1 - k1/k2); the reload follows k2 (D - Dp') up to
//     delta_1 = Dmax'^(1/n), then f1 to dmax, and the sub-cycle dissipates
//       Ws = k2 (I(da, d1) - Dp' (d1 - da)) + k1 I(d1, dmax)
//            - [k2 (I(dmin, dmax) - Dp (dmax - dmin)) - kadh I(da, dmin)].
// (e) Impact of two bodies (reduced mass m*, speed v0), no viscous damping: the particle
//     reaches dmax with k1 I(0, dmax) = m* v0^2 / 2 and leaves with the energy returned,
//       E_ret = k2 (I(dmin, dmax) - Dp (dmax - dmin)) - kadh I(0, dmin),
//     which is the minimum of the kinetic energy on the way out (the force is tensile from
//     dp to 0), so it separates iff E_ret > 0, with e^2 = E_ret / (k1 I(0, dmax)). Every term
//     scales as dmax^(n+1), so e and the sticking threshold do not depend on v0.
//     n = 1, kadh = 0: e^2 = (k2/k1)(dmax - dp)^2/dmax^2 = k1/k2.
//     n = 1: E_ret = dmax^2/2 [k1^2/k2 - kadh (k2 - k1)^2 / (k2 (k2 + kadh))], so the contact
//     sticks iff kadh >= k1^2 / (k2 - 2 k1) (and only if k2 > 2 k1).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "contact_fixture.hpp"
#include "models/normal/mepa.hpp"

using namespace cohdem;
using namespace cohdem::testing;

namespace {

struct Case {
  double n, k1, k2, kadh, dmax;
  double I(double a, double b) const { return (std::pow(b, n + 1) - std::pow(a, n + 1)) / (n + 1); }
  double Dmax() const { return std::pow(dmax, n); }
  double Dp() const { return Dmax() * (1 - k1 / k2); }
  double dp() const { return std::pow(Dp(), 1 / n); }
  double Dmin() const { return k2 * Dp() / (k2 + kadh); }
  double dmin() const { return std::pow(Dmin(), 1 / n); }
  double fmin() const { return -kadh * Dmin(); }
  double unload_work(double to) const {  // int_to^dmax f d delta along f2 then f3 (to <= dmin)
    return k2 * (I(dmin(), dmax) - Dp() * (dmax - dmin())) - kadh * I(to, dmin());
  }
  double W1() const { return k1 * I(0, dmax) - unload_work(0); }
  double fscale() const { return k1 * Dmax(); }
};

// Forces ~10 N at dmax = 0.1 mm for both exponents (k in N/m^n).
const Case kLinear{1.0, 1e5, 5e5, 2e5, 1e-4};
const Case kHertz{1.5, 1e7, 5e7, 2e7, 1e-4};

std::unique_ptr<ContactModel> mepa(const Case& c, double shift = 0, double coulomb_offset = 0) {
  return one_pair_model("mepa", "none",
                        pset({{"k1", c.k1}, {"k2", c.k2}, {"kadh", c.kadh}, {"n", c.n}, {"mu", 0.5},
                              {"dp_shift", shift}, {"coulomb_offset", coulomb_offset}}));
}

struct Cols {
  int d, fn, ft, dmax, dp, branch, contact;
  explicit Cols(const ContactModel& m)
      : d(column(m, "delta")), fn(column(m, "fn")), ft(column(m, "ft")), dmax(column(m, "dmax")),
        dp(column(m, "dp")), branch(column(m, "branch")), contact(column(m, "contact")) {}
};

DriverSetup setup() { return DriverSetup{}; }  // two 1 mm spheres, quasi-static

}  // namespace

class MepaExponent : public ::testing::TestWithParam<Case> {};

// (a), (b), (c): plastic overlap, largest tension, adhesive take-over, cycle dissipation.
TEST_P(MepaExponent, LoadUnloadSeparateClosedForms) {
  const Case c = GetParam();
  auto m = mepa(c);
  const Cols k(*m);
  const int N = 20000;
  PathBuilder pb;
  pb.at(0.0).to(c.dmax, N);  // starts at touching (no contact at delta = 0)
  const size_t i_max = pb.size() - 1;
  pb.to(c.dmin(), N);
  const size_t i_min = pb.size() - 1;
  pb.to(0.0, N).at(-1e-6);
  const Rows r = drive_contact(*m, 0, 0, setup(), pb.table());

  // Exact at the rows (the law is rate-independent): relative 1e-12 allows pow() rounding.
  EXPECT_NEAR(r[i_max][k.dp], c.dp(), 1e-12 * c.dmax);
  EXPECT_NEAR(r[i_max][k.fn], c.fscale(), 1e-12 * c.fscale());
  EXPECT_EQ(r[i_max][k.branch], 1);
  EXPECT_NEAR(r[i_min][k.fn], c.fmin(), 1e-10 * c.fscale());
  double fmin_seen = 0;
  for (const auto& row : r) fmin_seen = std::min(fmin_seen, row[k.fn]);
  EXPECT_NEAR(fmin_seen, c.fmin(), 1e-10 * c.fscale());
  // Adhesive branch takes over at delta_min: the rows either side.
  EXPECT_EQ(r[i_min - 1][k.branch], 2);
  EXPECT_EQ(r[i_min + 1][k.branch], 3);
  EXPECT_LT(r[i_min - 1][k.d] - c.dmin(), 1e-8);
  // Contact ends at zero overlap.
  EXPECT_EQ(r.back()[k.contact], 0);
  EXPECT_EQ(r[r.size() - 2][k.contact], 0);  // delta = 0 is not a contact
  EXPECT_EQ(r[r.size() - 3][k.contact], 1);

  // Trapezoid rule over the loop: exact for n = 1 (piecewise linear, corners on rows);
  // for n = 3/2 its error is ~(h/dmax)^2/12 ~ 2e-10 relative. Tolerance 1e-7.
  const double W = path_work(r, k.d, k.fn, 0, r.size() - 2);
  EXPECT_NEAR(W, c.W1(), 1e-7 * c.W1());
  std::printf("n=%.1f: dp=%.10e (exp %.10e), fmin=%.10e (exp %.10e), dmin=%.6e, W=%.10e (exp %.10e, rel %.1e)\n",
              c.n, r[i_max][k.dp], c.dp(), fmin_seen, c.fmin(), c.dmin(), W, c.W1(), W / c.W1() - 1);
}

// (d): repeating a sub-cycle inside the bounds dissipates nothing without dp_shift, and the
// closed-form Ws with it.
TEST_P(MepaExponent, RepeatedCycleDissipation) {
  const Case c = GetParam();
  const double da = 0.5 * c.dmin();
  const int N = 20000;
  for (double shift : {0.0, 1.0}) {
    auto m = mepa(c, shift);
    const Cols k(*m);
    PathBuilder pb;
    pb.at(0.0).to(c.dmax, N).to(c.dmin(), N).to(da, N);
    const size_t i1 = pb.size() - 1;
    // Reload through the same points as the unloading (dmin, then dmax), so that the two
    // legs of a sub-cycle visit the same overlaps.
    pb.to(c.dmin(), N).to(c.dmax, N).to(c.dmin(), N).to(da, N);
    const size_t i2 = pb.size() - 1;
    pb.to(c.dmin(), N).to(c.dmax, N).to(c.dmin(), N).to(da, N);
    const size_t i3 = pb.size() - 1;
    const Rows r = drive_contact(*m, 0, 0, setup(), pb.table());
    const double w1 = path_work(r, k.d, k.fn, i1, i2), w2 = path_work(r, k.d, k.fn, i2, i3);
    if (shift == 0) {
      // Reload and unload legs visit the same rows with the same forces: the sums cancel
      // to rounding. Tolerance 1e-12 of the first-cycle dissipation.
      EXPECT_NEAR(w1, 0.0, 1e-12 * c.W1());
      EXPECT_NEAR(w2, 0.0, 1e-12 * c.W1());
      EXPECT_NEAR(r[i2][k.dp], c.dp(), 1e-12 * c.dmax);  // dp kept for the contact's life
      std::printf("n=%.1f no shift: sub-cycle W = %.3e, %.3e (first cycle %.3e)\n", c.n, w1, w2, c.W1());
    } else {
      const double Dmax2 = std::pow(da, c.n) * (c.k2 + c.kadh) / (c.k2 - c.k1);
      const double Dp2 = Dmax2 * (1 - c.k1 / c.k2), d1 = std::pow(Dmax2, 1 / c.n);
      const double Ws = c.k2 * (c.I(da, d1) - Dp2 * (d1 - da)) + c.k1 * c.I(d1, c.dmax) - c.unload_work(da);
      ASSERT_GT(Ws, 0);
      // One corner (delta_1) falls between rows: trapezoid error <= h^2 |jump of slope| / 8
      // ~ 1e-13 J against Ws ~ 1e-4 J; n = 3/2 curvature error ~1e-9 relative. Tol 1e-7.
      EXPECT_NEAR(w1, Ws, 1e-7 * Ws);
      EXPECT_NEAR(w2, Ws, 1e-7 * Ws);
      EXPECT_NEAR(r[i2][k.dp], std::pow(Dp2, 1 / c.n), 1e-12 * c.dmax);
      std::printf("n=%.1f dp_shift: sub-cycle W = %.10e, %.10e (exp %.10e, rel %.1e)\n", c.n, w1, w2, Ws, w1 / Ws - 1);
    }
  }
}

// Branch-by-branch table: unload into adhesion, reload, load past the old maximum, end the
// contact and start a new one. Expected values from (a), (b), (d); rows are jumps (the law
// is rate-independent, so only the visited points matter).
TEST_P(MepaExponent, BranchTable) {
  const Case c = GetParam();
  const double n = c.n, dmax = c.dmax, dp = c.dp(), dmin = c.dmin();
  const double lam = 1 - c.k1 / c.k2;
  auto D = [&](double d) { return std::pow(d, n); };
  auto f1 = [&](double d) { return c.k1 * D(d); };
  auto f2 = [&](double d, double Dp) { return c.k2 * (D(d) - Dp); };
  auto f3 = [&](double d) { return -c.kadh * D(d); };
  const double dmid = 0.5 * (dp + dmin);
  const double d4 = 0.5 * dmin, d5 = 0.25 * dmin, d6 = 0.75 * dmin;
  // Shifted history: f2 through the last point on f3.
  const double Dmax5 = D(d5) * (c.k2 + c.kadh) / (c.k2 - c.k1);
  ASSERT_LT(Dmax5, D(d6));  // with shift the reload at d6 is already virgin loading
  struct Row { double d; int b_keep; double f_keep; int b_shift; double f_shift; double dp_keep, dp_shift; };
  const double Dp = c.Dp();
  const Row rows[] = {
      {0.5 * dmax, 1, f1(0.5 * dmax), 1, f1(0.5 * dmax), 0.5 * dmax * std::pow(lam, 1 / n), 0.5 * dmax * std::pow(lam, 1 / n)},
      {dmax, 1, f1(dmax), 1, f1(dmax), dp, dp},
      {0.9 * dmax, 2, f2(0.9 * dmax, Dp), 2, f2(0.9 * dmax, Dp), dp, dp},
      {dmid, 2, f2(dmid, Dp), 2, f2(dmid, Dp), dp, dp},
      {d4, 3, f3(d4), 3, f3(d4), dp, std::pow(D(d4) * (c.k2 + c.kadh) / c.k2, 1 / n)},
      {d5, 3, f3(d5), 3, f3(d5), dp, std::pow(D(d5) * (c.k2 + c.kadh) / c.k2, 1 / n)},
      {d6, 3, f3(d6), 1, f1(d6), dp, d6 * std::pow(lam, 1 / n)},
      {dmid, 2, f2(dmid, Dp), 1, f1(dmid), dp, dmid * std::pow(lam, 1 / n)},
      {0.95 * dmax, 2, f2(0.95 * dmax, Dp), 1, f1(0.95 * dmax), dp, 0.95 * dmax * std::pow(lam, 1 / n)},
      {1.2 * dmax, 1, f1(1.2 * dmax), 1, f1(1.2 * dmax), 1.2 * dp, 1.2 * dp},
      {1.1 * dmax, 2, f2(1.1 * dmax, D(1.2 * dp)), 2, f2(1.1 * dmax, D(1.2 * dp)), 1.2 * dp, 1.2 * dp},
      {0.0, 0, 0.0, 0, 0.0, 0.0, 0.0},  // contact ends, history reset
      {0.5 * dmax, 1, f1(0.5 * dmax), 1, f1(0.5 * dmax), 0.5 * dp, 0.5 * dp},
  };
  for (double shift : {0.0, 1.0}) {
    auto m = mepa(c, shift);
    const Cols k(*m);
    PathBuilder pb;
    for (const Row& w : rows) pb.at(w.d);
    const Rows r = drive_contact(*m, 0, 0, setup(), pb.table());
    for (size_t i = 0; i < std::size(rows); ++i) {
      const Row& w = rows[i];
      const bool s = shift != 0;
      EXPECT_EQ(r[i][k.branch], s ? w.b_shift : w.b_keep) << "row " << i << " shift " << s;
      EXPECT_NEAR(r[i][k.fn], s ? w.f_shift : w.f_keep, 1e-12 * c.fscale()) << "row " << i << " shift " << s;
      EXPECT_NEAR(r[i][k.dp], s ? w.dp_shift : w.dp_keep, 1e-12 * c.dmax) << "row " << i << " shift " << s;
    }
  }
}

// (e): two spheres collide without damping; velocity Verlet through ContactModel::evaluate.
namespace {

struct Impact {
  bool separated;
  double e;
};

Impact collide(const ContactModel& m, double R, double mass, double v0, double tc) {
  const double dt = tc / 5000;
  // Body i at +x moving left, body j at -x moving right; n = +x (from j to i).
  double xi = R + 1e-9, xj = -R - 1e-9, vi = -0.5 * v0, vj = 0.5 * v0, fi = 0;
  std::vector<std::byte> state(m.state_size(), std::byte{0});
  bool touched = false;
  auto force = [&]() {
    PairGeom g;
    g.n = {1, 0, 0};
    g.delta = 2 * R - (xi - xj);
    g.ri = g.rj = R;
    g.rstar = R / 2;
    g.mi = g.mj = mass;
    g.mstar = mass / 2;
    g.Ii = g.Ij = 0.4 * mass * R * R;
    g.vn = vi - vj;
    g.dt = dt;
    if (g.delta <= 0 && !touched) return 0.0;
    PairForce out;
    const bool alive = m.evaluate(0, 0, g, state.data(), out);
    if (alive) touched = true;
    return alive ? out.f.x : 0.0;
  };
  fi = force();
  for (double t = 0; t < 40 * tc; t += dt) {
    const double ai = fi / mass;
    xi += vi * dt + 0.5 * ai * dt * dt;
    xj += vj * dt - 0.5 * ai * dt * dt;
    const double fn = force();
    vi += 0.5 * (ai + fn / mass) * dt;
    vj -= 0.5 * (ai + fn / mass) * dt;
    fi = fn;
    if (touched && 2 * R - (xi - xj) < 0 && fi == 0) return {true, (vi - vj) / v0};
  }
  return {false, 0.0};
}

// Energy returned per unit dmax^(n+1), from (e).
double e_squared(const Case& c) {
  Case u = c;
  u.dmax = 1;
  return u.unload_work(0) / (u.k1 * u.I(0, 1));
}

}  // namespace

TEST_P(MepaExponent, ImpactRestitutionAndSticking) {
  Case c = GetParam();
  const double R = 1e-3, rho = 2500, mass = 4.0 / 3.0 * M_PI * R * R * R * rho, v0 = 0.2;
  // Contact time scale of the loading spring at the expected dmax.
  auto tc_of = [&](const Case& cc) {
    const double dm = std::pow((cc.n + 1) * 0.5 * mass * v0 * v0 / (2 * cc.k1), 1 / (cc.n + 1));
    return M_PI * std::sqrt(0.5 * mass / (cc.n * cc.k1 * std::pow(dm, cc.n - 1)));
  };
  // kadh = 0: n = 1 gives sqrt(k1/k2).
  c.kadh = 0;
  const double e_exp0 = std::sqrt(e_squared(c));
  if (c.n == 1.0) EXPECT_NEAR(e_exp0, std::sqrt(c.k1 / c.k2), 1e-14);
  const Impact a = collide(*mepa(c), R, mass, v0, tc_of(c));
  ASSERT_TRUE(a.separated);
  // Velocity Verlet with 5000 steps per contact time: the force is continuous with slope
  // jumps at dmax and dmin, energy error O((dt/tc)^2) ~ 1e-7; exit detection at the step
  // where the overlap turns negative (force already ~0 there). Tolerance 1e-4 relative.
  EXPECT_NEAR(a.e, e_exp0, 1e-4 * e_exp0);

  // Sticking threshold: E_ret(kadh*) = 0. n = 1: kadh* = k1^2 / (k2 - 2 k1); otherwise
  // bisection on the closed form (E_ret decreases with kadh).
  double lo = 0, hi = 100 * c.k2;
  for (int it = 0; it < 200; ++it) {
    Case t = c;
    t.kadh = 0.5 * (lo + hi);
    (e_squared(t) > 0 ? lo : hi) = t.kadh;
  }
  const double kstar = 0.5 * (lo + hi);
  if (c.n == 1.0) EXPECT_NEAR(kstar, c.k1 * c.k1 / (c.k2 - 2 * c.k1), 1e-12 * kstar);
  Case below = c, above = c;
  below.kadh = 0.8 * kstar;
  above.kadh = 1.2 * kstar;
  const double e_below = std::sqrt(e_squared(below));
  const Impact b = collide(*mepa(below), R, mass, v0, tc_of(below));
  ASSERT_TRUE(b.separated);
  EXPECT_NEAR(b.e, e_below, 1e-3 * e_below);  // smaller e: same absolute error, 1e-3 relative
  const Impact s = collide(*mepa(above), R, mass, v0, tc_of(above));
  EXPECT_FALSE(s.separated) << "kadh = 1.2 kadh* must stick";
  std::printf("n=%.1f: e(kadh=0) = %.8f (exp %.8f, rel %.1e); kadh* = %.6e; e(0.8 kadh*) = %.8f (exp %.8f, rel %.1e); "
              "1.2 kadh*: %s\n",
              c.n, a.e, e_exp0, a.e / e_exp0 - 1, kstar, b.e, e_below, b.e / e_below - 1,
              s.separated ? "separated" : "stuck");
}

INSTANTIATE_TEST_SUITE_P(N, MepaExponent, ::testing::Values(kLinear, kHertz),
                         [](const auto& info) { return info.param.n == 1.0 ? "linear" : "hertz"; });

// Tangential spring kt tied to k1, and the two Coulomb forms, for n = 3/2.
TEST(MepaTangential, StiffnessFormsAndCoulombLimits) {
  const Case c = kHertz;
  const double d0 = c.dmax, xi = 1e-9, mu = 0.5;
  const double expected[3] = {1.5 * c.k1 * std::sqrt(d0), c.k1 * std::sqrt(d0), c.k1};
  for (int form = 0; form < 3; ++form) {
    auto m = one_pair_model("mepa", "none", pset({{"k1", c.k1}, {"k2", c.k2}, {"n", 1.5}, {"mu", mu},
                                                  {"kt_form", double(form)}}));
    const Cols k(*m);
    PathBuilder pb;
    pb.to(d0, 10).go(PathBuilder::Xi, xi, 10);
    const Rows r = drive_contact(*m, 0, 0, setup(), pb.table());
    EXPECT_NEAR(r.back()[k.ft] / xi, expected[form], 1e-9 * expected[form]) << "kt_form " << form;
  }
  // Tension on the f2 branch (between dmin and dp): literal limit is 0, offset limit is
  // mu (f2 + kadh D) (the force above the adhesive bound).
  const double dmid = 0.5 * (c.dp() + c.dmin());
  const double f2 = c.k2 * (std::pow(dmid, 1.5) - c.Dp());
  ASSERT_LT(f2, 0);
  for (double off : {0.0, 1.0}) {
    auto m = mepa(c, 0, off);
    const Cols k(*m);
    PathBuilder pb;
    pb.to(c.dmax, 10).to(dmid, 10).go(PathBuilder::Xi, 1e-3, 10);  // far past sliding
    const Rows r = drive_contact(*m, 0, 0, setup(), pb.table());
    EXPECT_NEAR(r.back()[k.fn], f2, 1e-12 * c.fscale());
    const double lim = off ? mu * (f2 + c.kadh * std::pow(dmid, 1.5)) : 0.0;
    EXPECT_NEAR(r.back()[k.ft], lim, 1e-12 * c.fscale()) << "coulomb_offset " << off;
  }
}

// EEPA: the constant offset f0 is conservative (same dissipation, shifted forces); a separate
// adhesive exponent x moves delta_min to the root of k2 (delta^n - Dp) = -kadh delta^x.
TEST(Eepa, OffsetAndAdhesiveExponent) {
  const Case c = kHertz;
  const double f0 = -0.7, lp = 1 - c.k1 / c.k2;
  {
    auto m = one_pair_model("eepa", "none", pset({{"k1", c.k1}, {"lambda_p", lp}, {"kadh", c.kadh}, {"f0", f0},
                                                  {"mu", 0.5}}));
    const Cols k(*m);
    const int N = 20000;
    PathBuilder pb;
    pb.at(0.0).to(c.dmax, N);
    const size_t i_max = pb.size() - 1;
    pb.to(c.dmin(), N);
    const size_t i_min = pb.size() - 1;
    const double h = c.dmax / N;  // first and last steps equal: see the loop integral below
    pb.to(h, N).at(0.0);
    const Rows r = drive_contact(*m, 0, 0, setup(), pb.table());
    EXPECT_NEAR(r[1][k.fn], f0 + c.k1 * std::pow(r[1][k.d], 1.5), 1e-12);  // snap-in at f0
    EXPECT_NEAR(r[i_max][k.fn], f0 + c.fscale(), 1e-12 * c.fscale());
    EXPECT_NEAR(r[i_max][k.dp], c.dp(), 1e-12 * c.dmax);
    EXPECT_NEAR(r[i_min][k.fn], f0 + c.fmin(), 1e-10 * c.fscale());
    // Loop from delta = 0 back to delta = 0 (rows with no contact, fn = 0, at both ends):
    // the f0 terms cancel between the loading and unloading legs. The trapezoid rule smears
    // the jump to f0 at delta = 0 over the first and last segments; with equal lengths h the
    // two smears cancel, so W = W1 of the offset-free law (tolerance as above).
    const double W = path_work(r, k.d, k.fn, 0, r.size() - 1);
    EXPECT_NEAR(W, c.W1(), 1e-7 * c.W1());
  }
  {
    const double x = 1.0, kadh = 2e5;  // N/m^x
    auto m = one_pair_model("eepa", "none", pset({{"k1", c.k1}, {"lambda_p", lp}, {"kadh", kadh}, {"x", x},
                                                  {"mu", 0.5}}));
    const Cols k(*m);
    // delta_min: root of g(d) = k2 (d^1.5 - Dp) + kadh d in (0, dp) (g(0) < 0 < g(dp)).
    double lo = 0, hi = c.dp();
    for (int it = 0; it < 200; ++it) {
      const double mid = 0.5 * (lo + hi);
      (c.k2 * (std::pow(mid, 1.5) - c.Dp()) + kadh * mid < 0 ? lo : hi) = mid;
    }
    const double dmin = 0.5 * (lo + hi), fmin = -kadh * dmin;
    PathBuilder pb;
    pb.to(c.dmax, 100).to(dmin, 1000);
    const size_t i_min = pb.size() - 1;
    pb.to(0.0, 1000);
    const Rows r = drive_contact(*m, 0, 0, setup(), pb.table());
    EXPECT_NEAR(r[i_min][k.fn], fmin, 1e-9 * c.fscale());
    EXPECT_EQ(r[i_min - 1][k.branch], 2);
    EXPECT_EQ(r[i_min + 1][k.branch], 3);
    double fmin_seen = 0;
    for (const auto& row : r) fmin_seen = std::min(fmin_seen, row[k.fn]);
    EXPECT_NEAR(fmin_seen, fmin, 1e-9 * c.fscale());
  }
}

// EEPA with k1 = 0: Hertz coefficient 4/3 E* sqrt(R*) per contact, k2 = k1/(1 - lambda_p).
TEST(Eepa, HertzLoadingStiffness) {
  const double E = 1e9, nu = 0.3, lp = 0.6, R = 1e-3;
  auto m = one_pair_model("eepa", "none", pset({{"lambda_p", lp}, {"mu", 0.5}}), E, nu);
  const Cols k(*m);
  const double Es = E / (2 * (1 - nu * nu)), k1 = 4.0 / 3.0 * Es * std::sqrt(R / 2), d = 1e-5;
  PathBuilder pb;
  pb.to(d, 10).at(0.9 * d);
  const Rows r = drive_contact(*m, 0, 0, setup(), pb.table());
  EXPECT_NEAR(r[9][k.fn], k1 * std::pow(d, 1.5), 1e-12 * k1 * std::pow(d, 1.5));
  EXPECT_NEAR(r[9][k.dp], d * std::pow(lp, 1 / 1.5), 1e-12 * d);
  EXPECT_NEAR(r[10][k.fn], k1 / (1 - lp) * (std::pow(0.9 * d, 1.5) - lp * std::pow(d, 1.5)),
              1e-12 * k1 * std::pow(d, 1.5));
  // Bad inputs name their key.
  EXPECT_THROW(one_pair_model("eepa", "none", pset({{"lambda_p", 1.0}, {"mu", 0.5}})), InputError);
  try {
    one_pair_model("eepa", "none", pset({{"lambda_p", 0.5}, {"n", 1.2}, {"mu", 0.5}}));
    FAIL() << "k1 = 0 with n != 1.5 must be rejected";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "k1");
  }
}

// Luding: k2 grows linearly with dmax up to k2-hat at dmax_p = k2/(k2-k1) phi_f 2R*; the
// shift on f3 solves k2(Dm) D - (k2(Dm) - k1) Dm = -kc D with the growing k2.
TEST(Luding, GrowingUnloadingStiffnessAndShift) {
  const double k1 = 1e5, k2h = 5e5, kc = 1e5, phi = 0.05, R = 1e-3, Rs = R / 2;
  const double dmp = k2h / (k2h - k1) * phi * 2 * Rs;  // 6.25e-5 m
  auto m = one_pair_model("luding", "none",
                          pset({{"k1", k1}, {"k2", k2h}, {"kc", kc}, {"phi_f", phi}, {"mu", 0.5}}));
  const Cols k(*m);
  const double d1 = 0.5 * dmp, k2_1 = k1 + (k2h - k1) * 0.5;
  const double dp1 = d1 * (1 - k1 / k2_1);
  const double dmin1 = k2_1 * dp1 / (k2_1 + kc), da = 0.5 * dmin1;
  PathBuilder pb;
  pb.at(d1).at(0.5 * (dp1 + d1)).at(da).at(da * (1 + 1e-9)).at(2 * dmp).at(1.5 * dmp);
  const Rows r = drive_contact(*m, 0, 0, setup(), pb.table());
  EXPECT_NEAR(r[0][k.dp], dp1, 1e-12 * d1);
  EXPECT_NEAR(r[1][k.fn], k2_1 * (0.5 * (dp1 + d1) - dp1), 1e-12 * k1 * d1);
  // Shift from da on f3: the reported history satisfies the defining equation.
  EXPECT_EQ(r[2][k.branch], 3);
  const double Dm = r[2][k.dmax], k2m = k1 + (k2h - k1) * std::min(1.0, Dm / dmp);
  EXPECT_LT(Dm, d1);
  EXPECT_NEAR(k2m * (da - r[2][k.dp]), -kc * da, 1e-9 * kc * da);
  EXPECT_NEAR(r[2][k.dp], Dm * (1 - k1 / k2m), 1e-12 * d1);
  // Reload: continuous, now on the shifted f2 line.
  EXPECT_EQ(r[3][k.branch], 2);
  EXPECT_NEAR(r[3][k.fn], -kc * da, 1e-6 * kc * da);
  // Past the plastic limit k2 = k2-hat.
  EXPECT_NEAR(r[4][k.dp], 2 * dmp * (1 - k1 / k2h), 1e-12 * dmp);
  EXPECT_NEAR(r[5][k.fn], k2h * (1.5 * dmp - 2 * dmp * (1 - k1 / k2h)), 1e-12 * k1 * dmp);
}

TEST(MepaRegistry, BadInputsNameTheirKey) {
  try {
    one_pair_model("mepa", "none", pset({{"k1", 2e5}, {"k2", 1e5}, {"mu", 0.3}}));
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "k2");
  }
  try {
    one_pair_model("mepa", "none", pset({{"k1", 1e5}, {"k2", 2e5}, {"mu", 0.3}, {"kt_form", 0.5}}));
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "kt_form");
  }
  // Rolling is chosen at run time; keys of the chosen rolling model are part of the law.
  auto m = make_contact_model("mepa", "epsd");
  bool has_mu_r = false;
  for (const auto& s : m->specs()) has_mu_r = has_mu_r || std::string(s.name) == "mu_r";
  EXPECT_TRUE(has_mu_r);
  EXPECT_EQ(m->state_names(), (std::vector<std::string>{"dmax", "dp", "branch"}));
}

// The same impact through the bulk force kernel (System, neighbor list, contact history):
// e = sqrt(k1/k2) for n = 1, kadh = 0, and a contact that sticks for kadh = 1.2 kadh*.
#include "physics/fixture.hpp"

TEST(MepaSystem, ImpactThroughForceKernel) {
  const double r = 1e-3, rho = 2500, k1 = 1e4, k2 = 5e4, v0 = 0.2;
  const double mass = 4.0 / 3.0 * M_PI * r * r * r * rho, tc = M_PI * std::sqrt(0.5 * mass / k1);
  for (double kadh : {0.0, 1.2 * k1 * k1 / (k2 - 2 * k1)}) {
    auto s = make_system({{"ore", rho, 1e9, 0.3}}, "mepa", "none",
                         params({{"k1", k1}, {"k2", k2}, {"kadh", kadh}, {"n", 1}, {"mu", 0.0}}), tc / 1000,
                         {0, 0, 0}, 1e-4);
    s->add_particle(0, r, {-r - 1e-7, 0, 0}, {0.5 * v0, 0, 0});
    s->add_particle(0, r, {r + 1e-7, 0, 0}, {-0.5 * v0, 0, 0});
    s->prepare();
    s->run(5000);  // 5 contact times
    const double e = (s->particles.v[1].x - s->particles.v[0].x) / v0;
    if (kadh == 0) {
      // dt = tc/1000: energy error O((dt/tc)^2) ~ 1e-6, tolerance 1e-3 as above.
      EXPECT_NEAR(e, std::sqrt(k1 / k2), 1e-3 * std::sqrt(k1 / k2));
      EXPECT_EQ(s->pair_contact_count(), 0u);
      std::printf("System: e = %.8f (exp %.8f, rel %.1e)\n", e, std::sqrt(k1 / k2), e / std::sqrt(k1 / k2) - 1);
    } else {
      EXPECT_EQ(s->pair_contact_count(), 1u) << "kadh = 1.2 kadh*: the pair must stay in contact";
    }
  }
}

// Fixed stiffnesses (MEPA; Luding with phi_f = 0; EEPA with a given k1) take a per-pair
// constant 1 - k1/k2 and skip the per-contact stiffness reading; the general path (Luding's
// growing k2, EEPA's Hertz k1) is tested above against closed forms. The two must agree to
// the bit on the same path: the fast path is the same arithmetic, done once. The path loads,
// unloads through f2 into the adhesive branch, reloads past the old maximum and ends.
TEST(MepaFixedStiffness, FastPathIsTheGeneralPathBitForBit) {
  const PairMaterial mat = PairMaterial::make(1e9, 0.3, 1e9, 0.3, false);
  struct Set { const char* what; HystereticNormal::Params p; };
  std::vector<Set> sets;
  for (double n : {1.0, 1.5, 1.3})
    for (double shift : {0.0, 1.0})
      for (double off : {0.0, 1.0}) {
        const auto ps = pset({{"k1", 2e6}, {"k2", 1e7}, {"kadh", 3e5}, {"n", n}, {"dp_shift", shift},
                              {"coulomb_offset", off}});
        sets.push_back({"mepa", MepaNormal::make(ps, mat)});
      }
  sets.push_back({"luding", LudingNormal::make(pset({{"k1", 2e5}, {"k2", 1e6}, {"kc", 1e4}}), mat)});
  sets.push_back({"eepa", EepaNormal::make(pset({{"k1", 2e6}, {"lambda_p", 0.7}, {"kadh", 1e5}, {"x", 1.2},
                                                  {"f0", -0.01}}), mat)});
  const double dpath[] = {1e-5, 4e-5, 8e-5, 6e-5, 3e-5, 1e-5, 5e-6, 2e-6, 4e-6, 9e-5, 1.2e-4, 7e-5, 0.0, 2e-5};
  for (const Set& s : sets) {
    ASSERT_TRUE(s.p.fixed) << s.what;
    HystereticNormal::Params general = s.p;
    general.fixed = false;
    general.plastic = 0;  // not read by the general path: a wrong read shows up as Dp = 0
    HystereticNormal::State fast_s, gen_s;
    for (double d : dpath) {
      PairGeom g;
      g.delta = d;
      g.rstar = 5e-4;
      NormalOut a, b;
      HystereticNormal::apply(s.p, g, fast_s, a);
      HystereticNormal::apply(general, g, gen_s, b);
      const std::string at = std::string(s.what) + " n " + std::to_string(s.p.n) + " shift " +
                             std::to_string(s.p.shift) + " delta " + std::to_string(d);
      ASSERT_EQ(a.alive, b.alive) << at;
      if (!a.alive) {
        fast_s = gen_s = {};
        continue;
      }
      // EXPECT_EQ on doubles: bit-for-bit (the same operations on the same values).
      EXPECT_EQ(a.f_el, b.f_el) << at;
      EXPECT_EQ(a.kn, b.kn) << at;
      EXPECT_EQ(a.k_load, b.k_load) << at;
      EXPECT_EQ(a.f_adh, b.f_adh) << at;
      EXPECT_EQ(fast_s.Dmax, gen_s.Dmax) << at;
      EXPECT_EQ(fast_s.Dp, gen_s.Dp) << at;
      EXPECT_EQ(fast_s.branch, gen_s.branch) << at;
    }
  }
  // Luding with a growing k2 and EEPA with the Hertz k1 stay on the general path.
  EXPECT_FALSE(LudingNormal::make(pset({{"k1", 2e5}, {"k2", 1e6}, {"phi_f", 0.05}}), mat).fixed);
  EXPECT_FALSE(EepaNormal::make(pset({{"lambda_p", 0.7}}), mat).fixed);
}

// The tangential stiffness, read once per material pair (HystTangential::make), against its
// definition (kt_form 0: kt_ratio n k1 delta^(n-1); 1: kt_ratio k1 delta^(n-1); 2: kt_ratio
// k1, EEPA's Hertz k1 = 4/3 E* sqrt(R*); kt > 0: kt) for n = 1, 1.5 and 1.3. Tolerance 1e-15
// relative: the definition is evaluated here in another order (a few roundings).
TEST(MepaTangential, StiffnessReadingMatchesItsDefinition) {
  const PairMaterial mat = PairMaterial::make(1e9, 0.3, 1e9, 0.3, false);
  const double d = 3e-5, rstar = 5e-4, k1 = 2e6, ratio = 0.7;
  PairGeom g;
  g.delta = d;
  g.rstar = rstar;
  // The normal law's evaluation at delta = d (k_load), then the tangential stiffness.
  auto kt_of = [&]<class T>(const typename T::Params& tp) {
    HystereticNormal::State s;
    NormalOut no;
    HystereticNormal::apply(tp.np, g, s, no);
    return T::stiffness(tp, g, no);
  };
  using MepaT = HystTangential<MepaNormal>;
  using EepaT = HystTangential<EepaNormal>;
  for (double n : {1.0, 1.5, 1.3})
    for (int form = 0; form < 3; ++form) {
      const auto tp = MepaT::make(
          pset({{"k1", k1}, {"k2", 1e7}, {"n", n}, {"mu", 0.5}, {"kt_form", double(form)}, {"kt_ratio", ratio}}), mat);
      const double want = form == 0 ? ratio * n * k1 * std::pow(d, n - 1)
                                    : (form == 1 ? ratio * k1 * std::pow(d, n - 1) : ratio * k1);
      EXPECT_NEAR(kt_of.operator()<MepaT>(tp), want, 1e-15 * want) << "n " << n << " form " << form;
      const auto given = MepaT::make(
          pset({{"k1", k1}, {"k2", 1e7}, {"n", n}, {"mu", 0.5}, {"kt_form", double(form)}, {"kt", 1234.5}}), mat);
      EXPECT_EQ(kt_of.operator()<MepaT>(given), 1234.5) << "kt given, n " << n;
    }
  // EEPA with the Hertz k1 (k1 = 0, n = 1.5): kt_form 2 is kt_ratio 4/3 E* sqrt(R*) per contact.
  const auto tp = EepaT::make(pset({{"lambda_p", 0.7}, {"mu", 0.5}, {"kt_form", 2.0}, {"kt_ratio", ratio}}), mat);
  const double want = ratio * 4.0 / 3.0 * mat.Estar * std::sqrt(rstar);
  EXPECT_NEAR(kt_of.operator()<EepaT>(tp), want, 1e-15 * want);
}
