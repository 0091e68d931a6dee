// Heat conduction through contact spots and thermal expansion of particles (docs/packed-beds.md).
//
// Conduction (lumped parameter; Batchelor & O'Brien 1977, McCarthy 2003): two bodies touching
// on a circular spot of radius a exchange heat at Q = H (T_j - T_i), with the constriction
// conductance of two half-spaces in series,
//     H = 4 a / (1/k_i + 1/k_j)        (= 2 k_s a for one material),
// a from the contact law (the overlap: sqrt(R* delta) for Hertz and linear springs, the plastic
// spot for plastic laws) or, with contact_radius = hertz_force, from the actual normal force,
//     a = (3 F_n R* / (4 E*_c))^(1/3),
// with E*_c from each material's conduction modulus (the real one where the contact law uses a
// softened modulus). Walls at a fixed temperature conduct the same way (their material's k;
// R* = r_i); other walls are adiabatic. Heat sources add a specific power (W/kg) to the
// particles whose centres lie in a region.
//
// Temperature: m c dT/dt = sum Q + P, explicit Euler once per time step after the force pass,
// with the heat capacities divided by time_scale S (heat flows S times faster than in reality;
// the mechanics are untouched). The sums are per-particle gathers in list order, so results do
// not depend on the number of threads. Stability needs S dt sum_j H_ij / (m_i c_i) < 1; a step
// past that throws RunError.
//
// Expansion: r = r0 (1 + alpha (T - T_ref)), mass kept (density falls), moment of inertia
// 2/5 m r^2 updated. The neighbor list's rebuild trigger counts radius growth.
#pragma once
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "particles/insertion.hpp"

namespace cohdem {

class System;
struct Material;

/// A value against time: constant, or piecewise linear through (times, values), held at the
/// end values outside them, and repeated with `period` when period > 0.
struct Schedule {
  std::vector<double> times, values;
  double period = 0;
  static Schedule constant(double v) { return {{0.0}, {v}, 0.0}; }
  double at(double t) const;
  bool empty() const { return values.empty(); }
};

struct WallThermal {
  bool fixed = false;     ///< false: adiabatic
  Schedule temperature;   ///< K, when fixed
};

struct HeatSource {
  std::string name;
  std::optional<Region> region;  ///< particles whose centres lie inside (all when absent)
  int material = -1;             ///< only particles of this material (-1: all)
  Schedule specific_power;       ///< W/kg
};

struct ThermalSettings {
  bool enabled = false;
  double time_scale = 1;   ///< S: heat capacities divided by S
  bool expansion = true;   ///< radii follow temperature
  enum class SpotRadius { Model, HertzForce } contact_radius = SpotRadius::Model;
  std::vector<WallThermal> walls;  ///< one per wall (empty: all adiabatic)
  std::vector<HeatSource> sources;
};

class ThermalModel {
 public:
  /// `materials` carry k, c, alpha, T_ref (> 0) and the conduction modulus (see Material).
  ThermalModel(ThermalSettings settings, const std::vector<Material>& materials);

  /// Evaluates conductances and heat flows at the current state; with `integrate`, advances
  /// temperatures by one time step and updates radii (and moments of inertia).
  void update(System& s, bool integrate);

  const ThermalSettings& settings() const { return set_; }
  double wall_temperature(size_t w, double t) const;
  bool wall_fixed(size_t w) const { return w < set_.walls.size() && set_.walls[w].fixed; }

  // Results of the last update.
  std::vector<double> h_pair, h_wall;  ///< conductance, W/K, per list entry (0: no contact)
  std::vector<double> wall_heat;       ///< W flowing from each wall into the particles
  double source_power = 0;             ///< W added by heat sources (real, unscaled)
  double stability = 0;                ///< max_i S dt sum H / (m c) of the last step (< 1)

 private:
  ThermalSettings set_;
  int nm_ = 0;
  std::vector<double> hk_;      ///< 4 / (1/k_i + 1/k_j) per material pair, W/(m K)
  std::vector<double> estar_c_; ///< conduction E* per material pair, Pa
  std::vector<double> cp_, alpha_, tref_;
  // Scratch reused every step: heat flow into the particle per pair / wall entry (W), wall
  // temperatures and source powers now.
  std::vector<double> q_pair_, q_wall_, tw_, src_;
};

/// Energy check helper: sum of m c T over particles, J (heat capacities unscaled).
double thermal_energy(const System& s);

}  // namespace cohdem
