#include "analysis/yield_locus.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace cohdem {

namespace {

std::string pa(double v) { return std::to_string(v) + " Pa"; }

}  // namespace

YieldLocusResult evaluate_yield_locus(ShearPoint pre, std::span<const ShearPoint> pts,
                                      std::optional<double> bulk_density, bool allow_preshear_above) {
  const std::size_t n = pts.size();
  if (n < 2)
    throw std::invalid_argument("yield locus: need at least 2 shear-to-failure points, got " +
                                std::to_string(n));
  // Least squares tau = m sigma + c on centred data (numerically stable).
  double ms = 0, mt = 0;
  for (const auto& p : pts) {
    if (!std::isfinite(p.sigma) || !std::isfinite(p.tau))
      throw std::invalid_argument("yield locus: shear point is not finite");
    ms += p.sigma;
    mt += p.tau;
  }
  ms /= double(n);
  mt /= double(n);
  double sxx = 0, sxy = 0, syy = 0;
  for (const auto& p : pts) {
    const double dx = p.sigma - ms, dy = p.tau - mt;
    sxx += dx * dx;
    sxy += dx * dy;
    syy += dy * dy;
  }
  if (!(sxx > 1e-24 * (ms * ms + 1.0)))
    throw std::invalid_argument(
        "yield locus: all shear points are at the same normal stress (" + pa(ms) +
        "); the slope is undefined");
  const double m = sxy / sxx;
  const double c = mt - m * ms;
  if (!(m > 0))
    throw std::invalid_argument("yield locus: fitted slope tan(phi_lin) = " + std::to_string(m) +
                                " is not positive");
  double ss_res = 0;
  for (const auto& p : pts) {
    const double r = p.tau - (m * p.sigma + c);
    ss_res += r * r;
  }

  YieldLocusResult out;
  out.n_points = n;
  out.phi_lin = std::atan(m);
  out.cohesion = c;
  out.r_squared = syy > 0 ? 1.0 - ss_res / syy : 1.0;
  out.bulk_density = bulk_density;
  const double sn = std::sin(out.phi_lin), cs = std::cos(out.phi_lin);

  // Unconfined yield strength: Mohr circle through the origin (sigma_2 = 0) tangent to the
  // locus. Tangency of a circle centred (s, 0), radius r: r = s sin(phi) + c cos(phi); with
  // s = r = sigma_c/2: sigma_c = 2 c cos(phi) / (1 - sin(phi)) (Schulze 2008, ch. 3).
  if (c > 0) {
    out.sigma_c = 2.0 * c * cs / (1.0 - sn);
  } else {
    out.sigma_c = 0.0;  // cohesionless (or negative intercept): no strength when unconfined
  }

  // Steady-state (consolidation) Mohr circle: through the pre-shear point P = (A, T) and
  // tangent to the locus, centre (s, 0) on the sigma axis, radius r = sin(phi)(s + c/tan(phi)).
  //   (A - s)^2 + T^2 = r^2
  //   => cos^2(phi) s^2 - 2 (A + c sin cos) s + (A^2 + T^2 - c^2 cos^2) = 0
  // whose reduced discriminant simplifies to D = cos^2(phi) [tau_YL(A)^2 - T^2], with
  // tau_YL(A) = tan(phi) A + c the locus at sigma_pre. A real circle exists only when
  // |T| <= tau_YL(A): every circle tangent to the locus from below lies below it.
  //   s = [A + c sin cos - cos(phi) sqrt(tau_YL(A)^2 - T^2)] / cos^2(phi)
  // The tangent point is at sigma_t = s cos^2 - c sin cos = A -/+ cos(phi) sqrt(...): the
  // smaller root puts it at or left of sigma_pre, where the measured locus is (it ends at the
  // pre-shear point: ASTM D6773, Schulze ch. 3); the larger root would touch the locus
  // extrapolated beyond sigma_pre. We take the smaller root.
  const double A = pre.sigma, T = pre.tau;
  if (!std::isfinite(A) || !std::isfinite(T))
    throw std::invalid_argument("yield locus: pre-shear point is not finite");
  if (!(A > 0))
    throw std::invalid_argument("yield locus: pre-shear normal stress must be > 0, got " + pa(A));
  const double tau_yl = m * A + c;
  double q = tau_yl * tau_yl - T * T;
  // Pre-shear point above the locus: no circle through it is tangent to the locus. When the
  // caller allows it (noisy DEM data of a nearly cohesionless sample, where the point lies on
  // the locus up to scatter), take the limiting circle: the one tangent AT the pre-shear point
  // to the line of slope tan(phi) through it (the locus moved up to meet P), centre
  // A + T tan(phi), radius T / cos(phi).
  double cc = c;  // intercept of the line the steady-state circle touches
  if (q < 0) {
    // Accept a point on the locus up to rounding; otherwise no tangent circle exists.
    if (tau_yl > 0 && std::abs(T) - tau_yl <= 1e-12 * tau_yl) {
      q = 0;
    } else if (allow_preshear_above && T > 0) {
      out.preshear_above_locus = true;
      cc = T - m * A;
      q = 0;
    } else {
      throw std::invalid_argument(
          "yield locus: pre-shear point (" + pa(A) + ", " + pa(T) +
          ") lies above the linearized yield locus (tau = " + pa(tau_yl) +
          " at sigma_pre); no Mohr circle through it is tangent to the locus. Check the "
          "pre-shear value (steady state reached?) and the shear points.");
    }
  }
  const double s = (A + cc * sn * cs - cs * std::sqrt(q)) / (cs * cs);
  const double r = s * sn + cc * cs;
  // Steady-state-flow angle (RST-CONTROL): line through origin and pre-shear point.
  out.phi_sf = std::atan2(T, A);
  if (!(s - r >= 0) || !(r >= 0)) {
    // The circle reaches into tension: no consolidation state with both principal stresses
    // compressive, so sigma_1 and what follows from it are not evaluated. The locus itself,
    // sigma_c and phi_sf stand (a very cohesive sample pre-sheared at a low stress).
    constexpr double nan = std::numeric_limits<double>::quiet_NaN();
    out.steady_state = false;
    out.steady_state_error = "the steady-state Mohr circle has sigma_2 = " + pa(s - r) +
                             " < 0 (pre-shear stress too low for this cohesion): sigma_1, phi_e and ffc not evaluated";
    out.sigma_1 = out.sigma_2 = out.sigma_tangent = out.phi_e = out.ffc = nan;
    return out;
  }
  out.sigma_1 = s + r;
  out.sigma_2 = s - r;
  out.sigma_tangent = s - r * sn;

  // Effective angle of internal friction: line through the origin tangent to the steady-state
  // circle, sin(phi_e) = (sigma_1 - sigma_2)/(sigma_1 + sigma_2) = r/s (Schulze, ch. 3).
  out.phi_e = std::asin(std::min(1.0, r / s));

  if (out.sigma_c > 0) {
    out.ffc = out.sigma_1 / out.sigma_c;
    out.ffc_infinite = false;
  } else {
    out.ffc = std::numeric_limits<double>::infinity();
    out.ffc_infinite = true;
  }
  return out;
}

namespace {

void check_series(std::span<const double> t, std::span<const double> tau, double t_begin,
                  double t_end, const char* who) {
  if (t.size() != tau.size())
    throw std::invalid_argument(std::string(who) + ": t and tau differ in length (" +
                                std::to_string(t.size()) + " vs " + std::to_string(tau.size()) +
                                ")");
  if (!(t_end > t_begin))
    throw std::invalid_argument(std::string(who) + ": phase end must be after phase begin");
}

}  // namespace

ShearPeak shear_peak(std::span<const double> t, std::span<const double> tau, double t_begin,
                     double t_end) {
  check_series(t, tau, t_begin, t_end, "shear_peak");
  ShearPeak best;
  bool found = false;
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (t[i] < t_begin || t[i] > t_end || !std::isfinite(tau[i])) continue;
    if (!found || tau[i] > best.tau) {  // first occurrence of the maximum
      best = {i, t[i], tau[i]};
      found = true;
    }
  }
  if (!found)
    throw std::invalid_argument("shear_peak: no finite samples in the phase [" +
                                std::to_string(t_begin) + ", " + std::to_string(t_end) + "] s");
  return best;
}

SteadyState steady_state_value(std::span<const double> t, std::span<const double> tau,
                               double t_begin, double t_end, double last_fraction,
                               double max_relative_drift) {
  check_series(t, tau, t_begin, t_end, "steady_state_value");
  if (!(last_fraction > 0 && last_fraction <= 1))
    throw std::invalid_argument("steady_state_value: last_fraction must be in (0, 1]");
  const double t_from = t_end - last_fraction * (t_end - t_begin);
  double st = 0, sy = 0;
  std::size_t k = 0;
  double t_first = 0, t_last = 0;
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (t[i] < t_from || t[i] > t_end || !std::isfinite(tau[i])) continue;
    if (k == 0) t_first = t[i];
    t_last = t[i];
    st += t[i];
    sy += tau[i];
    ++k;
  }
  if (k < 2)
    throw std::invalid_argument(
        "steady_state_value: fewer than 2 samples in the averaging window [" +
        std::to_string(t_from) + ", " + std::to_string(t_end) + "] s");
  st /= double(k);
  sy /= double(k);
  double stt = 0, sty = 0;
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (t[i] < t_from || t[i] > t_end || !std::isfinite(tau[i])) continue;
    stt += (t[i] - st) * (t[i] - st);
    sty += (t[i] - st) * (tau[i] - sy);
  }
  SteadyState out;
  out.mean = sy;
  out.n_used = k;
  out.slope = stt > 0 ? sty / stt : 0.0;
  const double change = std::abs(out.slope) * (t_last - t_first);
  if (sy != 0)
    out.relative_drift = change / std::abs(sy);
  else
    out.relative_drift = change == 0 ? 0.0 : std::numeric_limits<double>::infinity();
  out.steady = out.relative_drift <= max_relative_drift;
  return out;
}

}  // namespace cohdem
