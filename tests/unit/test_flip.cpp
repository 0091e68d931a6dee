// Newton's third law from either side of a contact, with a history carried across.
//
// A pair's history is kept as seen from the particle that holds the pair's row in the
// neighbor list (the one with the lower index). A re-sort can reverse that order; the list
// then rewrites the history as seen from the other particle (ContactModel::flip_state, each
// sub-model's flip). That is right only if the law, evaluated from j with the flipped history,
// gives j the opposite of the force on i and the torques exchanged, at every later step.
//
// For every preset and rolling choice: one contact is driven along a path (loading past the
// elastic range, unloading into adhesion for the adhesive laws, sliding, rolling and twisting
// all the while), evaluated from i. On the way in, when the springs are loaded, its history is
// flipped and a second copy continues from j's side with the mirrored geometry (n, v_t and
// omega_i - omega_j change sign; radii, masses and inertias exchange). The two must stay equal
// and opposite to the last step. The law's operations are antisymmetric term by term
// (negations and exchanged sums are exact in floating point), so the tolerance is a few
// rounding units of the force scale (1e-12 relative; a wrong sign in a flip is an O(1) error).
// Negative control: continuing without the flip must break the law for the laws with a spring.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "contact_fixture.hpp"

using namespace cohdem;
using namespace cohdem::testing;

namespace {

struct Case {
  std::string model, rolling;
  ParamSet ps;
};

std::vector<Case> cases() {
  std::vector<std::pair<std::string, ParamSet>> base = {
      {"linear", pset({{"kn", 2e4}, {"e", 0.5}, {"mu", 0.4}, {"damp_t", 0.5}})},
      {"hertz_mindlin", pset({{"e", 0.5}, {"mu", 0.4}})},
      {"mepa", pset({{"k1", 2e6}, {"k2", 1e7}, {"kadh", 5e5}, {"n", 1.5}, {"gamma_n", 0.5}, {"mu", 0.4}})},
      {"luding", pset({{"k1", 2e4}, {"k2", 1e5}, {"kc", 5e3}, {"phi_f", 0.05}, {"gamma_n", 0.5}, {"mu", 0.4}})},
      {"eepa", pset({{"k1", 2e6}, {"lambda_p", 0.6}, {"kadh", 5e5}, {"n", 1.5}, {"x", 1.5}, {"beta_n", 0.1},
                     {"mu", 0.4}})},
      {"jkr", pset({{"w", 0.05}, {"e", 0.5}, {"mu", 0.4}})},
      {"dmt", pset({{"w", 0.05}, {"e", 0.5}, {"mu", 0.4}})},
      {"walton", pset({{"Y", 5e5}, {"Fc0", 2e-3}, {"cf", 0.2}, {"beta_n", 0.1}, {"mu", 0.4}, {"bf", 1.0},
                       {"tf", 1.0}})},
  };
  std::vector<Case> v;
  for (auto& [m, ps] : base)
    for (const char* r : {"none", "epsd", "cdt", "sds"}) {
      if (m == "walton" && std::string(r) != "none") continue;
      ParamSet p = ps;
      if (std::string(r) != "none") p.set("mu_r", 0.1);
      if (std::string(r) == "epsd") p.set("eta_r", 0.3);
      if (std::string(r) == "sds") {
        p.set("k_r", 1e4);
        p.set("gamma_r", 0.01);
      }
      v.push_back({m, r, p});
    }
  return v;
}

/// The contact at step s of the path, seen from i (mirror = false) or from j.
PairGeom geom(int s, bool mirror, double dmax) {
  const double ri = 1.0e-3, rj = 1.6e-3, rho = 2500;
  const double mi = rho * 4.0 / 3.0 * M_PI * ri * ri * ri, mj = rho * 4.0 / 3.0 * M_PI * rj * rj * rj;
  const double t = double(s) / 400.0;
  // Overlap: load to dmax, unload to -0.02 dmax (adhesive laws hold on), reload to 0.6 dmax.
  const double d = t < 0.35 ? dmax * t / 0.35 : t < 0.6 ? dmax * (1 - 1.02 * (t - 0.35) / 0.25) : dmax * (-0.02 + 0.62 * (t - 0.6) / 0.4);
  // The normal turns slowly (the springs are rotated with it).
  const double a = 0.4 * t, b = 0.25 * std::sin(3 * t);
  const Vec3 n = normalized(Vec3{std::cos(a) * std::cos(b), std::sin(a) * std::cos(b), std::sin(b)});
  const Vec3 u = normalized(cross(n, Vec3{0.3, -0.2, 1.0}));
  const Vec3 w = cross(n, u);
  PairGeom g;
  g.delta = d;
  g.ri = ri;
  g.rj = rj;
  g.rstar = ri * rj / (ri + rj);
  g.mi = mi;
  g.mj = mj;
  g.mstar = mi * mj / (mi + mj);
  g.Ii = 0.4 * mi * ri * ri;
  g.Ij = 0.4 * mj * rj * rj;
  g.n = n;
  g.vn = -0.02 * std::cos(7 * t);
  // Sliding back and forth, with a turning direction; rolling and twisting rates.
  g.vt = u * (0.05 * std::sin(11 * t)) + w * (0.03 * std::cos(5 * t));
  g.wrel = u * (4.0 * std::cos(9 * t)) + w * (3.0 * std::sin(4 * t)) + n * (5.0 * std::sin(6 * t));
  g.dt = 2e-6;
  if (mirror) {
    std::swap(g.ri, g.rj);
    std::swap(g.mi, g.mj);
    std::swap(g.Ii, g.Ij);
    g.n = -g.n;
    g.vt = -g.vt;
    g.wrel = -g.wrel;
  }
  return g;
}

double max_abs(const Vec3& v) { return std::max({std::fabs(v.x), std::fabs(v.y), std::fabs(v.z)}); }

/// The step after which the history is flipped: on the way in, with the tangential, rolling
/// and bending springs loaded (later, on unloading into adhesion, the Coulomb limit of the
/// adhesive laws is zero and so are their springs: nothing to flip).
constexpr int kFlip = 100;

/// Drives the pair to step kFlip from i, flips (or not) and continues both sides; returns the
/// largest departure from the third law after the flip, relative to the largest force, and
/// the largest force.
std::pair<double, double> drive(const ContactModel& m, bool flip, double dmax) {
  std::vector<std::byte> si(m.state_size()), sj;
  double worst = 0, fmax = 0, lever = 0;
  PairForce fi, fj;
  for (int s = 0; s < 400; ++s) {
    const bool ai = m.evaluate(0, 0, geom(s, false, dmax), si.data(), fi);
    if (s == kFlip) {
      sj = si;
      if (flip) m.flip_state(sj.data());
    }
    if (s < kFlip) continue;
    // Step kFlip was evaluated from i only: j's copy starts from the state after it.
    if (s == kFlip) continue;
    const bool aj = m.evaluate(0, 0, geom(s, true, dmax), sj.data(), fj);
    EXPECT_EQ(ai, aj) << m.name() << " step " << s << ": the contact ends on one side only";
    if (!ai || !aj) continue;
    fmax = std::max(fmax, max_abs(fi.f));
    lever = 1.6e-3;
    worst = std::max({worst, max_abs(fi.f + fj.f), max_abs(fi.ti - fj.tj) / lever, max_abs(fi.tj - fj.ti) / lever});
  }
  return {fmax > 0 ? worst / fmax : 0.0, fmax};
}

}  // namespace

TEST(ContactLaws, ThirdLawFromEitherSideWithFlippedHistory) {
  for (const Case& c : cases()) {
    auto m = one_pair_model(c.model, c.rolling, c.ps);
    // An overlap of 2 % of R* (the hysteretic laws at a few times their elastic range).
    const auto [dev, fmax] = drive(*m, true, 0.02 * (1.0e-3 * 1.6e-3 / 2.6e-3));
    const std::string tag = c.model + " + " + c.rolling;
    ASSERT_GT(fmax, 0) << tag << ": the path never touched";
    EXPECT_LT(dev, 1e-12) << tag << ": j's force and torques are not the opposite of i's after the flip";
    std::printf("[ measured ] third law after a flipped history, %-22s max |f_i + f_j| / max |f| = %.2e (bound 1e-12)\n",
                tag.c_str(), dev);
    // Negative control: the history as it was (not flipped) must break it wherever the law
    // keeps a spring (every preset has a tangential one).
    const auto [bad, fb] = drive(*m, false, 0.02 * (1.0e-3 * 1.6e-3 / 2.6e-3));
    EXPECT_GT(bad, 1e-3) << tag << ": an unflipped history went unnoticed";
  }
}
