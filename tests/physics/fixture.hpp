// Helpers to build small systems in tests without a case file.
#pragma once
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "core/rng.hpp"
#include "models/registry.hpp"
#include "sim/system.hpp"

namespace cohdem::testing {

/// A system with the given materials, model and one parameter set used for every pair.
inline std::unique_ptr<System> make_system(std::vector<Material> mats, const std::string& model,
                                           const std::string& rolling, const ParamSet& params, double dt,
                                           Vec3 gravity = {0, 0, 0}, double skin = 1e-3) {
  auto s = std::make_unique<System>();
  s->materials = std::move(mats);
  s->cfg.dt = dt;
  s->cfg.gravity = gravity;
  s->cfg.skin = skin;
  // Small systems run serially: OpenMP barriers cost more than they save for a few particles
  // (and spin badly on a loaded machine). The thread test sets its own count.
  s->cfg.threads = 1;
  const size_t n = s->materials.size();
  std::vector<ParamSet> sets(n * n, params);
  s->set_model(make_contact_model(model, rolling), sets);
  return s;
}

inline ParamSet params(std::initializer_list<std::pair<const char*, double>> kv) {
  ParamSet p;
  for (auto& [k, v] : kv) p.set(k, v);
  return p;
}

/// `count` spheres of radii uniform in [rmin, rmax] placed at random in the box [lo, hi].
inline InsertSpec box_fill(const Vec3& lo, const Vec3& hi, double rmin, double rmax, size_t count) {
  InsertSpec spec;
  spec.region.kind = Region::Kind::Box;
  spec.region.lo = lo;
  spec.region.hi = hi;
  spec.size.kind = SizeDistribution::Kind::Uniform;
  spec.size.rmin = rmin;
  spec.size.rmax = rmax;
  spec.count = count;
  return spec;
}

/// A packed bed periodic in x, y and z: nx * nx * nz spheres of radius r on a simple cubic
/// lattice of spacing 0.999 (2 r) in a box of the lattice's size (the box and its periodicity
/// set here), so that each sphere presses on its six neighbours with an overlap of 0.002 r,
/// with velocities `v` times a normal draw per component (seed `seed`). Not prepared.
inline void fill_periodic_lattice(System& s, int nx, int nz, double r, double v, uint64_t seed) {
  const double a = 0.999 * 2 * r;
  s.cfg.domain.lo = {0, 0, 0};
  s.cfg.domain.hi = {nx * a, nx * a, nz * a};
  s.cfg.domain.periodic = {true, true, true};
  Rng rng(seed);
  for (int z = 0; z < nz; ++z)
    for (int y = 0; y < nx; ++y)
      for (int x = 0; x < nx; ++x)
        s.add_particle(0, r, {(x + 0.5) * a, (y + 0.5) * a, (z + 0.5) * a},
                       {v * rng.normal(), v * rng.normal(), v * rng.normal()});
}

inline Wall plane(const Vec3& point, const Vec3& normal, int material) {
  Wall w;
  w.name = "plane";
  w.shape = WallShape::Plane;
  w.point = point;
  w.normal = normalized(normal);
  w.material = material;
  return w;
}

/// Young's modulus of a wall material that stands for a rigid body: with E = 1e30 Pa the
/// wall's share of 1/E* = (1-nu_i^2)/E_i + (1-nu_j^2)/E_j is ~1e-19 of the particle's, so
/// E* = E_i/(1 - nu_i^2) and G* = G_i/(2 - nu_i) to double precision.
inline constexpr double kRigidE = 1e30;

inline Wall cylinder(const Vec3& point, const Vec3& axis, double radius, bool inside, int material) {
  Wall w;
  w.name = "cylinder";
  w.shape = WallShape::Cylinder;
  w.point = point;
  w.center = point;
  w.normal = normalized(axis);
  w.radius = radius;
  w.inside = inside;
  w.material = material;
  return w;
}

/// Local index of the particle with stable id `id` (re-sorting permutes indices).
inline size_t index_of(const System& s, uint64_t id) {
  for (size_t i = 0; i < s.particles.size(); ++i)
    if (s.particles.id[i] == id) return i;
  return size_t(-1);
}

inline double sphere_mass(double rho, double r) { return rho * 4.0 / 3.0 * M_PI * r * r * r; }

/// One line of the validation table (measured vs reference, tolerance), for the issue notes.
inline void report(const char* what, double measured, double reference, double tol, const char* tol_kind = "abs") {
  std::printf("[validation] %-58s measured %-14.8g reference %-14.8g tol %s %.3g\n", what, measured, reference,
              tol_kind, tol);
}

/// What one binary impact looked like: overlap crossing times (linear interpolation between
/// steps), last step with a repulsive normal force, peaks.
struct ImpactTrace {
  double t_touch = NAN;      ///< overlap crosses zero on approach, s
  double t_sep = NAN;        ///< overlap crosses zero on separation, s
  double t_force_last = NAN; ///< time of the last step with normal force > 0, s
  double delta_max = 0;      ///< largest sampled overlap, m
  double f_max = 0;          ///< largest sampled normal force, N
  bool separated = false;
};

/// Steps `s` until the contact described by overlap() ends (or max_steps). force() returns
/// the normal force on the contact (repulsive > 0) after a step.
template <class Overlap, class Force>
ImpactTrace trace_impact(System& s, Overlap overlap, Force force, uint64_t max_steps) {
  ImpactTrace tr;
  s.prepare();
  double d_prev = overlap(), t_prev = s.time;
  bool touched = d_prev > 0;
  if (touched) tr.t_touch = s.time;
  for (uint64_t k = 0; k < max_steps; ++k) {
    s.step_once();
    const double d = overlap(), f = force(), t = s.time;
    if (!touched && d > 0) {
      touched = true;
      tr.t_touch = t_prev + (t - t_prev) * (0 - d_prev) / (d - d_prev);
    }
    if (touched) {
      tr.delta_max = std::max(tr.delta_max, d);
      tr.f_max = std::max(tr.f_max, f);
      if (f > 0) tr.t_force_last = t;
      if (d <= 0) {
        tr.t_sep = t_prev + (t - t_prev) * d_prev / (d_prev - d);
        tr.separated = true;
        return tr;
      }
    }
    d_prev = d;
    t_prev = t;
  }
  return tr;
}

}  // namespace cohdem::testing
