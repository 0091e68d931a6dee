#include "particles/insertion.hpp"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "core/error.hpp"

namespace cohdem {

double SizeDistribution::sample(Rng& rng) const {
  switch (kind) {
    case Kind::Constant: return r;
    case Kind::Uniform: return rng.uniform(rmin, rmax);
    case Kind::Gaussian: {
      for (;;) {  // rejection keeps the truncated normal exact
        const double v = mean + stddev * rng.normal();
        if (v >= mean * (1 - bound) && v <= mean * (1 + bound)) return v;
      }
    }
    case Kind::List: {
      double tot = 0;
      for (double w : weights) tot += w;
      double u = rng.uniform() * tot;
      for (size_t k = 0; k < radii.size(); ++k) {
        if (u < weights[k]) return radii[k];
        u -= weights[k];
      }
      return radii.back();
    }
  }
  return r;
}

double SizeDistribution::min_radius() const {
  switch (kind) {
    case Kind::Constant: return r;
    case Kind::Uniform: return rmin;
    case Kind::Gaussian: return mean * (1 - bound);
    case Kind::List: return *std::min_element(radii.begin(), radii.end());
  }
  return r;
}

double SizeDistribution::max_radius() const {
  switch (kind) {
    case Kind::Constant: return r;
    case Kind::Uniform: return rmax;
    case Kind::Gaussian: return mean * (1 + bound);
    case Kind::List: return *std::max_element(radii.begin(), radii.end());
  }
  return r;
}

double SizeDistribution::mean_volume() const {
  // Deterministic quadrature of E[4/3 pi r^3] (exact for Constant/List/Uniform).
  const double c = 4.0 / 3.0 * M_PI;
  switch (kind) {
    case Kind::Constant: return c * r * r * r;
    case Kind::Uniform: return c * (std::pow(rmax, 4) - std::pow(rmin, 4)) / (4 * (rmax - rmin));
    case Kind::List: {
      double tot = 0, s = 0;
      for (size_t k = 0; k < radii.size(); ++k) { tot += weights[k]; s += weights[k] * c * std::pow(radii[k], 3); }
      return s / tot;
    }
    case Kind::Gaussian: {
      const double a = mean * (1 - bound), b = mean * (1 + bound);
      const int m = 2000;
      double s = 0, w = 0;
      for (int k = 0; k < m; ++k) {
        const double x = a + (b - a) * (k + 0.5) / m;
        const double pdf = std::exp(-0.5 * std::pow((x - mean) / stddev, 2));
        s += pdf * c * x * x * x;
        w += pdf;
      }
      return s / w;
    }
  }
  return 0;
}

double Region::volume() const {
  switch (kind) {
    case Kind::Box: return (hi.x - lo.x) * (hi.y - lo.y) * (hi.z - lo.z);
    case Kind::Cylinder: return M_PI * r_out * r_out * (zmax - zmin);
    case Kind::Annulus: return M_PI * (r_out * r_out - r_in * r_in) * (zmax - zmin);
  }
  return 0;
}

bool Region::sample_center(Rng& rng, double r, Vec3& x) const {
  switch (kind) {
    case Kind::Box: {
      for (int d = 0; d < 3; ++d)
        if (hi[d] - lo[d] < 2 * r) return false;
      x = {rng.uniform(lo.x + r, hi.x - r), rng.uniform(lo.y + r, hi.y - r), rng.uniform(lo.z + r, hi.z - r)};
      return true;
    }
    case Kind::Cylinder:
    case Kind::Annulus: {
      const double a = kind == Kind::Annulus ? r_in + r : 0.0, b = r_out - r;
      if (b <= a || zmax - zmin < 2 * r) return false;
      const double rho = std::sqrt(rng.uniform(a * a, b * b));  // uniform in area
      const double th = rng.uniform(0, 2 * M_PI);
      x = {center.x + rho * std::cos(th), center.y + rho * std::sin(th), rng.uniform(zmin + r, zmax - r)};
      return true;
    }
  }
  return false;
}

InsertResult insert_random(const InsertSpec& s, Rng& rng, const std::vector<Vec3>& ex,
                           const std::vector<double>& er, uint64_t max_count) {
  const double rmax = s.size.max_radius();
  // Hash grid of cell size 2 rmax_all: overlap tests look at 27 cells.
  double rall = rmax;
  for (double r : er) rall = std::max(rall, r);
  const double h = 2 * rall;
  auto key = [&](const Vec3& x) {
    const int64_t i = int64_t(std::floor(x.x / h)), j = int64_t(std::floor(x.y / h)), k = int64_t(std::floor(x.z / h));
    return (i * 73856093) ^ (j * 19349663) ^ (k * 83492791);
  };
  std::unordered_multimap<int64_t, uint32_t> grid;
  std::vector<Vec3> px(ex);
  std::vector<double> pr(er);
  for (uint32_t q = 0; q < px.size(); ++q) grid.emplace(key(px[q]), q);

  const double target_volume = s.solids_fraction * s.region.volume();
  uint64_t want = s.count;
  const bool by_fraction = s.count == 0;
  InsertResult out;
  double placed_volume = 0;
  while (true) {
    if (!by_fraction && out.x.size() >= want) break;
    if (by_fraction && placed_volume >= target_volume) break;
    if (out.x.size() >= max_count) break;
    const double r = s.size.sample(rng);
    bool ok = false;
    Vec3 x;
    for (int a = 0; a < s.max_attempts && !ok; ++a) {
      if (!s.region.sample_center(rng, r, x))
        throw RunError("insertion region '" + s.region.name + "' is too small for a particle of radius " +
                       std::to_string(r) + " m");
      ok = true;
      const int64_t i0 = int64_t(std::floor(x.x / h)), j0 = int64_t(std::floor(x.y / h)),
                    k0 = int64_t(std::floor(x.z / h));
      for (int64_t i = i0 - 1; i <= i0 + 1 && ok; ++i)
        for (int64_t j = j0 - 1; j <= j0 + 1 && ok; ++j)
          for (int64_t k = k0 - 1; k <= k0 + 1 && ok; ++k) {
            auto range = grid.equal_range((i * 73856093) ^ (j * 19349663) ^ (k * 83492791));
            for (auto it = range.first; it != range.second; ++it) {
              const uint32_t q = it->second;
              const double rs = r + pr[q];
              if (norm2(x - px[q]) < rs * rs) { ok = false; break; }
            }
          }
    }
    if (!ok) {
      if (max_count != UINT64_MAX) break;  // pouring: try again at the next interval
      const double frac = placed_volume / s.region.volume();
      throw RunError("could not insert particle " + std::to_string(out.x.size() + 1) + " into region '" +
                     s.region.name + "' after " + std::to_string(s.max_attempts) +
                     " attempts: reached solids fraction " + std::to_string(frac) +
                     " (random insertion jams near 0.3); insert fewer particles, use a larger region, or pour");
    }
    grid.emplace(key(x), uint32_t(px.size()));
    px.push_back(x);
    pr.push_back(r);
    out.x.push_back(x);
    out.r.push_back(r);
    placed_volume += 4.0 / 3.0 * M_PI * r * r * r;
  }
  return out;
}

}  // namespace cohdem
