// Normal damping chosen from a coefficient of restitution e.
//
// Linear spring (LinearRestitutionDamping): f_d = -2 beta sqrt(m* kn) v_n with
//   beta = -ln e / sqrt(pi^2 + ln^2 e)  (damped linear oscillator; e.g. Schwager & Poeschel
//   2008, Eq. 8); this gives exactly e when the contact ends at zero overlap.
// Hertz spring (TsujiDamping, Tsuji et al. 1992): f_d = -2 beta sqrt(m* kn) v_n with the
//   tangent stiffness kn = 2 E* sqrt(R* delta), i.e. damping ~ delta^(1/4). The restitution
//   of this law does not depend on impact velocity; beta(e) has no closed form, so it is
//   found once per species pair by integrating the dimensionless impact and bisecting
//   (restitution input = output to 1e-6).
//
// limit_damping = 1 keeps the damping from making the normal force attractive: the force
// then reaches zero before the overlap does (the contact still ends at zero overlap; see
// docs/contact-models.md, "When a contact ends").
#pragma once
#include <algorithm>
#include <array>
#include <cmath>

#include "models/pair.hpp"
#include "models/params.hpp"

namespace cohdem {

inline constexpr std::array<ParamSpec, 2> kRestitutionSpecs = {
    req("e", "-", 0, 1, "coefficient of normal restitution", true),
    opt("limit_damping", "0/1", 0, 0, 1, "1: damping never makes the normal force attractive")};

/// Restitution of the dimensionless impact x'' = -(x^p + 2 b sqrt(p x^(p-1)) x'),
/// x(0) = 0, x'(0) = 1 (p = 1 linear, p = 3/2 Hertz), ended at zero overlap or, with
/// `limit`, when the normal force reaches zero (the particle then flies off with x').
double restitution_of_beta(double beta, double p, bool limit);
/// Inverse of restitution_of_beta (bisection), for e in (0, 1].
double beta_for_restitution(double e, double p, bool limit);

inline double apply_limit(double f_el, double fd, bool limit) {
  if (limit && f_el + fd < 0.0 && fd < 0.0) return -std::max(f_el, 0.0);
  return fd;
}

struct LinearRestitutionDamping {
  struct Params { double beta; bool limit; };
  struct State {};
  static constexpr auto specs = kRestitutionSpecs;
  static Params make(const ParamSet& p, const PairMaterial&) {
    const double e = p.get(specs[0]);
    const bool limit = p.get(specs[1]) != 0;
    if (e >= 1.0) return {0.0, limit};
    const double l = std::log(e);
    return {limit ? beta_for_restitution(e, 1.0, true) : -l / std::sqrt(M_PI * M_PI + l * l), limit};
  }
  /// Returns the damping force (repulsive > 0); writes the damping coefficient gamma (N s/m).
  COHDEM_INLINE static double apply(const Params& p, const PairGeom& g, const NormalOut& no, double& gamma) {
    gamma = 2.0 * p.beta * std::sqrt(g.mstar * no.kn);
    return apply_limit(no.f_el, -gamma * g.vn, p.limit);
  }
};

struct TsujiDamping {
  struct Params { double beta; bool limit; };
  struct State {};
  static constexpr auto specs = kRestitutionSpecs;
  static Params make(const ParamSet& p, const PairMaterial&) {
    const double e = p.get(specs[0]);
    const bool limit = p.get(specs[1]) != 0;
    if (e >= 1.0) return {0.0, limit};
    return {beta_for_restitution(e, 1.5, limit), limit};
  }
  COHDEM_INLINE static double apply(const Params& p, const PairGeom& g, const NormalOut& no, double& gamma) {
    gamma = 2.0 * p.beta * std::sqrt(g.mstar * no.kn);
    return apply_limit(no.f_el, -gamma * g.vn, p.limit);
  }
};

/// Plain viscous damping f_d = -gamma_n v_n (MEPA paper, Eq. for F_n); gamma_n in N s/m.
struct ViscousDamping {
  struct Params { double gamma_n; bool limit; };
  struct State {};
  static constexpr std::array<ParamSpec, 2> specs = {
      opt("gamma_n", "N s/m", 0, 0, kInf, "normal viscous damping coefficient"),
      opt("limit_damping", "0/1", 0, 0, 1, "1: damping never makes the normal force attractive")};
  static Params make(const ParamSet& p, const PairMaterial&) { return {p.get(specs[0]), p.get(specs[1]) != 0}; }
  COHDEM_INLINE static double apply(const Params& p, const PairGeom& g, const NormalOut& no, double& gamma) {
    gamma = p.gamma_n;
    return apply_limit(no.f_el, -gamma * g.vn, p.limit);
  }
};

}  // namespace cohdem
