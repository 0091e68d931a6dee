// Particle sizes and random non-overlapping insertion (random sequential addition).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "core/rng.hpp"
#include "core/vec3.hpp"

namespace cohdem {

/// Radius distribution. Gaussian: mean and standard deviation, truncated to mean*(1 +/- bound)
/// (copper ore: mean 3.175 mm, bound 0.1 gives 2.8575..3.4925 mm) by rejection.
struct SizeDistribution {
  enum class Kind { Constant, Uniform, Gaussian, List } kind = Kind::Constant;
  double r = 0;                 ///< Constant
  double rmin = 0, rmax = 0;    ///< Uniform (and the bounds of every kind, derived)
  double mean = 0, stddev = 0, bound = 0;  ///< Gaussian
  std::vector<double> radii, weights;      ///< List (weights: number fractions)

  double sample(Rng& rng) const;
  double min_radius() const;
  double max_radius() const;
  double mean_volume() const;   ///< expected sphere volume, m^3 (for solids-fraction fills)
};

struct Region {
  enum class Kind { Box, Cylinder, Annulus } kind = Kind::Box;
  Vec3 lo, hi;                  ///< Box
  Vec3 center;                  ///< Cylinder/Annulus: base centre (axis along z)
  double r_in = 0, r_out = 0;   ///< Cylinder: r_out; Annulus: both
  double zmin = 0, zmax = 0;    ///< Cylinder/Annulus: height range (absolute z)
  std::string name;

  double volume() const;
  /// Uniform random centre for a sphere of radius r lying fully inside.
  bool sample_center(Rng& rng, double r, Vec3& x) const;
};

struct InsertSpec {
  Region region;
  SizeDistribution size;
  int species = 0;
  uint64_t count = 0;           ///< fill to a count, or ...
  double solids_fraction = 0;   ///< ... to a solids fraction of the region volume
  Vec3 velocity;                ///< initial velocity
  double velocity_jitter = 0;   ///< plus a random velocity, each component uniform in +/- this, m/s
  int max_attempts = 2000;      ///< per particle
};

struct InsertResult {
  std::vector<Vec3> x;
  std::vector<double> r;
};

/// Draws non-overlapping spheres (none overlapping `existing_x/r` either). Throws RunError
/// when a particle cannot be placed, naming the region, how many fit and the fraction reached.
InsertResult insert_random(const InsertSpec& spec, Rng& rng, const std::vector<Vec3>& existing_x,
                           const std::vector<double>& existing_r, uint64_t max_count = UINT64_MAX);

}  // namespace cohdem
