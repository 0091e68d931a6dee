// Janssen analysis of a bed in a vertical cylinder (Walton, seed 001, Eqs. 13 and 16;
// docs/analysis.md). SI units; stresses compression positive; y is the depth below the free
// top surface (for a whole bed: the bed height, the stress acting on the base pedestal).
// mu_k is the product mu * k (wall friction times stress ratio), fitted as one parameter
// because mu and k are not measured separately.
#pragma once
#include <cstddef>
#include <optional>
#include <span>
#include <vector>

namespace cohdem {

enum class JanssenMode {
  Silo,    ///< wall friction holds the bed up (wall pulled up / bed settling): Eq. 13
  Piston,  ///< base pushes the bed up, wall friction acts down: Eq. 16
};

struct JanssenSetup {
  double rho = 0;     ///< bulk density, kg/m^3
  double g = 0;       ///< gravitational acceleration, m/s^2 (positive)
  double radius = 0;  ///< cylinder radius R, m
};

/// Vertical stress at depth y, Pa:
///   silo:   sigma = rho g R/(2 mu_k) (1 - exp(-2 mu_k y/R))
///   piston: sigma = rho g R/(2 mu_k) (exp(2 mu_k y/R) - 1)
/// evaluated as rho g y * (-expm1(-x))/x resp. rho g y * expm1(x)/x, x = 2 mu_k y/R, so that
/// mu_k -> 0 gives the hydrostatic rho g y without cancellation.
double janssen_stress(JanssenMode mode, double mu_k, double y, const JanssenSetup& s);

/// Force on the base pedestal, N: janssen_stress * pi R^2.
double janssen_force(JanssenMode mode, double mu_k, double y, const JanssenSetup& s);

struct JanssenFit {
  double mu_k = 0;
  double asymptote_stress = 0;  ///< rho g R/(2 mu_k), Pa (silo: the deep-bed limit)
  double asymptote_force = 0;   ///< rho g R/(2 mu_k) * pi R^2, N
  double rms_residual = 0;      ///< sqrt(mean (F_model - F)^2), N
  bool at_bound = false;        ///< minimum at the edge of the search range: not trustworthy
  std::size_t n = 0;
};

/// Least-squares fit of mu_k to pedestal forces F_i (N, magnitudes) at bed heights y_i (m):
/// minimises sum (janssen_force(mu_k, y_i) - F_i)^2 over mu_k in [mu_k_lo, mu_k_hi] by a
/// log-spaced scan (to bracket the global minimum) followed by golden-section search to a
/// relative bracket width of 1e-13. Throws std::invalid_argument on size mismatch, < 1 point,
/// non-positive rho/g/R, or a bad range.
JanssenFit fit_janssen_mu_k(JanssenMode mode, std::span<const double> heights,
                            std::span<const double> forces, const JanssenSetup& s,
                            double mu_k_lo = 1e-4, double mu_k_hi = 5.0);

/// Ratio fit through the origin, value = sum(num*den)/sum(den^2) (least squares of
/// num = value * den over bins), used for the stress ratio and the wall friction.
struct RatioFit {
  double value = 0;
  double rms_residual = 0;  ///< sqrt(mean (num - value*den)^2) over the bins used, Pa
  std::size_t n_used = 0;
  std::vector<std::optional<double>> per_bin;  ///< num/den per bin; empty where not used
};

/// Stress ratio k = sigma_h/sigma_v from depth-binned profiles (Janssen's k, Walton's
/// assumption 2). Bins with sigma_v <= min_sigma_v (empty, tensile) are skipped.
RatioFit fit_stress_ratio(std::span<const double> sigma_v, std::span<const double> sigma_h,
                          double min_sigma_v = 0);

/// Mobilised wall friction mu_w = tau_w/sigma_h from wall shear and wall normal stress
/// profiles (Janssen assumes it fully mobilised, tau_w = mu sigma_h). Bins with
/// sigma_h <= min_sigma_h are skipped. Sign of tau_w as given (upward on the bed positive in
/// the silo case gives mu_w > 0).
RatioFit fit_wall_friction(std::span<const double> sigma_h, std::span<const double> tau_w,
                           double min_sigma_h = 0);

}  // namespace cohdem
