// Small 3-vector used everywhere (positions, velocities, forces, torques). SI units.
#pragma once
#include <cmath>

namespace cohdem {

// The arithmetic below is forced inline (COHDEM_INLINE): in the force kernel's large OpenMP
// function GCC's inliner otherwise runs out of budget and leaves some of these three-line
// operators as calls (seen in its multi-thread paths).
#define COHDEM_INLINE [[gnu::always_inline]] inline

struct Vec3 {
  double x = 0, y = 0, z = 0;
  constexpr Vec3() = default;
  constexpr Vec3(double x_, double y_, double z_) : x(x_), y(y_), z(z_) {}
  constexpr double& operator[](int k) { return k == 0 ? x : (k == 1 ? y : z); }
  constexpr double operator[](int k) const { return k == 0 ? x : (k == 1 ? y : z); }
  COHDEM_INLINE constexpr Vec3& operator+=(const Vec3& o) { x += o.x; y += o.y; z += o.z; return *this; }
  COHDEM_INLINE constexpr Vec3& operator-=(const Vec3& o) { x -= o.x; y -= o.y; z -= o.z; return *this; }
  COHDEM_INLINE constexpr Vec3& operator*=(double s) { x *= s; y *= s; z *= s; return *this; }
  COHDEM_INLINE constexpr Vec3& operator/=(double s) { x /= s; y /= s; z /= s; return *this; }
};

COHDEM_INLINE constexpr Vec3 operator+(Vec3 a, const Vec3& b) { return a += b; }
COHDEM_INLINE constexpr Vec3 operator-(Vec3 a, const Vec3& b) { return a -= b; }
COHDEM_INLINE constexpr Vec3 operator-(const Vec3& a) { return {-a.x, -a.y, -a.z}; }
COHDEM_INLINE constexpr Vec3 operator*(Vec3 a, double s) { return a *= s; }
COHDEM_INLINE constexpr Vec3 operator*(double s, Vec3 a) { return a *= s; }
COHDEM_INLINE constexpr Vec3 operator/(Vec3 a, double s) { return a /= s; }
COHDEM_INLINE constexpr bool operator==(const Vec3& a, const Vec3& b) { return a.x == b.x && a.y == b.y && a.z == b.z; }
COHDEM_INLINE constexpr double dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
COHDEM_INLINE constexpr Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
COHDEM_INLINE constexpr double norm2(const Vec3& a) { return dot(a, a); }
/// c ? a : b, component by component. In the force loop GCC builds a select of whole Vec3s
/// (`v = c ? a : b`) in a stack temporary of three 8-byte stores and copies it with a 16-byte
/// load, which the store buffer cannot forward: a stall of a dozen cycles per contact (seen in
/// `perf annotate`). Three scalar selects stay in registers.
COHDEM_INLINE constexpr Vec3 select(bool c, const Vec3& a, const Vec3& b) {
  return {c ? a.x : b.x, c ? a.y : b.y, c ? a.z : b.z};
}
inline double norm(const Vec3& a) { return std::sqrt(dot(a, a)); }
inline Vec3 normalized(const Vec3& a) {
  const double l = norm(a);
  return l > 0 ? a / l : Vec3{};
}

/// Factor that brings a vector of squared length m2 back to length lim (>= 0) when it is
/// longer (a Coulomb-type limit on a spring's force or moment): lim/sqrt(m2) above the limit,
/// exactly 1 within it. Selected without a branch: whether a contact slides changes from
/// contact to contact and step to step, so a branch mispredicts. Above the limit m2 > lim^2
/// >= 0, so the square root is of a positive number; within it, of 1 (the result unused).
inline double limit_scale(double m2, double lim) {
  const bool over = m2 > lim * lim;
  return over ? lim / std::sqrt(over ? m2 : 1.0) : 1.0;
}

/// Turns a history vector h (a contact's tangential force, rolling or bending moment) into
/// the plane normal to the unit vector n, keeping its length: h -= n (n.h), then h *= (1 -
/// x)^(-1/2) with x = (n.h)^2/|h|^2. For x < 1e-4 (the contact turned by less than 0.6
/// degrees since the last step: always, in practice) the factor's series to x^3 is exact to
/// double precision (the next term, 35/128 x^4, is below 3e-17) and saves a square root on
/// the critical path of every contact; larger turns take the exact factor.
COHDEM_INLINE void rotate_into_plane(Vec3& h, const Vec3& n) {
  const double m0 = norm2(h);
  if (!(m0 > 0)) return;
  const double hn = dot(n, h);
  h -= n * hn;
  const double hn2 = hn * hn;
  if (hn2 < 1e-4 * m0) {
    const double x = hn2 / m0;
    h *= 1.0 + x * (0.5 + x * (0.375 + x * 0.3125));
  } else {
    const double m1 = norm2(h);
    if (m1 > 0) h *= std::sqrt(m0 / m1);
  }
}

}  // namespace cohdem
