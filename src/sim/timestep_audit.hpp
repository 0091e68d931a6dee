// Time-step audit: compares dt with the Rayleigh-wave time of each species and with the
// collision time of each material pair at the audit velocity.
//
// Rayleigh time (Li, Xu & Thornton 2005; Ning & Ghadiri): T_R = pi r_min sqrt(rho/G) /
//   (0.1631 nu + 0.8766), G = E/(2(1+nu)); only for materials with E given.
// Collision time: the two smallest particles of the pair collide at v_audit; the contact
//   law is driven quasi-statically to the overlap that stores 1/2 m* v^2, and the stiffest
//   of the loading tangent and the unloading slope there gives t_c = pi sqrt(m*/k). For
//   Hertz this is 22% shorter than Hertz's exact duration (conservative); for plastic laws it
//   sees the stiff unloading branch.
// Rolling time: the half period pi sqrt(I_eff/k_rot) of the rolling (or bending) spring of
//   the same pair at the overlap of that collision, k_rot its moment per radian of relative
//   rotation (probed through the law: SDS's k_r R*^2, EPSD's k_r, Walton's k_theta) and
//   I_eff = I_i I_j/(I_i + I_j) (I_i against a wall). SDS's k_r and Walton's bending
//   stiffness are the user's, not tied to kn, so a stiff one can need a shorter step than
//   the collision; EPSD's is slower than the collision unless mu_r > 0.84.
// Levels: warn when dt > 0.2 T_R or dt > t_c/20 (fewer than 20 steps per collision) or
//   fewer than 20 steps per half period of the rolling spring; error when dt > 0.5 T_R or
//   dt > t_c/8 or fewer than 8 steps per rolling half period.
#pragma once
#include <string>
#include <vector>

#include "sim/system.hpp"

namespace cohdem {

struct TimestepAudit {
  enum Level { Ok, Warn, Error };
  double dt = 0;
  double rayleigh = 0;          ///< smallest Rayleigh time, s (0: no material with E)
  std::string rayleigh_material;
  double collision = 0;         ///< smallest collision time, s (0: none evaluated)
  std::string collision_pair;
  double rolling = 0;           ///< smallest half period of a rolling spring, s (0: none)
  std::string rolling_pair;
  double velocity = 0;          ///< audit velocity, m/s
  Level level = Ok;
  std::vector<std::string> messages;
};

/// `rmin[m]` is the smallest radius of material m among particles (0 if none).
TimestepAudit audit_timestep(const System& s, const std::vector<double>& rmin, double v_audit);

/// Warn/error thresholds (fractions), exposed for documentation and tests.
inline constexpr double kWarnRayleigh = 0.2, kErrorRayleigh = 0.5;
inline constexpr double kWarnStepsPerCollision = 20, kErrorStepsPerCollision = 8;

}  // namespace cohdem
