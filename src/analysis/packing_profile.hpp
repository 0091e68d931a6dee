// Solids-fraction (packing) profiles from sphere centres and radii (SI units, m).
// Slab profile: exact (spherical segment volumes). Radial profile: exact in the cross-section
// (circle-circle intersection areas), Gauss-Legendre along the axis; see the .cpp.
#pragma once
#include <span>
#include <vector>

#include "core/vec3.hpp"

namespace cohdem {

/// A 1-D profile: bin i spans [edges[i], edges[i+1]]; fraction[i] is the solids fraction
/// (solid volume / bin volume) in it.
struct Profile {
  std::vector<double> edges;
  std::vector<double> fraction;
  double centre(std::size_t i) const { return 0.5 * (edges[i] + edges[i + 1]); }
};

/// Volume of a sphere of radius R between the planes z = a and z = b measured from its
/// centre (a <= b; clipped to [-R, R]): pi [R^2 (b - a) - (b^3 - a^3)/3]. Exact.
double sphere_slab_volume(double radius, double a, double b);

/// Area of the intersection of a disk of radius r centred at the origin with a disk of
/// radius rho centred at distance d (>= 0). Exact (lens formula).
double disk_intersection_area(double r, double rho, double d);

/// Slab profile along coordinate `axis` (0 = x, 1 = y, 2 = z): nbins equal bins on [lo, hi],
/// each bin volume = cross_section_area * (hi - lo)/nbins. Every sphere counts with its full
/// cross-section, so pass the spheres (or periodic images, once each) whose centres lie in
/// the lateral domain of area cross_section_area; spheres cut by side walls are not clipped.
Profile solids_fraction_profile(std::span<const Vec3> centers, std::span<const double> radii,
                                int axis, double lo, double hi, int nbins,
                                double cross_section_area);

/// Exact mean solids fraction between the planes lo and hi (e.g. a sub-range that excludes
/// the wall layers), same conventions as solids_fraction_profile.
double mean_solids_fraction(std::span<const Vec3> centers, std::span<const double> radii,
                            int axis, double lo, double hi, double cross_section_area);

/// Radial profile in a cylinder with axis through axis_point along axis_dir (need not be
/// unit): nbins equal shells on r in [0, r_max], axial extent z in [z_lo, z_hi] measured along
/// axis_dir from axis_point. Bin volume = pi (r_{i+1}^2 - r_i^2)(z_hi - z_lo). Sphere parts
/// outside r_max or the z range are not counted. Error of each bin's solid volume below 1e-9
/// of the sphere volume (measured ~2e-11); the sum over bins is exact to rounding when a
/// sphere lies wholly within r < r_max.
Profile radial_solids_fraction_profile(std::span<const Vec3> centers,
                                       std::span<const double> radii, Vec3 axis_point,
                                       Vec3 axis_dir, double z_lo, double z_hi, double r_max,
                                       int nbins);

}  // namespace cohdem
