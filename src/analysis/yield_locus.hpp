// Ring shear test evaluation as in ASTM D6773 and Schulze, "Powders and Bulk Solids"
// (2008/2021), ch. 3-4 (RST-CONTROL conventions). Stresses in Pa, compression positive,
// shear stress positive in the shear direction; angles in radians (use to_degrees()).
#pragma once
#include <cstddef>
#include <optional>
#include <span>
#include <string>

namespace cohdem {

constexpr double to_degrees(double rad) { return rad * 57.295779513082320877; }
constexpr double to_radians(double deg) { return deg / 57.295779513082320877; }

/// One point (normal stress, shear stress) of a shear test, Pa.
struct ShearPoint {
  double sigma = 0;
  double tau = 0;
};

/// Everything RST-CONTROL reports for one yield locus.
struct YieldLocusResult {
  // Linearized yield locus tau = tan(phi_lin) sigma + cohesion, least squares through the
  // shear-to-failure points only (the pre-shear point is not part of the fit).
  double phi_lin = 0;      ///< angle of internal friction of the linearized yield locus, rad
  double cohesion = 0;     ///< tau intercept tau_c, Pa (may be < 0 for noisy free-flowing data)
  double r_squared = 0;    ///< coefficient of determination of the fit
  std::size_t n_points = 0;
  double sigma_c = 0;      ///< unconfined yield strength, Pa (0 when cohesion <= 0)
  double sigma_1 = 0;      ///< major consolidation stress (steady-state Mohr circle), Pa
  double sigma_2 = 0;      ///< minor principal stress of that circle, Pa
  double sigma_tangent = 0;  ///< sigma where the steady-state circle touches the yield locus, Pa
  double ffc = 0;          ///< flow function sigma_1/sigma_c; +infinity when ffc_infinite
  bool ffc_infinite = false;  ///< true when cohesion <= 0 (sigma_c = 0): no finite ffc
  double phi_e = 0;        ///< effective angle of internal friction, rad
  double phi_sf = 0;       ///< steady-state-flow angle atan(tau_pre/sigma_pre), rad
  std::optional<double> bulk_density;  ///< kg/m^3, passed through when given
  /// The pre-shear point lay above the locus and the limiting circle (tangent at the pre-shear
  /// point to the locus moved up through it) was used (allow_preshear_above).
  bool preshear_above_locus = false;
  /// False when the steady-state circle through the pre-shear point and tangent to the locus
  /// reaches into tension (sigma_2 < 0: the consolidation stress too low for the locus's
  /// cohesion). sigma_1, sigma_2, sigma_tangent, phi_e and ffc are then NaN (ffc_infinite
  /// false) and steady_state_error says why; the locus (phi_lin, cohesion, r_squared), sigma_c
  /// and phi_sf do not depend on that circle and are given as usual.
  bool steady_state = true;
  std::string steady_state_error;
};

/// Evaluates one yield locus. Throws std::invalid_argument for fewer than 2 shear points,
/// shear points all at the same sigma, a non-positive slope, a pre-shear point with
/// sigma_pre <= 0, a pre-shear point above the linearized yield locus (no Mohr circle through
/// it can be tangent to the locus; unless allow_preshear_above, which then takes the circle
/// tangent at the pre-shear point to the line of the locus's slope through it). A
/// steady-state circle with sigma_2 < 0 is not an error: see YieldLocusResult::steady_state.
YieldLocusResult evaluate_yield_locus(ShearPoint pre_shear,
                                      std::span<const ShearPoint> shear_points,
                                      std::optional<double> bulk_density = std::nullopt,
                                      bool allow_preshear_above = false);

/// Largest tau in the phase t_begin <= t <= t_end (shear to failure: the failure point).
struct ShearPeak {
  std::size_t index = 0;  ///< index into the series
  double t = 0;
  double tau = 0;
};
ShearPeak shear_peak(std::span<const double> t, std::span<const double> tau, double t_begin,
                     double t_end);

/// Steady-state value of a pre-shear phase: mean of tau over the last `last_fraction` of the
/// phase duration [t_begin, t_end]. Steadiness: relative_drift = |slope| * (t_last - t_first)
/// / |mean| (least-squares slope over the same window, i.e. the relative change across the
/// averaging window) must be <= max_relative_drift.
struct SteadyState {
  double mean = 0;
  double slope = 0;           ///< d tau/dt over the window, Pa/s
  double relative_drift = 0;  ///< dimensionless; +infinity if mean == 0 and slope != 0
  bool steady = false;
  std::size_t n_used = 0;
};
SteadyState steady_state_value(std::span<const double> t, std::span<const double> tau,
                               double t_begin, double t_end, double last_fraction = 0.25,
                               double max_relative_drift = 0.01);

}  // namespace cohdem
