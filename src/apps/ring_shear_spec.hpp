// Settings of the virtual ring shear tester ([ring_shear] table of a case file; see
// docs/ring-shear.md). Plain data, parsed in apps/ring_shear.cpp.
#pragma once
#include <cmath>
#include <string>
#include <vector>

#include "particles/insertion.hpp"

namespace cohdem {

class Section;

struct RingShearSpec {
  std::string cell = "shear_box";   ///< "shear_box" (periodic in x and y) or "annulus"
  double length = 0, width = 0;     ///< shear box: x (shear direction) and y extent, m
  double r_inner = 0, r_outer = 0;  ///< annulus radii, m
  int material = 0;                 ///< particle material
  int base_material = 0;            ///< base and lid planes, rough layers
  int wall_material = 0;            ///< annulus side walls
  SizeDistribution size;
  double bed_height = 0;            ///< target settled bed height, m
  double packing_guess = 0.55;      ///< settled solids fraction used to size the fill
  bool rough_layers = true;         ///< glued particle layers on base and lid
  double fill_kadh_fraction = 0.1;  ///< kadh during filling = fraction x k2 (MEPA family)
  double settle_time = 1.0;         ///< s, longest settling after insertion
  double settle_velocity = 0.05;    ///< settled when no particle is faster, m/s
  double approach_speed = 0.2;      ///< lid speed while it first closes on the bed, m/s
  double sigma_pre = 0;             ///< consolidation (pre-shear) normal stress, Pa
  std::vector<double> fractions{0.2, 0.4, 0.6, 0.8};  ///< shear points, fractions of sigma_pre
  double shear_velocity = 0.02;     ///< lid speed (annulus: at the mean radius), m/s
  double inertial_number_max = 0;   ///< > 0: shear_velocity from this limit (or checked against it)
  double lid_mass = 0;              ///< kg of the floating lid (0: the sample's mass)
  double tau_window = 0.0005;       ///< m of shear displacement over which tau is averaged
  double consolidate_time = 0.05;   ///< s under sigma_pre before the first pre-shear
  double first_preshear_distance = 0.01;  ///< m of shear to reach steady state the first time
  double preshear_distance = 0.005; ///< m of each later pre-shear
  double shear_distance = 0.005;    ///< m, longest shear to failure
  double steady_drift = 0.1;        ///< pre-shear steady: relative drift of tau over its last quarter
  double preshear_max_factor = 2.5; ///< a pre-shear goes on up to this many times its distance
  bool normalize_points = false;    ///< evaluate ASTM-normalized shear points (else the measured)
  double relax_time = 0.01;         ///< s at rest after changing the normal stress
  double peak_drop = 0.1;           ///< failure: averaged tau fell this fraction below its maximum
  double sample_interval = 0;       ///< s between series rows (0: 200 steps)
  int line = 0;                     ///< of [ring_shear], for errors
};

/// Inertial number of the shear, I = gamma_dot d / sqrt(sigma / rho_p), with the shear rate
/// taken over a shear band of 10 mean diameters (gamma_dot = v / (10 d)): I = v / (10
/// sqrt(sigma / rho_p)), independent of d.
inline double ring_shear_inertial_number(double v, double sigma, double rho_p) {
  return v / (10.0 * std::sqrt(sigma / rho_p));
}

/// Parses [ring_shear] (strict). `materials` names the case's materials in order,
/// `densities` gives their particle densities (kg/m^3, for the inertial-number limit).
RingShearSpec parse_ring_shear(Section& s, const std::vector<std::string>& materials, const std::vector<double>& densities);

}  // namespace cohdem
