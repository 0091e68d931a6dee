#include "analysis/packing_profile.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

namespace cohdem {

namespace {

void check_spheres(std::span<const Vec3> centers, std::span<const double> radii,
                   const char* who) {
  if (centers.size() != radii.size())
    throw std::invalid_argument(std::string(who) + ": centers and radii differ in length (" +
                                std::to_string(centers.size()) + " vs " +
                                std::to_string(radii.size()) + ")");
  for (double r : radii)
    if (!(r >= 0) || !std::isfinite(r))
      throw std::invalid_argument(std::string(who) + ": radii must be finite and >= 0");
}

// Gauss-Legendre nodes/weights on [0, 1] (Newton on P_n; exact for degree 2n - 1).
template <int N>
struct GaussLegendre01 {
  std::array<double, N> x{}, w{};
  GaussLegendre01() {
    for (int i = 0; i < N; ++i) {
      double z = std::cos(M_PI * (i + 0.75) / (N + 0.5)), dp = 0;
      for (int it = 0; it < 100; ++it) {
        double p0 = 1, p1 = 0;
        for (int k = 1; k <= N; ++k) {
          const double p2 = p1;
          p1 = p0;
          p0 = ((2.0 * k - 1.0) * z * p1 - (k - 1.0) * p2) / k;
        }
        dp = N * (z * p0 - p1) / (z * z - 1.0);
        const double dz = p0 / dp;
        z -= dz;
        if (std::abs(dz) < 1e-16) break;
      }
      x[i] = 0.5 * (1.0 - z);
      w[i] = 1.0 / ((1.0 - z * z) * dp * dp);  // = 2/((1-z^2) P'^2) on [-1,1], halved
    }
  }
};

}  // namespace

double sphere_slab_volume(double R, double a, double b) {
  a = std::max(a, -R);
  b = std::min(b, R);
  if (!(b > a)) return 0.0;
  // Cross-section at height z is a disk of area pi (R^2 - z^2); integrate from a to b.
  return M_PI * (R * R * (b - a) - (b * b * b - a * a * a) / 3.0);
}

double disk_intersection_area(double r, double rho, double d) {
  if (r <= 0 || rho <= 0) return 0.0;
  d = std::abs(d);
  if (d >= r + rho) return 0.0;
  if (d <= std::abs(r - rho)) {
    const double m = std::min(r, rho);
    return M_PI * m * m;
  }
  // Lens: r^2 acos((d^2 + r^2 - rho^2)/(2 d r)) + rho^2 acos((d^2 + rho^2 - r^2)/(2 d rho))
  //       - 1/2 sqrt((-d + r + rho)(d + r - rho)(d - r + rho)(d + r + rho)).
  const double c1 = std::clamp((d * d + r * r - rho * rho) / (2 * d * r), -1.0, 1.0);
  const double c2 = std::clamp((d * d + rho * rho - r * r) / (2 * d * rho), -1.0, 1.0);
  const double k = (-d + r + rho) * (d + r - rho) * (d - r + rho) * (d + r + rho);
  return r * r * std::acos(c1) + rho * rho * std::acos(c2) - 0.5 * std::sqrt(std::max(0.0, k));
}

namespace {

void check_axis_range(int axis, double lo, double hi, double area, const char* who) {
  if (axis < 0 || axis > 2)
    throw std::invalid_argument(std::string(who) + ": axis must be 0, 1 or 2");
  if (!(hi > lo)) throw std::invalid_argument(std::string(who) + ": need hi > lo");
  if (!(area > 0))
    throw std::invalid_argument(std::string(who) + ": cross_section_area must be > 0");
}

}  // namespace

Profile solids_fraction_profile(std::span<const Vec3> centers, std::span<const double> radii,
                                int axis, double lo, double hi, int nbins,
                                double cross_section_area) {
  check_spheres(centers, radii, "solids_fraction_profile");
  check_axis_range(axis, lo, hi, cross_section_area, "solids_fraction_profile");
  if (nbins < 1) throw std::invalid_argument("solids_fraction_profile: nbins must be >= 1");
  Profile p;
  p.edges.resize(nbins + 1);
  p.fraction.assign(nbins, 0.0);
  const double dz = (hi - lo) / nbins;
  for (int i = 0; i <= nbins; ++i) p.edges[i] = lo + dz * i;
  p.edges[nbins] = hi;
  for (std::size_t s = 0; s < centers.size(); ++s) {
    const double R = radii[s], zc = centers[s][axis];
    if (R <= 0 || zc + R <= lo || zc - R >= hi) continue;
    const int i0 = std::max(0, int(std::floor((zc - R - lo) / dz)));
    const int i1 = std::min(nbins - 1, int(std::floor((zc + R - lo) / dz)));
    for (int i = i0; i <= i1; ++i)
      p.fraction[i] += sphere_slab_volume(R, p.edges[i] - zc, p.edges[i + 1] - zc);
  }
  for (int i = 0; i < nbins; ++i)
    p.fraction[i] /= cross_section_area * (p.edges[i + 1] - p.edges[i]);
  return p;
}

double mean_solids_fraction(std::span<const Vec3> centers, std::span<const double> radii,
                            int axis, double lo, double hi, double cross_section_area) {
  check_spheres(centers, radii, "mean_solids_fraction");
  check_axis_range(axis, lo, hi, cross_section_area, "mean_solids_fraction");
  double v = 0;
  for (std::size_t s = 0; s < centers.size(); ++s)
    v += sphere_slab_volume(radii[s], lo - centers[s][axis], hi - centers[s][axis]);
  return v / (cross_section_area * (hi - lo));
}

// Radial profile. In the plane normal to the axis at axial offset z from a sphere's centre,
// the sphere's section is a disk of radius rho(z) = sqrt(R^2 - z^2) whose centre is at
// distance d from the axis; its area inside the cylinder r < r_j is the exact lens area
// A_j(z) = disk_intersection_area(r_j, rho(z), d), so shell j holds A_{j+1} - A_j. Only the
// axial integral is numerical. A_j(z) is smooth except where circle r_j and the section
// become tangent (rho = |r_j - d| or rho = r_j + d), where it behaves like |z - z_b|^(3/2),
// and at the poles. We split [z_a, z_b] at all these z, map each piece by the cubic
// z = z0 + (z1 - z0)(3t^2 - 2t^3) (which turns the (z - z_b)^(3/2) and sqrt ends into smooth
// functions of t) and apply 16-point Gauss-Legendre in t. Where a section lies wholly inside
// one shell the integrand pi (R^2 - z^2) maps to a degree-8 polynomial in t and is integrated
// exactly, so each sphere's volume inside r_max is conserved to rounding. Measured error of
// single bins against an adaptive reference: ~2e-11 of the sphere volume; the test bounds it
// by 1e-9 (test_packing_profile.cpp). Cost: ~16 x (pieces) x (edges cut) lens evaluations
// per sphere.
Profile radial_solids_fraction_profile(std::span<const Vec3> centers,
                                       std::span<const double> radii, Vec3 axis_point,
                                       Vec3 axis_dir, double z_lo, double z_hi, double r_max,
                                       int nbins) {
  check_spheres(centers, radii, "radial_solids_fraction_profile");
  if (!(norm(axis_dir) > 0))
    throw std::invalid_argument("radial_solids_fraction_profile: axis_dir must be non-zero");
  if (!(z_hi > z_lo))
    throw std::invalid_argument("radial_solids_fraction_profile: need z_hi > z_lo");
  if (!(r_max > 0))
    throw std::invalid_argument("radial_solids_fraction_profile: r_max must be > 0");
  if (nbins < 1)
    throw std::invalid_argument("radial_solids_fraction_profile: nbins must be >= 1");
  static const GaussLegendre01<16> gl;
  const Vec3 u = normalized(axis_dir);
  const double dr = r_max / nbins;
  Profile p;
  p.edges.resize(nbins + 1);
  for (int i = 0; i <= nbins; ++i) p.edges[i] = dr * i;
  p.edges[nbins] = r_max;
  std::vector<double> vol(nbins, 0.0), brk, area;
  for (std::size_t s = 0; s < centers.size(); ++s) {
    const double R = radii[s];
    if (R <= 0) continue;
    const Vec3 rel = centers[s] - axis_point;
    const double zc = dot(rel, u);
    const double d = norm(rel - zc * u);
    const double za = std::max(-R, z_lo - zc), zb = std::min(R, z_hi - zc);
    if (!(zb > za) || d - R >= r_max) continue;
    // Edges that can cut the sphere: j0..j1 (edges below j0 never reach it: A = 0; the
    // sphere's section is wholly inside edges above j1).
    const int j0 = std::max(0, int(std::floor((d - R) / dr)));
    const int j1 = std::min(nbins, int(std::ceil((d + R) / dr)));
    brk.assign({za, zb});
    for (int j = j0; j <= j1; ++j) {
      for (double v : {std::abs(p.edges[j] - d), p.edges[j] + d}) {
        if (v >= R) continue;
        const double zt = std::sqrt(R * R - v * v);
        for (double z : {-zt, zt})
          if (z > za && z < zb) brk.push_back(z);
      }
    }
    std::sort(brk.begin(), brk.end());
    area.assign(j1 - j0 + 1, 0.0);
    for (std::size_t k = 0; k + 1 < brk.size(); ++k) {
      const double z0 = brk[k], h = brk[k + 1] - brk[k];
      if (!(h > 0)) continue;
      for (int q = 0; q < 16; ++q) {
        const double t = gl.x[q];
        const double z = z0 + h * t * t * (3.0 - 2.0 * t);
        const double w = gl.w[q] * h * 6.0 * t * (1.0 - t);
        const double rho = std::sqrt(std::max(0.0, R * R - z * z));
        for (int j = j0; j <= j1; ++j) area[j - j0] = disk_intersection_area(p.edges[j], rho, d);
        for (int j = j0; j < j1; ++j) vol[j] += w * (area[j + 1 - j0] - area[j - j0]);
      }
    }
  }
  p.fraction.resize(nbins);
  const double hz = z_hi - z_lo;
  for (int i = 0; i < nbins; ++i) {
    const double r0 = p.edges[i], r1 = p.edges[i + 1];
    p.fraction[i] = vol[i] / (M_PI * (r1 * r1 - r0 * r0) * hz);
  }
  return p;
}

}  // namespace cohdem
