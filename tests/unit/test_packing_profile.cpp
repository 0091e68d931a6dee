// Solids-fraction profiles: lattices with known packing fractions (simple cubic pi/6, fcc
// pi/(3 sqrt 2)), volume conservation, and the radial quadrature against references.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <vector>

#include "analysis/packing_profile.hpp"

using namespace cohdem;

namespace {
double sphere_volume(double R) { return 4.0 / 3.0 * M_PI * R * R * R; }
}  // namespace

TEST(PackingProfile, SphereSlabVolume) {
  const double R = 0.7;
  EXPECT_NEAR(sphere_slab_volume(R, -1, 1), sphere_volume(R), 1e-15);
  EXPECT_NEAR(sphere_slab_volume(R, 0, 5), sphere_volume(R) / 2, 1e-15);
  // Cap of height h: pi h^2 (R - h/3) (independent textbook form).
  for (double h : {0.05, 0.3, 0.7, 1.2})
    EXPECT_NEAR(sphere_slab_volume(R, R - h, R), M_PI * h * h * (R - h / 3), 1e-14) << h;
  EXPECT_EQ(sphere_slab_volume(R, 0.8, 0.9), 0.0);
}

TEST(PackingProfile, DiskIntersectionArea) {
  EXPECT_NEAR(disk_intersection_area(1, 1, 1), 2 * M_PI / 3 - std::sqrt(3.0) / 2, 1e-14);
  EXPECT_NEAR(disk_intersection_area(1, 1, std::sqrt(2.0)), M_PI / 2 - 1, 1e-14);
  EXPECT_NEAR(disk_intersection_area(2, 1, 0.5), M_PI, 1e-15);
  EXPECT_NEAR(disk_intersection_area(0.5, 1, 0.3), M_PI * 0.25, 1e-15);
  EXPECT_EQ(disk_intersection_area(1, 1, 2.5), 0.0);
  EXPECT_EQ(disk_intersection_area(0, 1, 0.1), 0.0);
}

// A single sphere's slab profile integrates back to its volume (bins not aligned with it).
TEST(PackingProfile, SingleSphereSlabConservesVolume) {
  const std::vector<Vec3> c{{0.1, 0.33, -5}};
  const std::vector<double> r{0.7};
  for (int axis : {1}) {
    const auto p = solids_fraction_profile(c, r, axis, -1.0, 2.0, 7, 2.5);
    double v = 0;
    for (std::size_t i = 0; i < p.fraction.size(); ++i)
      v += p.fraction[i] * 2.5 * (p.edges[i + 1] - p.edges[i]);
    EXPECT_NEAR(v, sphere_volume(0.7), 1e-14);
  }
}

// Simple cubic: spheres of diameter a at cell centres in [0, 4a]^3.
// Whole-cell bins hold 16 whole spheres each: fraction = (pi a^3/6)/a^3 = pi/6.
// Quarter-cell bin [0, a/4]: caps of height h = R/2, pi h^2 (R - h/3) = 5 pi R^3/24 per
// sphere, over a^3/4 per sphere: 5 pi/48 = 0.32725.
TEST(PackingProfile, SimpleCubicLattice) {
  const double a = 0.002, R = a / 2;
  const int n = 4;
  std::vector<Vec3> c;
  std::vector<double> r;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        c.push_back({(i + 0.5) * a, (j + 0.5) * a, (k + 0.5) * a});
        r.push_back(R);
      }
  const double A = (n * a) * (n * a);
  for (int axis = 0; axis < 3; ++axis) {
    const auto p = solids_fraction_profile(c, r, axis, 0, n * a, n, A);
    for (double f : p.fraction) EXPECT_NEAR(f, M_PI / 6, 1e-12);
    const auto q = solids_fraction_profile(c, r, axis, 0, n * a, 4 * n, A);
    EXPECT_NEAR(q.fraction[0], 5 * M_PI / 48, 1e-12);
    EXPECT_NEAR(q.fraction[1], (M_PI / 6) * 2 - 5 * M_PI / 48, 1e-12);  // rest of the half cell
    EXPECT_NEAR(mean_solids_fraction(c, r, axis, a, 3 * a, A), M_PI / 6, 1e-12);
    EXPECT_NEAR(mean_solids_fraction(c, r, axis, 0, n * a, A), 0.5235987756, 1e-9);
  }
}

// fcc: cubic cell a with 4 spheres of radius a sqrt(2)/4 (touching along face diagonals).
// Laterally periodic 3x3 cells (each sphere once, centres in [0, 3a)^2), z cells -2..5, so
// any slab of whole cells in [0, 3a] has fraction 4 (4/3 pi R^3)/a^3 = pi/(3 sqrt 2).
TEST(PackingProfile, FccLattice) {
  const double a = 0.003, R = a * std::sqrt(2.0) / 4;
  const Vec3 basis[4] = {{0, 0, 0}, {0, 0.5, 0.5}, {0.5, 0, 0.5}, {0.5, 0.5, 0}};
  std::vector<Vec3> c;
  std::vector<double> r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = -2; k <= 5; ++k)
        for (const auto& b : basis) {
          c.push_back(a * Vec3{i + b.x, j + b.y, k + b.z});
          r.push_back(R);
        }
  const double A = 9 * a * a, expect = M_PI / (3 * std::sqrt(2.0));
  EXPECT_NEAR(expect, 0.7405, 1e-4);
  const auto p = solids_fraction_profile(c, r, 2, 0, 3 * a, 3, A);
  for (double f : p.fraction) EXPECT_NEAR(f, expect, 1e-12);
  EXPECT_NEAR(mean_solids_fraction(c, r, 2, a, 2 * a, A), expect, 1e-12);
  // Half-cell bins: each contains one layer's upper halves and the next layer's lower halves.
  const auto q = solids_fraction_profile(c, r, 2, 0, 3 * a, 6, A);
  for (double f : q.fraction) EXPECT_NEAR(f, expect, 1e-12);
}

TEST(PackingProfile, SlabErrors) {
  const std::vector<Vec3> c{{0, 0, 0}};
  const std::vector<double> r{1.0};
  EXPECT_THROW(solids_fraction_profile(c, r, 3, 0, 1, 2, 1), std::invalid_argument);
  EXPECT_THROW(solids_fraction_profile(c, r, 2, 1, 0, 2, 1), std::invalid_argument);
  EXPECT_THROW(solids_fraction_profile(c, r, 2, 0, 1, 0, 1), std::invalid_argument);
  EXPECT_THROW(solids_fraction_profile(c, r, 2, 0, 1, 2, 0), std::invalid_argument);
  EXPECT_THROW(solids_fraction_profile(c, std::vector<double>{}, 2, 0, 1, 2, 1),
               std::invalid_argument);
}

// Sphere on the axis: the volume inside the cylinder r < rc is exact,
// V(rc) = 4/3 pi [R^3 - (R^2 - rc^2)^(3/2)] for rc <= R.
TEST(RadialProfile, OnAxisSphereExact) {
  const double R = 1e-3, rmax = 1.5e-3;
  const int nb = 6;
  const std::vector<Vec3> c{{0.2, -0.1, 0.5}};
  const std::vector<double> r{R};
  const auto p = radial_solids_fraction_profile(c, r, {0.2, -0.1, 0.0}, {0, 0, 2}, 0.0, 1.0,
                                                rmax, nb);
  auto Vin = [&](double rc) {
    rc = std::min(rc, R);
    return 4.0 / 3.0 * M_PI * (R * R * R - std::pow(R * R - rc * rc, 1.5));
  };
  for (int i = 0; i < nb; ++i) {
    const double r0 = p.edges[i], r1 = p.edges[i + 1];
    const double v = p.fraction[i] * M_PI * (r1 * r1 - r0 * r0) * 1.0;
    EXPECT_NEAR(v, Vin(r1) - Vin(r0), 1e-12 * sphere_volume(R)) << i;
  }
}

namespace {

// Adaptive Simpson, used only as an independent check of the radial quadrature.
double simpson(const std::function<double(double)>& f, double a, double b, double fa, double fm,
               double fb, double whole, double tol, int depth) {
  const double m = 0.5 * (a + b), lm = 0.5 * (a + m), rm = 0.5 * (m + b);
  const double flm = f(lm), frm = f(rm);
  const double left = (m - a) / 6 * (fa + 4 * flm + fm), right = (b - m) / 6 * (fm + 4 * frm + fb);
  if (depth <= 0 || std::abs(left + right - whole) <= 15 * tol)
    return left + right + (left + right - whole) / 15;
  return simpson(f, a, m, fa, flm, fm, left, tol / 2, depth - 1) +
         simpson(f, m, b, fm, frm, fb, right, tol / 2, depth - 1);
}
double integrate(const std::function<double(double)>& f, double a, double b, double tol) {
  const double fa = f(a), fb = f(b), fm = f(0.5 * (a + b));
  return simpson(f, a, b, fa, fm, fb, (b - a) / 6 * (fa + 4 * fm + fb), tol, 60);
}

}  // namespace

// Off-axis spheres on a tilted axis, one clipped axially: each shell's solid volume against
// (1) an adaptive-Simpson integral of the same lens areas (checks the quadrature: measured 2e-11, bound 1e-9 of
// the sphere volume) and (2) an independent double midpoint integral of the arc length of
// each circle r inside the sphere section, V = int dz int r L(r) dr with
// L = 2 acos((r^2 + d^2 - rho^2)/(2 r d)) (checks the lens formula; its midpoint error is ~1e-6, bound 1e-5).
TEST(RadialProfile, OffAxisAgainstReferences) {
  const Vec3 p0{0.01, 0.02, -0.03}, dir{1, 1, 1};
  const Vec3 u = normalized(dir), e = normalized(cross(u, Vec3{0, 0, 1}));
  const double R = 1e-3, rmax = 4e-3, z_lo = 0.0, z_hi = 0.01;
  const int nb = 8;
  struct Case { double zc, d; };
  for (const Case cs : {Case{0.005, 1.3e-3}, Case{0.004, 0.25e-3}, Case{0.0004, 2.0e-3},
                        Case{0.006, 3.5e-3}}) {
    const std::vector<Vec3> c{p0 + cs.zc * u + cs.d * e};
    const std::vector<double> r{R};
    const auto prof = radial_solids_fraction_profile(c, r, p0, dir, z_lo, z_hi, rmax, nb);
    const double za = std::max(-R, z_lo - cs.zc), zb = std::min(R, z_hi - cs.zc);
    double total = 0;
    for (int i = 0; i < nb; ++i) {
      const double r0 = prof.edges[i], r1 = prof.edges[i + 1];
      const double v = prof.fraction[i] * M_PI * (r1 * r1 - r0 * r0) * (z_hi - z_lo);
      total += v;
      auto g = [&](double z) {
        const double rho = std::sqrt(std::max(0.0, R * R - z * z));
        return disk_intersection_area(r1, rho, cs.d) - disk_intersection_area(r0, rho, cs.d);
      };
      const double ref = integrate(g, za, zb, 1e-17);
      EXPECT_NEAR(v, ref, 1e-9 * sphere_volume(R)) << "d=" << cs.d << " bin " << i;
      // Independent arc-length double integral (coarse).
      const int nz = 800, nr = 800;
      double vm = 0;
      for (int iz = 0; iz < nz; ++iz) {
        const double z = za + (zb - za) * (iz + 0.5) / nz;
        const double rho = std::sqrt(std::max(0.0, R * R - z * z));
        double s = 0;
        for (int ir = 0; ir < nr; ++ir) {
          const double rr = r0 + (r1 - r0) * (ir + 0.5) / nr;
          double L;
          if (rr + cs.d <= rho) L = 2 * M_PI;
          else if (rr >= cs.d + rho || rr <= cs.d - rho) L = 0;
          else L = 2 * std::acos(std::clamp((rr * rr + cs.d * cs.d - rho * rho) / (2 * rr * cs.d), -1.0, 1.0));
          s += rr * L;
        }
        vm += s * (r1 - r0) / nr;
      }
      vm *= (zb - za) / nz;
      EXPECT_NEAR(v, vm, 1e-5 * sphere_volume(R)) << "d=" << cs.d << " bin " << i;
    }
    // Conservation: wholly inside r_max, the shells add up to the (axially clipped) volume.
    if (cs.d + R <= rmax)
      EXPECT_NEAR(total, sphere_slab_volume(R, za, zb), 1e-13 * sphere_volume(R));
  }
}

TEST(RadialProfile, Errors) {
  const std::vector<Vec3> c{{0, 0, 0}};
  const std::vector<double> r{1.0};
  EXPECT_THROW(radial_solids_fraction_profile(c, r, {}, {0, 0, 0}, 0, 1, 1, 2),
               std::invalid_argument);
  EXPECT_THROW(radial_solids_fraction_profile(c, r, {}, {0, 0, 1}, 1, 0, 1, 2),
               std::invalid_argument);
  EXPECT_THROW(radial_solids_fraction_profile(c, r, {}, {0, 0, 1}, 0, 1, 0, 2),
               std::invalid_argument);
  EXPECT_THROW(radial_solids_fraction_profile(c, r, {}, {0, 0, 1}, 0, 1, 1, 0),
               std::invalid_argument);
}
