#include "models/damping/restitution.hpp"

#include <map>
#include <mutex>
#include <tuple>

namespace cohdem {

double restitution_of_beta(double beta, double p, bool limit) {
  // State (x, u = x'); force f(x,u) = x^p + 2 beta sqrt(p) x^((p-1)/2) u (unit mass, unit k).
  auto force = [&](double x, double u) {
    if (x < 0) return 0.0;
    const double fe = std::pow(x, p);
    double fd = 2.0 * beta * std::sqrt(p * std::pow(x, p - 1.0)) * u;
    if (limit && fe + fd < 0) fd = -fe;
    return fe + fd;
  };
  // Undamped contact lasts ~3.2 (p = 1.5) or pi (p = 1) in these units. RK4 with h = 1e-3;
  // the step that crosses the end of contact is redone with h/10, five times, so the kink
  // of the force at zero overlap costs no accuracy (final step 1e-8).
  double h = 1e-3;
  double x = 0, u = 1;
  int refine = 0;
  // Past t = 60 (twenty undamped contact times) the particle is taken as stuck (e = 0).
  for (double t = 0; t < 60.0; t += h) {
    const double k1x = u, k1u = -force(x, u);
    const double k2x = u + 0.5 * h * k1u, k2u = -force(x + 0.5 * h * k1x, u + 0.5 * h * k1u);
    const double k3x = u + 0.5 * h * k2u, k3u = -force(x + 0.5 * h * k2x, u + 0.5 * h * k2u);
    const double k4x = u + h * k3u, k4u = -force(x + h * k3x, u + h * k3u);
    const double xn = x + h / 6 * (k1x + 2 * k2x + 2 * k3x + k4x);
    const double un = u + h / 6 * (k1u + 2 * k2u + 2 * k3u + k4u);
    const bool ends = xn <= 0 || (limit && un < 0 && force(xn, un) <= 0);
    if (ends) {
      if (refine < 5) { h *= 0.1; ++refine; continue; }
      if (xn <= 0) {  // interpolate the exit velocity inside the last tiny step
        const double s = x / (x - xn);
        return -(u + s * (un - u));
      }
      return -un;  // force reached zero with overlap left: flies off at this speed
    }
    x = xn; u = un;
  }
  return 0.0;  // stuck (overdamped)
}

namespace {
double solve_beta(double e, double p, bool limit) {
  double lo = 0.0, hi = 1.0;
  while (restitution_of_beta(hi, p, limit) > e && hi < 1e3) hi *= 2;
  for (int it = 0; it < 60; ++it) {
    const double mid = 0.5 * (lo + hi);
    (restitution_of_beta(mid, p, limit) > e ? lo : hi) = mid;
    if (hi - lo < 1e-10) break;
  }
  return 0.5 * (lo + hi);
}
}  // namespace

double beta_for_restitution(double e, double p, bool limit) {
  if (e >= 1.0) return 0.0;
  // Each solve integrates some forty impacts (~0.05 s); a case asks for the same (e, p,
  // limit) once per material pair and per model set-up, so solved values are kept for the
  // process (the same function of the same arguments: identical results).
  static std::mutex mutex;
  static std::map<std::tuple<double, double, bool>, double> solved;
  const auto key = std::make_tuple(e, p, limit);
  {
    const std::lock_guard<std::mutex> lock(mutex);
    if (const auto it = solved.find(key); it != solved.end()) return it->second;
  }
  const double beta = solve_beta(e, p, limit);
  const std::lock_guard<std::mutex> lock(mutex);
  solved.emplace(key, beta);
  return beta;
}

}  // namespace cohdem
