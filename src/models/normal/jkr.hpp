// JKR adhesive elastic contact (Johnson, Kendall & Roberts 1971; seed 001 Eqs. 1-4), for
// comparison with the plastic-cohesive models. In terms of the contact radius a:
//   P(a)     = 4 E* a^3 / (3 R*) - sqrt(8 pi w E* a^3)
//   alpha(a) = a^2 / R* - sqrt(2 pi w a / E*)
// w is the work of adhesion (J/m^2) = Gamma of the paper = 2 gamma for two equal surfaces
// (LAMMPS `jkr` takes gamma = w/2; EDEM's JKR "surface energy" is w).
//  - Snap-in: a contact forms when the surfaces touch (alpha > 0) and jumps to the JKR
//    curve: at alpha = 0+ the force is -(8/9) Pc.
//  - Pull-off (force control minimum): Pc = (3/2) pi w R*  at a_c^3 = 9 pi w R*^2 / (8 E*).
//  - Separation: the contact lives while alpha > alpha_s = -(3/4) (pi^2 w^2 R* / E*^2)^(1/3)
//    (where d alpha/da = 0; force there -(5/9) Pc), then breaks; reach() = -alpha_s.
// a(alpha) on the stable branch (a > a_s): x = sqrt(a) solves x^4 - R* c x - R* alpha = 0,
// c = sqrt(2 pi w / E*); Newton from an upper bound converges monotonically (convex, increasing).
// kn = 2 E* a (the Hertz stiffness at the current spot, used by damping and the time-step
// audit; the JKR slope dP/dalpha diverges at separation). Coulomb base: |Fn + 2 Pc| as in
// Thornton & Yin (1991) and LAMMPS (friction persists in tension).
#pragma once
#include <algorithm>
#include <array>
#include <cmath>

#include "models/normal/base.hpp"

namespace cohdem {

inline constexpr ParamSpec kWorkOfAdhesion =
    req("w", "J/m^2", 0, kInf, "work of adhesion (= 2 x surface energy of each surface; LAMMPS gamma = w/2)");

struct JkrNormal : NormalBase {
  struct Params { double Estar, w; };
  static constexpr bool kHertzianStiffness = true;  // kn = 2 E* a, E* of the material pair
  struct State { bool formed = false; };
  static void flip(State&) {}  ///< the same seen from either particle
  static constexpr std::array specs = {kWorkOfAdhesion};
  static Params make(const ParamSet& p, const PairMaterial& m) { return {m.Estar, p.get(specs[0])}; }

  static double pull_off(const Params& p, double rstar) { return 1.5 * M_PI * p.w * rstar; }
  /// Separation overlap alpha_s (<= 0).
  static double alpha_s(const Params& p, double rstar) {
    return -0.75 * std::cbrt(M_PI * M_PI * p.w * p.w * rstar / (p.Estar * p.Estar));
  }
  static double reach(const Params& p, double rstar) { return -alpha_s(p, rstar); }

  /// Contact radius on the stable branch for overlap alpha >= alpha_s.
  static double contact_radius(const Params& p, double R, double alpha) {
    if (p.w <= 0) return alpha > 0 ? std::sqrt(R * alpha) : 0.0;
    const double c = std::sqrt(2.0 * M_PI * p.w / p.Estar);
    const double Rc = R * c, Ra = R * alpha;
    // x^4 >= 2 R alpha and x^3 >= 2 R c give g(x) >= 0: start right of the root.
    double x = std::max(std::sqrt(std::sqrt(2.0 * std::max(Ra, 0.0))), std::cbrt(2.0 * Rc));
    for (int it = 0; it < 100; ++it) {
      const double x3 = x * x * x;
      const double gp = 4.0 * x3 - Rc;
      if (gp <= 0) break;  // at the separation point (double root)
      const double dx = (x3 * x - Rc * x - Ra) / gp;
      x -= dx;
      if (std::abs(dx) <= 1e-15 * x) break;
    }
    return x * x;
  }
  static double force(const Params& p, double R, double a) {
    const double a3 = a * a * a;
    return 4.0 * p.Estar * a3 / (3.0 * R) - std::sqrt(8.0 * M_PI * p.w * p.Estar * a3);
  }

  COHDEM_INLINE static void apply(const Params& p, const PairGeom& g, State& s, NormalOut& o) {
    const double R = g.rstar;
    if (!s.formed) {
      if (!(g.delta > 0)) { o.alive = false; return; }
      s.formed = true;  // snap-in
    } else if (g.delta <= alpha_s(p, R)) {
      o.alive = false;
      return;
    }
    o.alive = true;
    const double a = contact_radius(p, R, g.delta);
    o.a = a;
    o.f_el = force(p, R, a);
    o.kn = 2.0 * p.Estar * a;
    o.f_adh = pull_off(p, R);
  }
  template <class P>
  COHDEM_INLINE static double coulomb_base(const P&, const NormalOut& o, double) {
    return std::max(o.f_el + 2.0 * o.f_adh, 0.0);
  }
};

}  // namespace cohdem
