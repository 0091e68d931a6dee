// What a contact sub-model sees and writes. Sign conventions (used everywhere):
//  - n is the unit normal from j to i; delta = r_i + r_j - |x_i - x_j| > 0 in contact.
//  - A wall plays j with r_j = 0 (R* = r_i, m* = m_i); its velocity at the contact point is v_j.
//  - Normal forces are scalars with repulsion positive; the force on i is fn * n + ft.
#pragma once
#include "core/vec3.hpp"

namespace cohdem {

struct PairGeom {
  Vec3 n;            ///< unit normal, j -> i
  double delta = 0;  ///< overlap, m (negative when apart)
  double ri = 0, rj = 0;       ///< radii; rj = 0 for a wall
  double rstar = 0, mstar = 0; ///< effective radius m, effective mass kg
  double mi = 0, mj = 0;       ///< masses, kg (mj = inf for a wall)
  double Ii = 0, Ij = 0;       ///< moments of inertia, kg m^2 (Ij = inf for a wall)
  double vn = 0;     ///< (v_i - v_j) . n, m/s; negative while approaching
  Vec3 vt;           ///< tangential relative velocity of the contact points (i relative to j), m/s
  Vec3 wrel;         ///< omega_i - omega_j, rad/s
  double dt = 0;     ///< time step, s
  /// Whether NormalOut::a is read. The force loop clears it when nothing reads the contact
  /// radius (no conduction, no contact output); a normal model whose a is only geometric
  /// (sqrt(R* delta), not part of its force) may then leave a = 0 and skip the square root.
  bool want_a = true;
};

/// Output of the normal sub-model, read by damping, tangential, rolling and twisting.
struct NormalOut {
  double f_el = 0;   ///< elastic/hysteretic normal force, N (repulsive > 0, adhesive < 0)
  /// Normal stiffness, N/m (damping, rolling stiffness, time step): the tangent d f_el/d delta
  /// for elastic laws; hysteretic laws give their elastic (unloading) stiffness, JKR 2 E* a.
  double kn = 0;
  double a = 0;      ///< contact radius, m (conduction, Mindlin stiffness)
  /// Hysteretic laws: the virgin-loading coefficient times delta^(n-1), k1 delta^(n-1) (N/m),
  /// the base of their tangential stiffness (HystTangential reads it, so delta^(n-1) and k1
  /// are computed once per contact); 0 for other laws.
  double k_load = 0;
  /// Adhesive part included in f_el, as a magnitude (N, >= 0): the pull-off force an
  /// adhesive model adds (Walton Fc, JKR/DMT pull-off, MEPA/EEPA adhesive bound). Read by
  /// cohesion-offset Coulomb limits and by Walton's bending/twisting limits; 0 otherwise.
  double f_adh = 0;
  bool alive = false;///< the contact exists (history kept); false ends it and resets history
};

/// Output of one contact evaluation.
struct PairForce {
  Vec3 f;            ///< total force on i (on j: -f), N
  Vec3 ti, tj;       ///< torques on i and on j, N m
  double fn = 0;     ///< total normal force (elastic + damping), N, repulsive > 0
  double fn_el = 0;  ///< elastic/hysteretic part, N
  Vec3 ft;           ///< tangential force on i, N
  Vec3 mr;           ///< rolling (and bending) moment on i, N m
  double mt = 0;     ///< twisting moment on i about n, N m
  double a = 0;      ///< contact radius, m
};

}  // namespace cohdem
