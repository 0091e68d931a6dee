// rotate_into_plane (core/vec3.hpp): a contact's history vector turned into the new tangent
// plane keeps its length, whether the series branch (small turns) or the exact square root
// (large turns) is taken. Reference: the exact construction h - n (n.h) scaled by
// |h| / |h - n (n.h)|, evaluated in long double.
#include <gtest/gtest.h>

#include <cmath>

#include "core/rng.hpp"
#include "core/vec3.hpp"

using namespace cohdem;

namespace {

/// Rodrigues: v turned by th about the unit axis a.
Vec3 turn(const Vec3& v, const Vec3& a, double th) {
  return v * std::cos(th) + cross(a, v) * std::sin(th) + a * (dot(a, v) * (1 - std::cos(th)));
}

/// The history h of a contact whose normal was n0, after the normal turned by `angle` about
/// an axis normal to n0.
void check(double angle, int cases, double tol_len, double tol_dir) {
  Rng rng(7);
  for (int c = 0; c < cases; ++c) {
    const Vec3 n0 = normalized(Vec3{rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)});
    Vec3 h = Vec3{rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)} * 1e3;
    h -= n0 * dot(n0, h);  // in the old tangent plane
    const Vec3 axis = normalized(h);
    const Vec3 n = turn(n0, cross(n0, axis), angle);  // the normal turned towards h
    // Reference in long double.
    const long double hn = (long double)n.x * h.x + (long double)n.y * h.y + (long double)n.z * h.z;
    const long double px = h.x - n.x * hn, py = h.y - n.y * hn, pz = h.z - n.z * hn;
    const long double l0 = std::sqrt((long double)h.x * h.x + (long double)h.y * h.y + (long double)h.z * h.z);
    const long double l1 = std::sqrt(px * px + py * py + pz * pz);
    const Vec3 ref{double(px * l0 / l1), double(py * l0 / l1), double(pz * l0 / l1)};
    Vec3 r = h;
    rotate_into_plane(r, n);
    EXPECT_NEAR(norm(r) / double(l0), 1.0, tol_len) << "angle " << angle;
    EXPECT_LE(norm(r - ref) / double(l0), tol_dir) << "angle " << angle;
    // Left in the plane to round-off: the projection subtracts n (n.h), up to |h| in size,
    // so a few roundings of |h| (eps = 2.2e-16 each) remain along n: bound 4e-15.
    EXPECT_LE(std::fabs(dot(r, n)) / double(l0), 4e-15) << "angle " << angle;
  }
}

}  // namespace

// Turns of 1e-6 .. 5e-3 rad (x = sin^2 < 1e-4: series branch) and 0.02 .. 1 rad (exact
// branch). Length kept to 4 ulp (round-off of a few multiplications, 2.2e-16 each); the
// direction matches the long-double construction to the same level.
TEST(RotateHistory, KeepsLengthOnBothBranches) {
  for (double a : {1e-6, 1e-4, 1e-3, 5e-3}) check(a, 200, 9e-16, 2e-15);
  for (double a : {0.02, 0.1, 0.5, 1.0}) check(a, 200, 9e-16, 2e-15);
}

// The zero vector stays zero; a vector along n (a contact turned by 90 degrees) has no
// tangential part left and comes out zero, not NaN.
TEST(RotateHistory, DegenerateInputs) {
  Vec3 z{};
  rotate_into_plane(z, {0, 0, 1});
  EXPECT_EQ(norm(z), 0.0);
  Vec3 along{0, 0, 2};
  rotate_into_plane(along, {0, 0, 1});
  EXPECT_FALSE(std::isnan(along.x) || std::isnan(along.y) || std::isnan(along.z));
  EXPECT_EQ(norm(along), 0.0);
}
