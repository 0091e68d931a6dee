// MEPA family: hysteretic elasto-plastic adhesive normal models with a history variable
// (the largest overlap), and the tangential spring that goes with them.
//
// MEPA (Del Cid & Mustoe, seed 000, Eqs. 1-6), with D = delta^n (n > 0; the paper uses 3/2,
// Luding's linear form is n = 1):
//   f1 = k1 D                  virgin loading
//   f2 = k2 (D - Dp)           elastic unloading / reloading,  Dp = dp^n
//   f3 = -kadh delta^x         adhesive bound (x = n in MEPA and Luding; separate in EEPA)
//   fhys = f0 + { f1 if f2 >= f1;  f2 if f1 > f2 > f3;  f3 if f3 >= f2 }        (Eq. 4)
// Every branch is linear in D, so the n = 1 closed forms hold for any n with delta -> D.
// History: Dmax, the largest D seen; Dp = Dmax (1 - k1/k2) makes f2 meet f1 at Dmax.
// The contact exists for delta > 0 and ends (history reset) at delta <= 0, where f3 -> 0
// (MEPA, Luding) or the force jumps from f0 to 0 (EEPA); reach() = 0.
//
// Three parameterizations of the one law (same apply, own key tables and defaults):
//  - MepaNormal   (preset mepa):   k1, k2, kadh, n              [N/m^n]
//  - LudingNormal (preset luding): k1, k2 (= Luding's k2-hat, the limit), kc, phi_f, n = 1:
//      k2(Dmax) = k1 + (k2 - k1) min(1, Dmax / Dmax_p),  Dmax_p = (k2/(k2-k1) phi_f 2R*)^n
//      (Luding 2008, Granular Matter 10:235, Eq. 6; MercuryDPM LinearPlasticViscoelastic).
//      phi_f = 0 keeps k2 constant.
//  - EepaNormal   (preset eepa):   lambda_p (k2 = k1/(1 - lambda_p)), kadh [N/m^x], n, x, f0
//      (Morrissey 2013; Thakur et al. 2014, Granular Matter 16:383); k1 = 0 takes the Hertz
//      coefficient k1 = 4/3 E* sqrt(R*) per contact (n = 3/2 only).
//
// OPEN points of reference/models.md, decided here (docs/contact-models.md has the table):
//  - Reloading from f3 (dp_shift): 0 = dp is kept; the contact retraces f3 up to delta_min
//    and then follows f2, so unload/reload cycles inside the bounds dissipate nothing (MEPA,
//    EEPA default: "dp recorded over the contact lifetime"). 1 = Luding's shift: while on
//    f3, Dmax (hence Dp) is moved so that f2 passes through the current point; reloading
//    then follows a new k2 line and re-enters f1 below the old maximum (Luding default).
//  - Coulomb limit (coulomb_offset): 0 = literal mu max(fhys, 0) (paper Eq. 6; no friction
//    in tension); 1 = cohesion offset mu (fhys - f_lower) = mu (fhys + kadh delta^x - f0),
//    the force above the adhesive bound, >= 0 on every branch (Luding 2008). Damping is
//    not part of the friction base (the paper writes fhys).
//  - Units: k1, k2, kadh in N/m^n (N/m^1.5 for n = 3/2); the paper's Table 1 prints N/m and
//    its text says k1 = 15 k2 while the table has k2 = 5 k1: we read the table values in
//    N/m^n (k1 = 4.75e8, k2 = 2.37e9).
//  - NormalOut::kn is the elastic (unloading) stiffness n k2max delta^(n-1), the stiffest
//    branch: it sets the time step and the EPSD rolling stiffness.
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>

#include "models/normal/base.hpp"
#include "models/tangential/spring.hpp"

namespace cohdem {

/// d^n with the common exponents exact and cheap (hot path).
/// d^(n-1) for d > 0, without pow or a division for the usual n = 1 and 3/2 (then d^n is
/// d * pow_nm1(d, n), and the tangent n k d^(n-1) needs no d^n / d).
inline double pow_nm1(double d, double n) {
  if (n == 1.0) return 1.0;
  if (n == 1.5) return std::sqrt(d);
  return std::pow(d, n - 1.0);
}
/// d^n for d >= 0.
COHDEM_INLINE double powe(double d, double n) { return d > 0 ? d * pow_nm1(d, n) : 0.0; }

/// An InputError about `key` of a parameter set, naming where the key was given.
inline InputError param_error(const ParamSet& ps, const std::string& key, const std::string& what) {
  const auto o = ps.origin(key);
  return InputError(o.file, o.line, o.section.empty() ? key : o.section + "." + key, what);
}

/// An integer choice stored as a number in a ParamSet (0/1/2 ...), checked.
inline int get_choice(const ParamSet& p, const ParamSpec& s) {
  const double v = p.get(s);
  if (v != std::floor(v)) throw param_error(p, s.name, std::string("expected an integer choice (") + s.doc + ")");
  return int(v);
}

struct HystereticNormal : NormalBase {
  struct Params {
    double k1 = 0;        ///< loading stiffness, N/m^n (hertz_k1: computed per contact)
    double k2 = 0;        ///< unloading stiffness, N/m^n (Luding: the limit k2-hat)
    double ratio = 0;     ///< hertz_k1 only: k2 = k1 / (1 - lambda_p)
    double kadh = 0;      ///< adhesive stiffness, N/m^x
    double n = 1.5, x = 1.5;
    double f0 = 0;        ///< constant pull-off offset, N (<= 0)
    double phi_f = 0;     ///< Luding plastic flow limit (0: constant k2)
    double Estar = 0;     ///< hertz_k1 only
    /// 1 - k1/k2 where both are fixed per material pair (no hertz_k1, phi_f = 0; set by
    /// fix_ratio()): the plastic overlap of a new maximum, Dp = D (1 - k1/k2), then needs no
    /// division per contact (the same operations, done once).
    double plastic = 0;
    bool fixed = false;   ///< k1, k2 fixed per material pair (plastic is set)
    bool hertz_k1 = false, shift = false, offset = false, x_is_n = true;
  };
  struct State {
    double Dmax = 0;       ///< largest delta^n of this contact (moved by dp_shift)
    double Dp = 0;         ///< plastic overlap to the power n, Dmax (1 - k1/k2(Dmax))
    int32_t branch = 0;    ///< branch of the last evaluation: 1 loading, 2 un/reloading, 3 adhesive
  };
  static void flip(State&) {}  ///< overlaps and branch: the same seen from either particle
  static constexpr std::array<const char*, 3> state_columns = {"dmax", "dp", "branch"};
  static void state_values(const Params& p, const State& s, double* out) {
    out[0] = std::pow(s.Dmax, 1.0 / p.n);
    out[1] = std::pow(std::max(s.Dp, 0.0), 1.0 / p.n);
    out[2] = s.branch;
  }

  /// Stiffnesses of one contact (they depend on R* for hertz_k1 and Luding's phi_f).
  struct Stiff { double k1, k2, Dmax_p; };
  COHDEM_INLINE static Stiff stiff(const Params& p, double rstar) {
    if (p.fixed) return {p.k1, p.k2, 0.0};  // the usual MEPA case: no per-contact reading
    Stiff k;
    k.k1 = p.hertz_k1 ? (4.0 / 3.0) * p.Estar * std::sqrt(rstar) : p.k1;
    k.k2 = p.hertz_k1 ? k.k1 / (1.0 - p.ratio) : p.k2;
    k.Dmax_p = (p.phi_f > 0 && k.k2 > k.k1) ? powe(k.k2 / (k.k2 - k.k1) * p.phi_f * 2.0 * rstar, p.n) : 0.0;
    return k;
  }
  static double k1_of(const Params& p, double rstar) {
    return p.hertz_k1 ? (4.0 / 3.0) * p.Estar * std::sqrt(rstar) : p.k1;
  }
  COHDEM_INLINE static double k2_at(const Stiff& k, double Dmax) {
    if (k.Dmax_p <= 0 || Dmax >= k.Dmax_p) return k.k2;
    return k.k1 + (k.k2 - k.k1) * Dmax / k.Dmax_p;
  }
  /// Luding's shift: the Dmax whose f2 line passes through (D, -A), i.e.
  /// k2(Dm) D - (k2(Dm) - k1) Dm = -A. Constant k2: Dm = (k2 D + A)/(k2 - k1); in the
  /// growing range k2 = k1 + s Dm it is the positive root of s Dm^2 - s D Dm - (k1 D + A) = 0.
  COHDEM_INLINE static double shifted_dmax(const Stiff& k, double D, double A) {
    const double dc = (k.k2 * D + A) / (k.k2 - k.k1);
    if (k.Dmax_p <= 0 || dc >= k.Dmax_p) return dc;
    const double s = (k.k2 - k.k1) / k.Dmax_p;
    return (s * D + std::sqrt(s * s * D * D + 4.0 * s * (k.k1 * D + A))) / (2.0 * s);
  }

  COHDEM_INLINE static void apply(const Params& p, const PairGeom& g, State& s, NormalOut& o) {
    const double d = g.delta;
    o.alive = d > 0;
    if (!o.alive) return;
    const Stiff k = stiff(p, g.rstar);
    const double dn1 = pow_nm1(d, p.n);
    const double D = d * dn1;
    const double A = p.kadh * (p.x_is_n ? D : powe(d, p.x));  // adhesive bound magnitude
    // (k2_at gives k.k2 when fixed too; the select lets GCC drop its test: 8 instructions.)
    const double k2 = p.fixed ? k.k2 : k2_at(k, s.Dmax);
    const double f1 = k.k1 * D, f2 = k2 * (D - s.Dp);
    // The branch (loading, un/reloading, adhesive) changes from step to step in a sheared bed
    // and mispredicts, so all three are computed and the result selected (same values as a
    // branch would give). Virgin loading: a new maximum (f2 >= f1 <=> D >= Dmax for k2 > k1).
    const bool load = f2 >= f1, adh = !load && !(f2 > -A);
    const double f = load ? f1 : (adh ? -A : f2);
    // Fixed stiffnesses: 1 - k1/k2 is the per-pair constant (the same value, no division).
    const double Dp_new = D * (p.fixed ? p.plastic : 1.0 - k.k1 / k2_at(k, D));
    s.Dmax = load ? D : s.Dmax;
    s.Dp = load ? Dp_new : s.Dp;
    s.branch = load ? 1 : (adh ? 3 : 2);
    if (p.shift && adh) {  // Luding's shift of the plastic overlap on the adhesive branch
      s.Dmax = shifted_dmax(k, D, A);
      s.Dp = s.Dmax * (1.0 - k.k1 / k2_at(k, s.Dmax));
    }
    o.f_el = p.f0 + f;
    o.f_adh = A - p.f0;
    o.kn = p.n * k.k2 * dn1;
    o.k_load = k.k1 * dn1;
    o.a = g.want_a ? std::sqrt(g.rstar * d) : 0.0;
  }

  template <class P>
  COHDEM_INLINE static double coulomb_base(const P& p, const NormalOut& o, double /*fn_total*/) {
    return std::max(p.offset ? o.f_el + o.f_adh : o.f_el, 0.0);
  }

 protected:
  /// Sets Params::plastic and fixed where k1 and k2 do not depend on the contact.
  static void fix_ratio(Params& p) {
    p.fixed = !p.hertz_k1 && !(p.phi_f > 0);
    p.plastic = p.fixed ? 1.0 - p.k1 / p.k2 : 0.0;
  }
  static void check_k2(const ParamSet& ps, const char* key, double k1, double k2) {
    if (k2 < k1)
      throw param_error(ps, key, "unloading stiffness must be >= k1 (k1 = " + std::to_string(k1) + ", " + key +
                                     " = " + std::to_string(k2) + ")");
  }
};

/// MEPA as in the paper (preset `mepa`).
struct MepaNormal : HystereticNormal {
  static constexpr std::array specs = {
      req("k1", "N/m^n", 0, kInf, "virgin loading stiffness, f1 = k1 delta^n", true),
      req("k2", "N/m^n", 0, kInf, "unloading/reloading stiffness, f2 = k2 (delta^n - dp^n); k2 >= k1", true),
      opt("kadh", "N/m^n", 0, 0, kInf, "adhesive stiffness, f3 = -kadh delta^n"),
      opt("n", "-", 1.5, 0, kInf, "force-overlap exponent (1: linear, 1.5: Hertz-like)", true),
      opt("dp_shift", "0/1", 0, 0, 1, "1: on the adhesive branch move dp so that f2 passes through the current point (Luding)"),
      opt("coulomb_offset", "0/1", 0, 0, 1,
          "friction base: 0 mu max(fhys, 0) (paper Eq. 6), 1 mu (fhys + kadh delta^n)")};
  static Params make(const ParamSet& ps, const PairMaterial&) {
    Params p;
    p.k1 = ps.get(specs[0]);
    p.k2 = ps.get(specs[1]);
    check_k2(ps, "k2", p.k1, p.k2);
    p.kadh = ps.get(specs[2]);
    p.n = p.x = ps.get(specs[3]);
    p.shift = ps.get(specs[4]) != 0;
    p.offset = ps.get(specs[5]) != 0;
    fix_ratio(p);
    return p;
  }
};

/// Luding (2008): linear by default, k2 growing with the largest overlap up to k2-hat.
struct LudingNormal : HystereticNormal {
  static constexpr std::array specs = {
      req("k1", "N/m^n", 0, kInf, "virgin loading stiffness (MercuryDPM loadingStiffness)", true),
      req("k2", "N/m^n", 0, kInf, "largest unloading stiffness k2-hat (MercuryDPM unloadingStiffnessMax); >= k1", true),
      opt("kc", "N/m^n", 0, 0, kInf, "adhesive (cohesion) stiffness, f3 = -kc delta^n (MercuryDPM cohesionStiffness)"),
      opt("phi_f", "-", 0, 0, kInf,
          "plastic flow limit: k2 reaches k2-hat when dp = phi_f 2R* (MercuryDPM penetrationDepthMax); 0: k2 constant"),
      opt("n", "-", 1.0, 0, kInf, "force-overlap exponent (Luding: 1)", true),
      opt("dp_shift", "0/1", 1, 0, 1, "1: on the adhesive branch move dp so that f2 passes through the current point"),
      opt("coulomb_offset", "0/1", 1, 0, 1, "friction base: 0 mu max(f, 0), 1 mu (f + kc delta^n) (Luding 2008)")};
  static Params make(const ParamSet& ps, const PairMaterial&) {
    Params p;
    p.k1 = ps.get(specs[0]);
    p.k2 = ps.get(specs[1]);
    check_k2(ps, "k2", p.k1, p.k2);
    p.kadh = ps.get(specs[2]);
    p.phi_f = ps.get(specs[3]);
    p.n = p.x = ps.get(specs[4]);
    p.shift = ps.get(specs[5]) != 0;
    p.offset = ps.get(specs[6]) != 0;
    fix_ratio(p);
    return p;
  }
};

/// EEPA (EDEM, PFC `eepa`): constant offset f0 and separate adhesive exponent x.
struct EepaNormal : HystereticNormal {
  static constexpr std::array specs = {
      opt("k1", "N/m^n", 0, 0, kInf, "virgin loading stiffness; 0: Hertz coefficient 4/3 E* sqrt(R*) per contact (n = 1.5)"),
      req("lambda_p", "-", 0, 1, "contact plasticity ratio 1 - k1/k2, < 1 (EDEM contact plasticity ratio, PFC plas_ratio)"),
      opt("kadh", "N/m^x", 0, 0, kInf, "adhesive stiffness, adhesive branch f0 - kadh delta^x"),
      opt("n", "-", 1.5, 0, kInf, "loading/unloading exponent (EDEM slope exp, PFC lu_exp)", true),
      opt("x", "-", 1.5, 0, kInf, "adhesive branch exponent (EDEM tensile exp, PFC adh_exp)", true),
      opt("f0", "N", 0, -kInf, 0, "constant pull-off force, <= 0, added to every branch (EDEM constant pull-off force)"),
      opt("dp_shift", "0/1", 0, 0, 1, "1: on the adhesive branch move dp so that f2 passes through the current point"),
      opt("coulomb_offset", "0/1", 1, 0, 1, "friction base: 0 mu max(f, 0), 1 mu (f - f0 + kadh delta^x)")};
  static Params make(const ParamSet& ps, const PairMaterial& m) {
    Params p;
    const double lp = ps.get(specs[1]);
    if (lp >= 1.0) throw param_error(ps, "lambda_p", "plasticity ratio must be < 1 (k2 = k1 / (1 - lambda_p))");
    p.n = ps.get(specs[3]);
    p.x = ps.get(specs[4]);
    p.x_is_n = p.x == p.n;
    p.k1 = ps.get(specs[0]);
    p.ratio = lp;
    if (p.k1 == 0) {
      if (p.n != 1.5)
        throw param_error(ps, "k1", "k1 = 0 (Hertz coefficient) needs n = 1.5; give k1 for n = " + std::to_string(p.n));
      p.hertz_k1 = true;
      p.Estar = m.Estar;
    }
    p.k2 = p.k1 / (1.0 - lp);
    p.kadh = ps.get(specs[2]);
    p.f0 = ps.get(specs[5]);
    p.shift = ps.get(specs[6]) != 0;
    p.offset = ps.get(specs[7]) != 0;
    fix_ratio(p);
    return p;
  }
};

/// Tangential spring of the MEPA family: kt tied to the loading stiffness k1 (the paper:
/// "kt set to the value of k1"). For n != 1, k1 is in N/m^n, so kt = k1 needs a reading
/// (kt_form): 0 tangent kt = n k1 delta^(n-1) (stiffness of the loading branch, N/m; the
/// default), 1 secant kt = k1 delta^(n-1), 2 constant kt = k1 taken as N/m (the paper's
/// literal use with its Table 1). All three agree for n = 1. kt_ratio scales it (EDEM
/// tangential stiffness multiplier); `kt` > 0 sets an absolute value. History, rotation and
/// the Coulomb limit (mu times the normal model's coulomb_base) are TangentialCommon's.
template <class N>
struct HystTangential : TangentialCommon {
  struct Params {
    typename N::Params np;
    double mu, kt_ratio, damp_t;
    // The reading of kt_form and kt, resolved once per material pair (same values as
    // resolving it per contact): kt_const, a fixed kt (kt given, or kt_form 2 with a fixed
    // k1); kt_hertz, kt_ratio k1(R*) per contact (kt_form 2, EEPA's Hertz k1); otherwise
    // kt_ratio k_load kt_mult, kt_mult n for the tangent (kt_form 0, n != 1), else 1.
    double kt_c = 0, kt_mult = 1;
    bool kt_const = false, kt_hertz = false;
  };
  static constexpr std::array specs = {
      kMuSpec,
      opt("kt_form", "0/1/2", 0, 0, 2,
          "kt from k1: 0 tangent n k1 delta^(n-1), 1 secant k1 delta^(n-1), 2 constant k1 (as N/m)"),
      opt("kt_ratio", "-", 1.0, 0, kInf, "kt / (k1-based stiffness) (EDEM tangential stiffness multiplier)"),
      opt("kt", "N/m", 0, 0, kInf, "absolute tangential stiffness (0: from k1 by kt_form)"), kDampTSpec};
  static Params make(const ParamSet& p, const PairMaterial& m) {
    Params q{N::make(p, m), p.get(specs[0]), p.get(specs[2]), p.get(specs[4])};
    const double kt = p.get(specs[3]), n = q.np.n;
    const int form = get_choice(p, specs[1]);
    // n = 1: every form is kt_ratio k1 (k_load = k1 delta^0 = k1 exactly).
    q.kt_hertz = form == 2 && q.np.hertz_k1;  // read after kt_const (a given kt wins)
    q.kt_const = kt > 0 || (form == 2 && !q.np.hertz_k1);
    q.kt_c = kt > 0 ? kt : q.kt_ratio * q.np.k1;
    q.kt_mult = n != 1.0 && form == 0 ? n : 1.0;
    return q;
  }
  /// no.k_load = k1 delta^(n-1), from the normal law's evaluation of this contact.
  COHDEM_INLINE static double stiffness(const Params& p, const PairGeom& g, const NormalOut& no) {
    if (p.kt_const) return p.kt_c;
    if (p.kt_hertz) return p.kt_ratio * N::k1_of(p.np, g.rstar);
    return p.kt_ratio * no.k_load * p.kt_mult;
  }
  COHDEM_INLINE static Vec3 apply(const Params& p, const PairGeom& g, const NormalOut& no, double gamma_n,
                                  double fc, State& s) {
    return update(s, g, stiffness(p, g, no), p.damp_t * gamma_n, p.mu, fc);
  }
};

}  // namespace cohdem
