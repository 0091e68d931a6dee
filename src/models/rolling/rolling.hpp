// Rolling resistance sub-models. The rolling angular velocity is the tangential part of
// omega_i - omega_j; the moment acts on i, its opposite on j.
//
// NoRolling: none.
// EpsdRolling: elastic-plastic spring-dashpot (Ai, Chen, Rotter & Ooi 2011, Powder Technol.
//   206, 269; model C): k_r = 2.25 kn mu_r^2 R*^2 (Eq. 15), spring moment updated
//   incrementally M_k -= k_r w_r dt, limit |M_k| <= mu_r R* F_c (Eq. 13); viscous part
//   M_d = -eta_r C_crit w_r with C_crit = 2 sqrt(I_r k_r), I_r = 1/(1/(I_i + m_i r_i^2) +
//   1/(I_j + m_j r_j^2)) (Eqs. 17-18), switched off while the spring is at its limit.
// CdtRolling: constant directional torque M = -mu_r R* F_c w_r/|w_r| (Zhou et al. 1999;
//   Ai et al. 2011 model A). It chatters at rest; prefer EPSD for static packings.
#pragma once
#include <array>
#include <cmath>

#include "models/pair.hpp"
#include "models/params.hpp"

namespace cohdem {

COHDEM_INLINE Vec3 rolling_rate(const PairGeom& g) { return g.wrel - g.n * dot(g.n, g.wrel); }

struct NoRolling {
  struct Params {};
  struct State {};
  static constexpr bool kNone = true;  // no moment: ContactLaw leaves its (zero) terms out
  static constexpr std::array<ParamSpec, 0> specs{};
  static Params make(const ParamSet&, const PairMaterial&) { return {}; }
  COHDEM_INLINE static Vec3 apply(const Params&, const PairGeom&, const NormalOut&, double, State&) {
    return {};
  }
};

struct EpsdRolling {
  struct Params { double mu_r, eta_r; };
  struct State { Vec3 mk; };
  /// The other side's history: the spring moment acts on i, so it changes sign.
  static void flip(State& s) { s.mk = -s.mk; }
  static constexpr std::array specs = {
      req("mu_r", "-", 0, kInf, "rolling friction coefficient"),
      opt("eta_r", "-", 0.0, 0, kInf, "rolling viscous damping ratio (Ai et al. 2011 Eq. 17)")};
  static Params make(const ParamSet& p, const PairMaterial&) { return {p.get(specs[0]), p.get(specs[1])}; }
  COHDEM_INLINE static Vec3 apply(const Params& p, const PairGeom& g, const NormalOut& no, double fc,
                                  State& s) {
    const Vec3 wr = rolling_rate(g);
    rotate_into_plane(s.mk, g.n);
    const double kr = 2.25 * no.kn * p.mu_r * p.mu_r * g.rstar * g.rstar;
    s.mk -= wr * (kr * g.dt);
    const double lim = p.mu_r * g.rstar * fc;
    const double m2 = norm2(s.mk);
    // Sliding, the spring is scaled to the limit and acts alone; sticking, it is multiplied
    // by exactly 1 (no branch: limit_scale) and the viscous part is added.
    const bool slide = m2 > lim * lim;
    s.mk *= limit_scale(m2, lim);
    if (p.eta_r > 0) {
      // I_r = Ji Jj / (Ji + Jj) with J = I + m r^2: one division. A wall (or fixed particle)
      // has I = inf and adds nothing (I_r is the other body's J); testing for it avoids
      // m r^2 = inf * 0 = NaN for a wall (r_j = 0).
      const bool wi = std::isinf(g.Ii), wj = std::isinf(g.Ij);
      const double Ji = wi ? 0.0 : g.Ii + g.mi * g.ri * g.ri, Jj = wj ? 0.0 : g.Ij + g.mj * g.rj * g.rj;
      const double Ir = wj ? Ji : (wi ? Jj : Ji * Jj / (Ji + Jj));
      const Vec3 damped = s.mk - wr * (p.eta_r * 2.0 * std::sqrt(Ir * kr));
      return select(slide, s.mk, damped);
    }
    return s.mk;
  }
};

struct CdtRolling {
  struct Params { double mu_r; };
  struct State {};
  static constexpr std::array specs = {req("mu_r", "-", 0, kInf, "rolling friction coefficient")};
  static Params make(const ParamSet& p, const PairMaterial&) { return {p.get(specs[0])}; }
  COHDEM_INLINE static Vec3 apply(const Params& p, const PairGeom& g, const NormalOut&, double fc, State&) {
    const Vec3 wr = rolling_rate(g);
    const double w = norm(wr);
    if (w <= 0) return {};
    return wr * (-p.mu_r * g.rstar * fc / w);
  }
};

}  // namespace cohdem
