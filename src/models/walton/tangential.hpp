// Walton's tangential (adhesive-friction) mode, linearized (seed 001): F_f = K_f ds up to
// F_max = mu F_R, K_f = kf_ratio K'_R (paper: K_f ~ 0.8 K_R; the softened K'_R is used so
// that sf softens both modes alike). F_R is the repulsion (normal model's coulomb_base, which
// for WaltonNormal is f + Fc). The increment ds = v_s dt; history, rotation into the current
// tangent plane and sliding are TangentialCommon's (incremental elastic force, projected and
// rescaled each step). Optional damping damp_t * gamma_n.
#pragma once
#include <array>

#include "models/tangential/spring.hpp"
#include "models/walton/common.hpp"

namespace cohdem {

struct WaltonTangential : TangentialCommon {
  struct Params { double mu, Y, sf, kf_ratio, damp_t; };
  static constexpr std::array specs = {
      kMuSpec, kWaltonY, kWaltonSf,
      opt("kf_ratio", "-", 0.8, 0, kInf, "tangential stiffness K_f = kf_ratio K'_R (paper ~0.8)"), kDampTSpec};
  static Params make(const ParamSet& p, const PairMaterial&) {
    return {p.get(specs[0]), p.get(specs[1]), p.get(specs[2]), p.get(specs[3]), p.get(specs[4])};
  }
  COHDEM_INLINE static Vec3 apply(const Params& p, const PairGeom& g, const NormalOut&, double gamma_n,
                                  double fc, State& s) {
    const double kf = p.kf_ratio * walton_kr(p.Y, p.sf, g.rstar);
    return update(s, g, kf, p.damp_t * gamma_n, p.mu, fc);
  }
};

}  // namespace cohdem
