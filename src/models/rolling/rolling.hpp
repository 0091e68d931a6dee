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
// SdsRolling: spring-dashpot-slider on the rolling displacement (Luding 2008, Granular
//   Matter 10, 235; the rolling velocity of Wang et al. 2015, Particuology 23, 49, Eq. 31;
//   LAMMPS pair granular's `rolling sds k_r gamma_r mu_r`): v_r = R* (w_rel x n), a spring
//   of stiffness k_r (N/m) on the displacement xi (xi += v_r dt, kept in the tangent plane)
//   and a dashpot gamma_r (kg/s): f_r = -k_r xi - gamma_r v_r, limited to |f_r| <= mu_r F_c,
//   where the spring is set so that spring and dashpot give the limit (xi = -(f_r +
//   gamma_r v_r)/k_r); moment on i M = R* n x f_r, so |M| <= mu_r R* F_c as with EPSD. Its
//   stiffness is a constant, not tied to the normal law's.
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

struct SdsRolling {
  struct Params { double k_r, gamma_r, mu_r; };
  /// The spring's force -k_r xi, kept instead of xi (the same values: k_r is a constant).
  struct State { Vec3 fk; };
  /// v_r = R* (w_rel x n) is the same seen from j (both w_rel and n change sign), and so are
  /// xi and the spring; only the moment R* n x f_r changes sign, and ContactLaw gives j the
  /// opposite of i's.
  static void flip(State&) {}
  static constexpr std::array specs = {
      req("k_r", "N/m", 0, kInf, "rolling spring stiffness, on the rolling displacement (SDS)"),
      opt("gamma_r", "kg/s", 0.0, 0, kInf, "rolling dashpot coefficient (SDS)"),
      req("mu_r", "-", 0, kInf, "rolling friction coefficient")};
  static Params make(const ParamSet& p, const PairMaterial&) {
    return {p.get(specs[0]), p.get(specs[1]), p.get(specs[2])};
  }
  COHDEM_INLINE static Vec3 apply(const Params& p, const PairGeom& g, const NormalOut&, double fc, State& s) {
    const Vec3 vr = cross(g.wrel, g.n) * g.rstar;
    rotate_into_plane(s.fk, g.n);
    s.fk -= vr * (p.k_r * g.dt);
    const Vec3 damp = vr * p.gamma_r;
    Vec3 f = s.fk - damp;
    const double lim = p.mu_r * fc;
    const double f2 = norm2(f);
    // Sliding, f is scaled to the limit and the spring becomes what gives it with the dashpot;
    // sticking, f is multiplied by exactly 1 (limit_scale).
    const bool slide = f2 > lim * lim;
    f *= limit_scale(f2, lim);
    s.fk = select(slide, f + damp, s.fk);
    return cross(g.n, f) * g.rstar;
  }
};

}  // namespace cohdem
