// Hertz elastic normal force (Hertz 1882; Johnson 1985, Eq. 4.22):
//   f = 4/3 E* sqrt(R*) delta^(3/2),  contact radius a = sqrt(R* delta),
//   tangent stiffness kn = 2 E* a.
// E* from the two materials' E and nu (PairMaterial). Contact ends at zero overlap.
#pragma once
#include <array>
#include <cmath>

#include "models/normal/base.hpp"

namespace cohdem {

struct HertzNormal : NormalBase {
  struct Params { double Estar; };
  static constexpr bool kHertzianStiffness = true;  // kn = 2 E* a, E* of the material pair
  static constexpr std::array<ParamSpec, 0> specs{};
  static Params make(const ParamSet&, const PairMaterial& m) { return {m.Estar}; }
  COHDEM_INLINE static void apply(const Params& p, const PairGeom& g, State&, NormalOut& o) {
    o.alive = g.delta > 0;
    if (!o.alive) return;
    o.a = std::sqrt(g.rstar * g.delta);
    o.kn = 2.0 * p.Estar * o.a;
    o.f_el = (2.0 / 3.0) * o.kn * g.delta;
  }
};

}  // namespace cohdem
