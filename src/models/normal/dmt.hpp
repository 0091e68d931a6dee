// DMT-style constant adhesion (Derjaguin, Muller & Toporov 1975): Hertz repulsion plus a
// constant attraction equal to the DMT pull-off force,
//   f = 4/3 E* sqrt(R*) delta^(3/2) - 2 pi w R*     for delta > 0,
// w the work of adhesion (J/m^2). The attraction acts only while the bodies overlap: the
// contact snaps in at delta = 0+ (force -2 pi w R*) and ends at delta <= 0 (reach 0). The
// law is conservative (no hysteresis). Contact radius and kn are Hertz's (a = sqrt(R* delta),
// kn = 2 E* a). Coulomb base: the Hertz repulsion f + 2 pi w R* (LAMMPS `dmt` uses
// |f + 2 F_pulloff|, i.e. one more pull-off force).
#pragma once
#include <algorithm>
#include <array>
#include <cmath>

#include "models/normal/jkr.hpp"

namespace cohdem {

struct DmtNormal : NormalBase {
  struct Params { double Estar, w; };
  static constexpr bool kHertzianStiffness = true;  // kn = 2 E* a, E* of the material pair
  static constexpr std::array specs = {kWorkOfAdhesion};
  static Params make(const ParamSet& p, const PairMaterial& m) { return {m.Estar, p.get(specs[0])}; }
  static double pull_off(const Params& p, double rstar) { return 2.0 * M_PI * p.w * rstar; }
  COHDEM_INLINE static void apply(const Params& p, const PairGeom& g, State&, NormalOut& o) {
    o.alive = g.delta > 0;
    if (!o.alive) return;
    o.a = std::sqrt(g.rstar * g.delta);
    o.kn = 2.0 * p.Estar * o.a;
    o.f_adh = pull_off(p, g.rstar);
    o.f_el = (2.0 / 3.0) * o.kn * g.delta - o.f_adh;
  }
  template <class P>
  COHDEM_INLINE static double coulomb_base(const P&, const NormalOut& o, double) {
    return std::max(o.f_el + o.f_adh, 0.0);
  }
};

}  // namespace cohdem
