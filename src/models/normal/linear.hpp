// Linear spring normal force (Cundall & Strack 1979): f = kn * delta.
// Contact ends when the overlap reaches zero.
#pragma once
#include <array>
#include <cmath>

#include "models/normal/base.hpp"

namespace cohdem {

struct LinearNormal : NormalBase {
  struct Params { double kn; };
  static constexpr bool kFixedStiffness = true;  // kn never changes within a contact
  static constexpr std::array specs = {
      req("kn", "N/m", 0, kInf, "normal spring stiffness", true)};
  static Params make(const ParamSet& p, const PairMaterial&) { return {p.get(specs[0])}; }
  COHDEM_INLINE static void apply(const Params& p, const PairGeom& g, State&, NormalOut& o) {
    o.alive = g.delta > 0;
    o.f_el = p.kn * g.delta;
    o.kn = p.kn;
    o.a = o.alive && g.want_a ? std::sqrt(g.rstar * g.delta) : 0.0;  // geometric contact radius
  }
};

}  // namespace cohdem
