// Tangential spring with history and a Coulomb limit (Cundall & Strack 1979; LAMMPS
// granular "linear_history"/"mindlin" sub-models for the bookkeeping).
//
// History is the elastic tangential force f_s (incremental form, Thornton 1991):
//  1. rotate f_s into the current tangent plane, keeping its magnitude;
//  2. if the stiffness fell since the last step (unloading in Mindlin's law), scale f_s by
//     kt_new/kt_old so no energy is created (Mindlin & Deresiewicz, as simplified by
//     Thornton et al. 2011); a stiffness that grows leaves f_s alone (no energy created);
//  3. f_s -= kt v_t dt;  trial F_t = f_s - gamma_t v_t;
//  4. if |F_t| > mu F_c (F_c: the normal model's Coulomb base, >= 0) the contact slides:
//     F_t = mu F_c F_t/|F_t| and f_s = F_t (damping plays no part while sliding).
// Stiffness: Linear: kt = kt_ratio * kn (kn the normal tangent stiffness; LAMMPS chute
// uses kt/kn = 2/7), or an absolute kt when given. Mindlin: kt = 8 G* a.
#pragma once
#include <array>
#include <cmath>

#include "models/pair.hpp"
#include "models/params.hpp"

namespace cohdem {

struct TangentialCommon {
  struct State { Vec3 fs; double kt_prev = 0; };
  /// History of a spring whose stiffness never changes within a contact (step 2 is void):
  /// 24 bytes, not 32, per list entry.
  struct FixedState { Vec3 fs; };
  /// The history as seen from the other particle (the pair's two sides exchanged, as when a
  /// re-sort reverses which of them holds the pair's row): the spring force is the one on i,
  /// so it changes sign; the stiffness does not.
  static void flip(State& s) { s.fs = -s.fs; }
  static void flip(FixedState& s) { s.fs = -s.fs; }
  /// Shared history update; returns the tangential force on i.
  template <class S>
  COHDEM_INLINE static Vec3 update(S& s, const PairGeom& g, double kt, double gamma_t, double mu, double fc) {
    // 1. rotate into the tangent plane, keep magnitude
    rotate_into_plane(s.fs, g.n);
    // 2. no energy from a stiffness drop
    if constexpr (requires { s.kt_prev; }) {
      if (s.kt_prev > 0 && kt < s.kt_prev) s.fs *= kt / s.kt_prev;
      s.kt_prev = kt;
    }
    // 3. increment
    s.fs -= g.vt * (kt * g.dt);
    Vec3 ft = s.fs - g.vt * gamma_t;
    // 4. Coulomb
    const double lim = mu * fc;
    const double f2 = norm2(ft);
    // Sliding, ft is scaled to the limit and becomes the spring; sticking, it is multiplied
    // by exactly 1 (no branch: limit_scale).
    const bool slide = f2 > lim * lim;
    ft *= limit_scale(f2, lim);
    s.fs = select(slide, ft, s.fs);
    return ft;
  }
};

inline constexpr ParamSpec kMuSpec = req("mu", "-", 0, kInf, "sliding friction coefficient");
inline constexpr ParamSpec kDampTSpec =
    opt("damp_t", "-", 0.0, 0, kInf, "tangential damping coefficient as a fraction of the normal one");

struct LinearTangential : TangentialCommon {
  struct Params { double mu, kt, kt_ratio, damp_t; };
  /// kt is fixed per material pair (kt, or kt_ratio times a linear normal law's constant
  /// kn; the registry pairs this model with LinearNormal only), so no kt_prev is kept.
  using State = FixedState;
  static constexpr bool kNeedsFixedStiffness = true;  // checked by ContactLaw
  static constexpr std::array specs = {
      kMuSpec,
      opt("kt", "N/m", 0, 0, kInf, "tangential stiffness (0: use kt_ratio * kn)"),
      opt("kt_ratio", "-", 2.0 / 7.0, 0, kInf, "tangential/normal stiffness ratio", true), kDampTSpec};
  static Params make(const ParamSet& p, const PairMaterial&) {
    return {p.get(specs[0]), p.get(specs[1]), p.get(specs[2]), p.get(specs[3])};
  }
  COHDEM_INLINE static Vec3 apply(const Params& p, const PairGeom& g, const NormalOut& no, double gamma_n,
                                  double fc, State& s) {
    const double kt = p.kt > 0 ? p.kt : p.kt_ratio * no.kn;
    return update(s, g, kt, p.damp_t * gamma_n, p.mu, fc);
  }
};

struct MindlinTangential : TangentialCommon {
  /// damp_kt = damp_t sqrt(kt/kn) = damp_t sqrt(4 G*/E*), a constant per material pair.
  struct Params { double mu, Gstar, damp_t, damp_kt; };
  /// Needs kn = 2 E* a with PairMaterial's E* (Hertz, JKR, DMT; checked by ContactLaw).
  static constexpr bool kNeedsHertzianStiffness = true;
  static constexpr std::array specs = {kMuSpec, opt("damp_t", "-", 1.0, 0, kInf,
      "tangential damping coefficient as a fraction of the normal one (scaled by sqrt(kt/kn))")};
  static Params make(const ParamSet& p, const PairMaterial& m) {
    const double damp_t = p.get(specs[1]);
    return {p.get(specs[0]), m.Gstar, damp_t, m.Estar > 0 ? damp_t * std::sqrt(4.0 * m.Gstar / m.Estar) : 0.0};
  }
  COHDEM_INLINE static Vec3 apply(const Params& p, const PairGeom& g, const NormalOut& no, double gamma_n,
                                  double fc, State& s) {
    const double kt = 8.0 * p.Gstar * no.a;
    // EDEM/LAMMPS form: gamma_t = gamma_n sqrt(kt/kn) (same damping ratio as the normal).
    // With the Hertzian kn = 2 E* a, kt/kn = 4 G*/E* whatever the overlap: no square root
    // per contact (gamma_n is 0 where a is, so no guard is needed at first touch).
    const double gt = p.damp_kt * gamma_n;
    return update(s, g, kt, gt, p.mu, fc);
  }
};

}  // namespace cohdem
