// Walton's bending and twisting modes (seed 001), both elastic-perfectly-plastic springs on
// the relative rotation of the two bodies:
//   bending rate  theta' = (w_i - w_j) - [(w_i - w_j) . n] n    (paper Eq. 11, I/J swapped)
//   twisting rate phi'   = [(w_i - w_j) . n] n                  (paper Eq. 10)
// Increments d(theta) = theta' dt, d(phi) = phi' dt. The spring moments are kept in
// incremental form, M -= K d(angle), then clipped to the limit (sliding), like the
// tangential force; the bending moment vector is rotated with the contact each step
// (projected on the current tangent plane, magnitude kept). The twisting moment is a scalar
// about n, which needs no rotation.
//   bending:  K_theta = c_theta K'_R a'_b^2,  |M_b| <= B_max = Fc a'_b / 2
//   twisting: K_phi = K_theta,                |M_t| <= T_max = tf B_max,  0 <= tf <= 2
// with a'_b and Fc from walton/common.hpp (Fc from the normal model, NormalOut::f_adh).
// The moments act on i; j gets the opposite (ContactLaw). When K_theta grows with Fc the
// stored moment is kept (no energy is created by a stiffer spring on a fixed moment).
#pragma once
#include <algorithm>
#include <array>
#include <cmath>

#include "models/pair.hpp"
#include "models/walton/common.hpp"

namespace cohdem {

struct WaltonBending {
  struct Params { double Y, sf, bf, c_theta; };
  struct State { Vec3 m; };
  /// The other side's history: the bending moment acts on i, so it changes sign.
  static void flip(State& s) { s.m = -s.m; }
  static constexpr std::array specs = {kWaltonY, kWaltonSf, kWaltonBf, kWaltonCtheta};
  static Params make(const ParamSet& p, const PairMaterial&) {
    return {p.get(specs[0]), p.get(specs[1]), p.get(specs[2]), p.get(specs[3])};
  }
  /// Returns the bending moment on i (N m). `fc` (Coulomb base) is not used: the limit is
  /// set by the pull-off force.
  COHDEM_INLINE static Vec3 apply(const Params& p, const PairGeom& g, const NormalOut& no, double /*fc*/,
                                  State& s) {
    const WaltonSpot sp = walton_spot(p.Y, p.sf, p.bf, p.c_theta, g.rstar, no.f_adh);
    rotate_into_plane(s.m, g.n);  // turn with the contact
    const Vec3 wb = g.wrel - g.n * dot(g.n, g.wrel);
    s.m -= wb * (sp.k_theta * g.dt);
    const double m2 = norm2(s.m);
    if (m2 > sp.b_max * sp.b_max) s.m = m2 > 0 ? s.m * (sp.b_max / std::sqrt(m2)) : Vec3{};
    return s.m;
  }
};

struct WaltonTwisting {
  struct Params { double Y, sf, bf, c_theta, tf; };
  struct State { double m = 0; };
  /// The other side's history: the twist about n, (w_i - w_j) . n, is the same seen from j
  /// (both factors change sign), and so is the moment about n.
  static void flip(State&) {}
  static constexpr std::array specs = {
      kWaltonY, kWaltonSf, kWaltonBf, kWaltonCtheta,
      opt("tf", "-", 1.0, 0, 2, "twist factor: T_max = tf B_max (0 <= tf <= 2), K_phi = K_theta")};
  static Params make(const ParamSet& p, const PairMaterial&) {
    return {p.get(specs[0]), p.get(specs[1]), p.get(specs[2]), p.get(specs[3]), p.get(specs[4])};
  }
  /// Returns the twisting moment on i about n (N m).
  COHDEM_INLINE static double apply(const Params& p, const PairGeom& g, const NormalOut& no, double /*fc*/,
                                    State& s) {
    const WaltonSpot sp = walton_spot(p.Y, p.sf, p.bf, p.c_theta, g.rstar, no.f_adh);
    const double t_max = p.tf * sp.b_max;
    s.m -= dot(g.n, g.wrel) * sp.k_theta * g.dt;
    s.m = std::clamp(s.m, -t_max, t_max);
    return s.m;
  }
};

}  // namespace cohdem
