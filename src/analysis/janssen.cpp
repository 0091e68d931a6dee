#include "analysis/janssen.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace cohdem {

namespace {

void check_setup(const JanssenSetup& s) {
  if (!(s.rho > 0) || !(s.g > 0) || !(s.radius > 0))
    throw std::invalid_argument("janssen: rho, g and radius must be > 0");
}

}  // namespace

double janssen_stress(JanssenMode mode, double mu_k, double y, const JanssenSetup& s) {
  const double x = 2.0 * mu_k * y / s.radius;
  double shape;  // sigma / (rho g y)
  if (x == 0.0)
    shape = 1.0;
  else if (mode == JanssenMode::Silo)
    shape = -std::expm1(-x) / x;  // (1 - e^-x)/x, Eq. 13
  else
    shape = std::expm1(x) / x;  // (e^x - 1)/x, Eq. 16
  return s.rho * s.g * y * shape;
}

double janssen_force(JanssenMode mode, double mu_k, double y, const JanssenSetup& s) {
  return janssen_stress(mode, mu_k, y, s) * M_PI * s.radius * s.radius;
}

JanssenFit fit_janssen_mu_k(JanssenMode mode, std::span<const double> y,
                            std::span<const double> f, const JanssenSetup& s, double lo,
                            double hi) {
  check_setup(s);
  if (y.size() != f.size())
    throw std::invalid_argument("fit_janssen_mu_k: heights and forces differ in length");
  if (y.empty()) throw std::invalid_argument("fit_janssen_mu_k: no data");
  if (!(lo > 0) || !(hi > lo))
    throw std::invalid_argument("fit_janssen_mu_k: need 0 < mu_k_lo < mu_k_hi");
  for (std::size_t i = 0; i < y.size(); ++i)
    if (!std::isfinite(y[i]) || !std::isfinite(f[i]) || y[i] < 0)
      throw std::invalid_argument("fit_janssen_mu_k: heights must be finite and >= 0, forces "
                                  "finite (point " + std::to_string(i) + ")");

  auto ssr = [&](double k) {
    double acc = 0;
    for (std::size_t i = 0; i < y.size(); ++i) {
      const double r = janssen_force(mode, k, y[i], s) - f[i];
      acc += r * r;
    }
    return std::isnan(acc) ? std::numeric_limits<double>::infinity() : acc;  // overflow -> inf
  };

  // Scan in log(mu_k) to bracket the global minimum, then golden section in the bracket.
  constexpr int kScan = 400;
  const double llo = std::log(lo), lhi = std::log(hi);
  auto at = [&](int i) { return i == 0 ? lo : (i == kScan ? hi : std::exp(llo + (lhi - llo) * i / kScan)); };
  int best = 0;
  double fbest = ssr(lo);
  for (int i = 1; i <= kScan; ++i) {
    const double v = ssr(at(i));
    if (v < fbest) {
      fbest = v;
      best = i;
    }
  }
  double a = at(best > 0 ? best - 1 : 0), b = at(best < kScan ? best + 1 : kScan);
  const double invphi = (std::sqrt(5.0) - 1.0) / 2.0;
  double x1 = b - invphi * (b - a), x2 = a + invphi * (b - a);
  double f1 = ssr(x1), f2 = ssr(x2);
  for (int it = 0; it < 200 && (b - a) > 1e-13 * (a + b); ++it) {
    if (f1 <= f2) {
      b = x2;
      x2 = x1;
      f2 = f1;
      x1 = b - invphi * (b - a);
      f1 = ssr(x1);
    } else {
      a = x1;
      x1 = x2;
      f1 = f2;
      x2 = a + invphi * (b - a);
      f2 = ssr(x2);
    }
  }
  double k = 0.5 * (a + b);
  double fk = ssr(k);
  if (fbest < fk) {  // the scan node itself was better (flat or edge minimum)
    k = at(best);
    fk = fbest;
  }

  JanssenFit out;
  out.mu_k = k;
  out.n = y.size();
  out.asymptote_stress = s.rho * s.g * s.radius / (2.0 * k);
  out.asymptote_force = out.asymptote_stress * M_PI * s.radius * s.radius;
  out.rms_residual = std::sqrt(fk / double(y.size()));
  out.at_bound = (k - lo) < 1e-6 * lo || (hi - k) < 1e-6 * hi;
  return out;
}

namespace {

RatioFit ratio_fit(std::span<const double> den, std::span<const double> num, double min_den,
                   const char* who) {
  if (den.size() != num.size())
    throw std::invalid_argument(std::string(who) + ": profiles differ in length (" +
                                std::to_string(den.size()) + " vs " +
                                std::to_string(num.size()) + ")");
  RatioFit out;
  out.per_bin.resize(den.size());
  double snd = 0, sdd = 0;
  for (std::size_t i = 0; i < den.size(); ++i) {
    if (!std::isfinite(den[i]) || !std::isfinite(num[i]) || !(den[i] > min_den)) continue;
    out.per_bin[i] = num[i] / den[i];
    snd += num[i] * den[i];
    sdd += den[i] * den[i];
    ++out.n_used;
  }
  if (out.n_used == 0)
    throw std::invalid_argument(std::string(who) + ": no bin has a denominator stress above " +
                                std::to_string(min_den) + " Pa");
  out.value = snd / sdd;
  double ss = 0;
  for (std::size_t i = 0; i < den.size(); ++i) {
    if (!out.per_bin[i]) continue;
    const double r = num[i] - out.value * den[i];
    ss += r * r;
  }
  out.rms_residual = std::sqrt(ss / double(out.n_used));
  return out;
}

}  // namespace

RatioFit fit_stress_ratio(std::span<const double> sigma_v, std::span<const double> sigma_h,
                          double min_sigma_v) {
  return ratio_fit(sigma_v, sigma_h, min_sigma_v, "fit_stress_ratio");
}

RatioFit fit_wall_friction(std::span<const double> sigma_h, std::span<const double> tau_w,
                           double min_sigma_h) {
  return ratio_fit(sigma_h, tau_w, min_sigma_h, "fit_wall_friction");
}

}  // namespace cohdem
