// Particle data as a structure of arrays. Particles carry a stable 64-bit id that never
// changes (contact history is keyed by ids, so it survives re-sorting and, later, MPI
// migration); the local index changes whenever particles are re-sorted for locality.
#pragma once
#include <cstdint>
#include <vector>

#include "core/vec3.hpp"

namespace cohdem {

enum ParticleFlag : uint8_t {
  kFree = 0,
  kFrozen = 1,    ///< does not move (rough base layers in chute benchmarks)
  kAttached = 2,  ///< rigidly carried by wall `body[i]` (ribs, glued rough layers)
};

/// A particle's moment of inertia: every particle is a solid sphere, I = 2/5 m r^2. Its one
/// formula: ParticleStore::add and the thermal expansion store it, checkpoints are checked
/// against it, and the contact lanes (sim/lanes_body.hpp's rolling_inertia4) compute it in
/// the same order, bit for bit, instead of gathering the partners' inertias.
inline double sphere_inertia(const double m, const double r) { return 0.4 * m * r * r; }

struct ParticleStore {
  std::vector<uint64_t> id;
  std::vector<int32_t> species;
  std::vector<uint8_t> flag;
  /// Wall index of each kAttached particle, -1 for the others; one entry per particle once
  /// attach() has run, empty before (4 bytes per particle that runs without attached
  /// particles would carry, permute and checkpoint for nothing).
  std::vector<int32_t> body;
  std::vector<double> radius;           ///< current radius, m
  std::vector<double> mass, inertia;    ///< kg, kg m^2 (solid sphere 2/5 m r^2)
  std::vector<Vec3> x, v, omega;        ///< position m, velocity m/s, angular velocity rad/s
  std::vector<Vec3> force, torque;      ///< N, N m (contact + body forces, this step; a free particle's not stored by a fused force call: ForceContext::open_dt)
  // The thermal fields: one entry per particle once enable_thermal() has run (a run with a
  // thermal model), empty otherwise (24 bytes per particle that a purely mechanical run
  // would carry, write to checkpoints and permute at every re-sort for nothing).
  std::vector<double> radius0;          ///< reference radius (at the material's T_ref), m
  std::vector<double> temperature;      ///< K
  std::vector<double> heat_flow;        ///< W (this step)

  size_t size() const { return id.size(); }
  /// Whether the thermal fields are kept (enable_thermal).
  bool thermal() const { return thermal_; }
  /// Keeps the thermal fields from now on: a particle that has none gets radius0 = its
  /// radius, temperature T0 and no heat flow (those already set, e.g. from a checkpoint or a
  /// case's particle table, stay). Idempotent.
  void enable_thermal(double T0);
  /// Drops the thermal fields (a checkpoint of a thermal run read into a mechanical one).
  void disable_thermal();
  /// Attaches particle i rigidly to wall `wall` (flag kAttached, body[i] = wall); the first
  /// call gives every particle a body entry (-1 for the unattached).
  void attach(size_t i, int32_t wall) {
    if (body.size() != size()) body.resize(size(), -1);
    flag[i] = kAttached;
    body[i] = wall;
  }
  /// The first particle flagged as attached that names none of `nwalls` walls (the carrying
  /// and the walls' force sums index the walls by body[i]), or size() if there is none.
  size_t first_bad_attachment(size_t nwalls) const {
    for (size_t i = 0; i < size(); ++i)
      if (flag[i] == kAttached && (body.size() != size() || body[i] < 0 || size_t(body[i]) >= nwalls)) return i;
    return size();
  }

  /// Appends one particle; returns its local index.
  size_t add(uint64_t pid, int32_t sp, double r, double density, const Vec3& pos,
             const Vec3& vel = {}, const Vec3& w = {}, double temp = 293.15) {
    id.push_back(pid);
    species.push_back(sp);
    flag.push_back(kFree);
    if (!body.empty()) body.push_back(-1);
    radius.push_back(r);
    const double m = density * 4.0 / 3.0 * M_PI * r * r * r;
    mass.push_back(m);
    inertia.push_back(sphere_inertia(m, r));
    x.push_back(pos);
    v.push_back(vel);
    omega.push_back(w);
    force.emplace_back();
    torque.emplace_back();
    if (thermal_) {
      radius0.push_back(r);
      temperature.push_back(temp);
      heat_flow.push_back(0.0);
    }
    return id.size() - 1;
  }

  /// Reorders every array by `perm` (new index k takes old index perm[k]).
  void permute(const std::vector<uint32_t>& perm);

  void resize(size_t n);
  /// Capacity for n particles in every array. Without it add() grows the arrays by
  /// doubling, which can leave up to half of their memory unused.
  void reserve(size_t n);
  /// Drops every array's unused capacity.
  void shrink_to_fit();
  void erase_if_flagged(const std::vector<uint8_t>& remove);

 private:
  /// The wall indices, empty until attach() ran.
  std::vector<std::vector<int32_t>*> body_array() {
    if (body.empty()) return {};
    return {&body};
  }
  /// The thermal fields' arrays, empty unless enable_thermal ran.
  std::vector<std::vector<double>*> thermal_arrays() {
    if (!thermal_) return {};
    return {&radius0, &temperature, &heat_flow};
  }
  bool thermal_ = false;
};

}  // namespace cohdem
