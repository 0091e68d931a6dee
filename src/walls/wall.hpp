// Walls: infinite or bounded planes and cylinders (particles inside or outside), moving by
// prescribed translation, rotation about their own symmetry axis and sinusoidal oscillation,
// or controlled along their normal (servo to a target force, or a floating spring-loaded
// lid). Walls use the same contact laws as particles, with their own material (friction etc.
// set per material pair). An annulus is two coaxial cylinders (see io/case_file.cpp).
#pragma once
#include <cmath>
#include <string>

#include "core/vec3.hpp"

namespace cohdem {

enum class WallShape { Plane, Cylinder };
enum class WallControl { Prescribed, Servo, Spring };

struct Wall {
  std::string name;
  WallShape shape = WallShape::Plane;
  int material = 0;  ///< index into the material table (species first, then wall materials)

  // Geometry (moves with the wall).
  Vec3 point;        ///< plane: a point on it; cylinder: a point on the axis
  Vec3 normal{0, 0, 1};  ///< plane: unit normal towards the particles; cylinder: unit axis
  double radius = 0;     ///< cylinder radius, m
  bool inside = true;    ///< cylinder: particles inside (true) or outside (false)
  double rmin = 0, rmax = INFINITY;       ///< plane: annular bounds around `point`, m
  double zmin = -INFINITY, zmax = INFINITY;  ///< cylinder: axial bounds relative to `point`, m

  // Prescribed motion.
  Vec3 velocity;     ///< translation velocity, m/s
  Vec3 omega;        ///< angular velocity about `center` (parallel to normal/axis), rad/s
  Vec3 center;       ///< a point on the rotation axis (moves with the wall)
  double osc_amplitude = 0, osc_frequency = 0;  ///< x(t) += A sin(2 pi f t) osc_dir
  Vec3 osc_dir{0, 0, 1};

  // Control along the normal (plane walls).
  WallControl control = WallControl::Prescribed;
  double control_start = 0;  ///< s: the control acts from this time on (held still before)
  double target_force = 0;   ///< servo: compressive load to hold, N
  double servo_gain = 0;     ///< servo: m/(N s)
  double servo_vmax = INFINITY;  ///< servo: speed limit, m/s
  double mass = 0;           ///< spring lid: mass, kg
  double spring_k = 0;       ///< spring lid: stiffness, N/m
  double spring_preload = 0; ///< spring lid: force at the start position, N
  double travel = 0;         ///< displacement along normal since start, m (output)
  double vn = 0;             ///< normal speed of a controlled wall, m/s

  // Totals from the last force evaluation (force and torque exerted BY particles ON the wall;
  // torque about `center`).
  Vec3 force, torque;

  Vec3 osc_velocity(double t) const {
    if (osc_amplitude == 0) return {};
    const double w = 2 * M_PI * osc_frequency;
    return osc_dir * (osc_amplitude * w * std::cos(w * t));
  }
  /// Velocity of the wall material at point c at time t.
  Vec3 velocity_at(const Vec3& c, double t) const {
    return velocity + osc_velocity(t) + normal * vn + cross(omega, c - center);
  }

  /// Signed gap between a sphere (x, r) and the wall: overlap delta = -gap... returns false
  /// when the sphere is outside the wall's bounds. n points from the wall to the sphere.
  bool contact(const Vec3& x, double r, Vec3& n, double& delta) const {
    const Vec3 d = x - point;
    if (shape == WallShape::Plane) {
      const double s = dot(d, normal);
      if (rmin > 0 || rmax < INFINITY) {
        const double rho = norm(d - normal * s);
        if (rho < rmin || rho > rmax) return false;
      }
      n = normal;
      delta = r - s;
      return true;
    }
    const double z = dot(d, normal);
    if (z < zmin || z > zmax) return false;
    const Vec3 rho = d - normal * z;
    const double s = norm(rho);
    if (s <= 0) return false;
    if (inside) {
      n = rho * (-1.0 / s);
      delta = r + s - radius;
    } else {
      n = rho * (1.0 / s);
      delta = r - (s - radius);
    }
    return true;
  }

  /// How far the wall's geometry moved (not counting motion within its own surface).
  double geometric_displacement(const Vec3& dx) const {
    if (shape == WallShape::Plane) return std::fabs(dot(dx, normal));
    return norm(dx - normal * dot(dx, normal));
  }
};

}  // namespace cohdem
