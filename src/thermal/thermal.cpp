#include "thermal/thermal.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.hpp"
#include "sim/system.hpp"

namespace cohdem {

double Schedule::at(double t) const {
  if (values.empty()) return 0.0;
  if (values.size() == 1) return values[0];
  if (period > 0) t = times.front() + std::fmod(std::fmod(t - times.front(), period) + period, period);
  if (t <= times.front()) return values.front();
  if (t >= times.back()) return values.back();
  const size_t k = size_t(std::upper_bound(times.begin(), times.end(), t) - times.begin());
  const double t0 = times[k - 1], t1 = times[k];
  const double u = t1 > t0 ? (t - t0) / (t1 - t0) : 1.0;
  return values[k - 1] + u * (values[k] - values[k - 1]);
}

namespace {

bool region_contains(const Region& r, const Vec3& x) {
  switch (r.kind) {
    case Region::Kind::Box:
      return x.x >= r.lo.x && x.x <= r.hi.x && x.y >= r.lo.y && x.y <= r.hi.y && x.z >= r.lo.z && x.z <= r.hi.z;
    case Region::Kind::Cylinder:
    case Region::Kind::Annulus: {
      if (x.z < r.zmin || x.z > r.zmax) return false;
      const double rho2 = (x.x - r.center.x) * (x.x - r.center.x) + (x.y - r.center.y) * (x.y - r.center.y);
      return rho2 <= r.r_out * r.r_out && (r.kind == Region::Kind::Cylinder || rho2 >= r.r_in * r.r_in);
    }
  }
  return false;
}

/// Hertz spot radius from the normal force: a = (3 F R* / (4 E*))^(1/3).
inline double hertz_spot(double fn, double rstar, double estar) {
  return fn > 0 && estar > 0 ? std::cbrt(0.75 * fn * rstar / estar) : 0.0;
}

}  // namespace

ThermalModel::ThermalModel(ThermalSettings settings, const std::vector<Material>& mats)
    : set_(std::move(settings)), nm_(int(mats.size())) {
  hk_.assign(size_t(nm_) * nm_, 0.0);
  estar_c_.assign(size_t(nm_) * nm_, 0.0);
  for (int i = 0; i < nm_; ++i)
    for (int j = 0; j < nm_; ++j) {
      const Material &a = mats[i], &b = mats[j];
      if (a.conductivity > 0 && b.conductivity > 0)
        hk_[size_t(i) * nm_ + j] = 4.0 / (1.0 / a.conductivity + 1.0 / b.conductivity);
      const double Ea = a.E_conduction > 0 ? a.E_conduction : a.E, Eb = b.E_conduction > 0 ? b.E_conduction : b.E;
      if (Ea > 0 && Eb > 0) estar_c_[size_t(i) * nm_ + j] = 1.0 / ((1 - a.nu * a.nu) / Ea + (1 - b.nu * b.nu) / Eb);
    }
  for (const Material& m : mats) {
    cp_.push_back(m.heat_capacity);
    alpha_.push_back(m.expansion);
    tref_.push_back(m.T_ref);
  }
}

double ThermalModel::wall_temperature(size_t w, double t) const {
  return wall_fixed(w) ? set_.walls[w].temperature.at(t) : NAN;
}

void ThermalModel::update(System& s, bool integrate) {
  ParticleStore& P = s.particles;
  // A model attached to a system already prepared without one: its particles start at the
  // initial temperature (System::prepare_reach does the same).
  if (!P.thermal()) P.enable_thermal(s.cfg.initial_temperature);
  const NeighborList& nl = s.nl;
  const long n = long(P.size());
  const size_t np = nl.pair_count(), nw = nl.wall_entry_count();
  h_pair.assign(np, 0.0);
  h_wall.assign(nw, 0.0);
  q_pair_.assign(np, 0.0);
  q_wall_.assign(nw, 0.0);
  const double t = s.time;
  tw_.assign(s.walls.size(), NAN);
  for (size_t w = 0; w < s.walls.size(); ++w) tw_[w] = wall_temperature(w, t);
  src_.resize(set_.sources.size());
  for (size_t q = 0; q < src_.size(); ++q) src_[q] = set_.sources[q].specific_power.at(t);
  const double* Tw = tw_.data();
  const double* src = src_.data();
  double* q_wall = q_wall_.data();

  const bool by_force = set_.contact_radius == ThermalSettings::SpotRadius::HertzForce;
  const auto& a_pair = s.pair_contact_radii();
  const auto& a_wall = s.wall_contact_radii();
  const auto& f_wall = s.wall_forces();
  const auto& c_wall = s.wall_contact_points();
  const uint8_t* live = nl.hist.live.data();
  const uint8_t* wlive = nl.whist.live.data();
  const int nm = nm_;

  // Below parallel_min both passes run without entering an OpenMP construct (a region on one
  // thread still sets up a team and ends with a futex wake-up, a system call each step; the
  // sums are the same: each pass's reduction starts from zero).
  const bool par = n > s.cfg.parallel_min;
  // Pass 1: conductance and heat flow into i of every live pair.
  auto pass1 = [&](const long i) {
    const int si = P.species[i];
    for (uint32_t k = nl.start[i]; k < nl.start[i + 1]; ++k) {
      if (!live[k]) continue;
      const uint32_t j = nl.jdx[k];
      const size_t pm = size_t(si) * nm + P.species[j];
      double a = a_pair[k];
      if (by_force) {
        const Vec3 nvec = normalized(P.x[i] - (P.x[j] + nl.shift[nl.image[k]]));
        const double rstar = P.radius[i] * P.radius[j] / (P.radius[i] + P.radius[j]);
        a = hertz_spot(dot(s.pair_force(k), nvec), rstar, estar_c_[pm]);
      }
      const double h = hk_[pm] * a;
      h_pair[k] = h;
      q_pair_[k] = h * (P.temperature[j] - P.temperature[i]);
    }
  };
  if (par) {
#pragma omp parallel for schedule(dynamic, 256)
    for (long i = 0; i < n; ++i) pass1(i);
  } else {
    for (long i = 0; i < n; ++i) pass1(i);
  }

  // Pass 2: per particle, in list order: pairs, fixed-temperature walls, sources; integrate.
  const double S = set_.time_scale, dt = s.cfg.dt;
  double stab = 0, power = 0;
  auto pass2 = [&](const long i, double& stab, double& power) {
    const int si = P.species[i];
    double Q = 0, H = 0;
    for (uint32_t k = nl.start[i]; k < nl.start[i + 1]; ++k)
      if (live[k]) { Q += q_pair_[k]; H += h_pair[k]; }
    for (uint32_t q = nl.rstart[i]; q < nl.rstart[i + 1]; ++q) {
      const uint32_t k = nl.rpair[q];
      if (live[k]) { Q -= q_pair_[k]; H += h_pair[k]; }
    }
    for (uint32_t e = nl.wstart[i]; e < nl.wstart[i + 1]; ++e) {
      const uint16_t w = nl.wall[e];
      if (!wlive[e] || std::isnan(Tw[w])) continue;
      const size_t pm = size_t(si) * nm + s.walls[w].material;
      double a = a_wall[e];
      if (by_force) a = hertz_spot(dot(f_wall[e], normalized(P.x[i] - c_wall[e])), P.radius[i], estar_c_[pm]);
      const double h = hk_[pm] * a;
      h_wall[e] = h;
      q_wall[e] = h * (Tw[w] - P.temperature[i]);
      Q += q_wall[e];
      H += h;
    }
    double Ps = 0;
    for (size_t q = 0; q < src_.size(); ++q) {
      const HeatSource& hs = set_.sources[q];
      if ((hs.material >= 0 && hs.material != si) || (hs.region && !region_contains(*hs.region, P.x[i]))) continue;
      Ps += src[q] * P.mass[i];
    }
    power += Ps;
    P.heat_flow[i] = Q + Ps;
    if (!integrate) return;
    const double mc = P.mass[i] * cp_[si] / S;
    stab = std::max(stab, H * dt / mc);
    P.temperature[i] += (Q + Ps) * dt / mc;
    if (set_.expansion && alpha_[si] != 0) {
      P.radius[i] = P.radius0[i] * (1.0 + alpha_[si] * (P.temperature[i] - tref_[si]));
      P.inertia[i] = sphere_inertia(P.mass[i], P.radius[i]);
    }
  };
  if (par) {
#pragma omp parallel for schedule(static) reduction(max : stab) reduction(+ : power)
    for (long i = 0; i < n; ++i) pass2(i, stab, power);
  } else {
    for (long i = 0; i < n; ++i) pass2(i, stab, power);
  }
  source_power = power;
  wall_heat.assign(s.walls.size(), 0.0);
  for (size_t e = 0; e < nw; ++e)
    if (h_wall[e] > 0) wall_heat[nl.wall[e]] += q_wall[e];
  if (integrate) {
    stability = stab;
    if (stab > 1.0)
      throw RunError("thermal step unstable at t = " + std::to_string(t) + " s: time_scale x dt x (sum of contact " +
                     "conductances) / (m c) = " + std::to_string(stab) + " > 1; reduce thermal.time_scale below " +
                     std::to_string(S / stab) + " or the time step");
  }
}

double thermal_energy(const System& s) {
  double e = 0;
  for (size_t i = 0; i < s.particles.size(); ++i)
    e += s.particles.mass[i] * s.materials[s.particles.species[i]].heat_capacity * s.particles.temperature[i];
  return e;
}

}  // namespace cohdem
