// Normal damping as a fraction of critical: f_d = -2 beta_n sqrt(m* kn) v_n, with kn the
// normal model's current (elastic) stiffness. The critical-damping-ratio form of PFC
// (dp_nratio) and the usual choice for models whose restitution has no closed form
// (EEPA, Walton): the damping then scales with particle size and stiffness by itself.
// beta_n = 0 (default) is no damping.
#pragma once
#include <algorithm>
#include <array>
#include <cmath>

#include "models/damping/restitution.hpp"

namespace cohdem {

struct RatioDamping {
  struct Params { double beta; bool limit; };
  struct State {};
  static constexpr std::array<ParamSpec, 2> specs = {
      opt("beta_n", "-", 0, 0, kInf, "normal damping ratio, gamma_n = 2 beta_n sqrt(m* kn) (PFC dp_nratio)"),
      kRestitutionSpecs[1]};
  static Params make(const ParamSet& p, const PairMaterial&) { return {p.get(specs[0]), p.get(specs[1]) != 0}; }
  COHDEM_INLINE static double apply(const Params& p, const PairGeom& g, const NormalOut& no, double& gamma) {
    gamma = p.beta > 0 ? 2.0 * p.beta * std::sqrt(g.mstar * std::max(no.kn, 0.0)) : 0.0;
    return apply_limit(no.f_el, -gamma * g.vn, p.limit);
  }
};

}  // namespace cohdem
