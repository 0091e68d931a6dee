// Shared pieces of Walton's plastic-cohesive model (seed 001, "New cohesion model with
// bending moments"): the keys every mode reads and the contact-spot geometry.
//
// Radius convention (OPEN, decided): the paper's spot radius a ~ sqrt(R alpha) and
// K_R ~ 2 pi Y R are written for equal spheres of radius R. The geometric truncation of two
// spheres (or a sphere on a wall) gives a^2 = 2 R* alpha for any pair, so R is read as 2 R*:
//   K_R = 2 pi Y (2 R*) = 4 pi Y R*,   K'_R = sf K_R
// (equal spheres: 2 R* = R, the paper's value; sphere on a wall: a^2 = 2 R alpha). Users who
// want R* instead set sf = 0.5: sf is a pure multiplier on K_R.
// Bending spot (paper): the radius where the plastic repulsion equals the pull-off force,
// widened by bf:  a'_b^2 = bf^2 (2 R*) Fc / K'_R = bf^2 Fc / (2 pi sf Y)   (R* cancels),
//   B_max = Fc a'_b / 2 = bf sqrt(Fc^3 / (8 pi sf Y))    (paper, sf = 1).
// The paper has 0 < bf < 5; bf = 0 is accepted as the switch to a point contact: a'_b = 0,
// so K_theta = B_max = T_max = 0 and both moments vanish (the classical cohesive-frictional
// contact without rotational resistance that Walton compares against).
// Fc is the contact's current pull-off force, Fc0 + cf F_Rmax: the spot grows with the
// largest load, as the flattening that causes the growth of Fc.
// Bending stiffness (OPEN: the extraction loses it): a uniform bed of normal springs of total
// stiffness K'_R over the spot gives K_theta = K'_R a'_b^2 / 4 = bf^2 R* Fc / 2; c_theta
// sets K_theta = c_theta K'_R a'_b^2 (default 1/4). The garbled extraction reads like
// "K_theta = R Fc / 2" with R the particle radius, which is c_theta = 1/2 (bf = 1).
#pragma once
#include <cmath>

#include "models/params.hpp"

namespace cohdem {

inline constexpr ParamSpec kWaltonY = req("Y", "Pa", 0, kInf, "yield strength, K_R = 2 pi Y (2 R*)", true);
inline constexpr ParamSpec kWaltonSf = opt("sf", "-", 1.0, 0, kInf, "soften factor: K'_R = sf K_R", true);
inline constexpr ParamSpec kWaltonBf =
    opt("bf", "-", 1.0, 0, 5, "widen factor of the bending spot a'_b (0 <= bf <= 5; 0: no bending or twisting resistance)");
inline constexpr ParamSpec kWaltonCtheta =
    opt("c_theta", "-", 0.25, 0, kInf, "bending stiffness K_theta = c_theta K'_R a'_b^2 (1/4: spring bed)", true);

/// Plastic normal stiffness K'_R = sf 2 pi Y (2 R*), N/m.
inline double walton_kr(double Y, double sf, double rstar) { return sf * 4.0 * M_PI * Y * rstar; }

/// Bending/twisting constants of one contact.
struct WaltonSpot {
  double ab;       ///< widened spot radius a'_b, m
  double k_theta;  ///< bending (and twisting) stiffness, N m/rad
  double b_max;    ///< bending limit, N m
};
inline WaltonSpot walton_spot(double Y, double sf, double bf, double c_theta, double rstar, double Fc) {
  const double kr = walton_kr(Y, sf, rstar);
  const double ab2 = bf * bf * 2.0 * rstar * Fc / kr;
  const double ab = std::sqrt(ab2);
  return {ab, c_theta * kr * ab2, 0.5 * Fc * ab};
}

}  // namespace cohdem
