#include "sim/timestep_audit.hpp"

#include <cmath>
#include <cstdio>
#include <vector>

namespace cohdem {

namespace {

struct PairTimes {
  double collision = INFINITY;
  double rolling = INFINITY;  ///< half period of the rolling (bending) spring; inf: none
};

/// Collision time of one pair (i, j) with radii ri, rj (rj = 0: wall) and masses, and the
/// half period of its rolling spring at the overlap of that collision.
PairTimes pair_times(const ContactModel& m, int i, int j, double ri, double rj, double mi, double mj, double v) {
  PairGeom g;
  g.n = {0, 0, 1};
  g.ri = ri;
  g.rj = rj;
  g.rstar = rj > 0 ? ri * rj / (ri + rj) : ri;
  g.mi = mi;
  g.mj = mj;
  g.mstar = rj > 0 ? mi * mj / (mi + mj) : mi;
  g.Ii = 0.4 * mi * ri * ri;
  g.Ij = rj > 0 ? 0.4 * mj * rj * rj : INFINITY;
  g.dt = 1e-9;
  const double target = 0.5 * g.mstar * v * v;
  std::vector<std::byte> st(m.state_size());
  auto load_to = [&](double dmax, int nsteps, double* f_end, double* k_load, double* k_unload) {
    std::fill(st.begin(), st.end(), std::byte{0});
    double w = 0, f_prev = 0;
    PairForce out;
    for (int k = 1; k <= nsteps; ++k) {
      g.delta = dmax * k / nsteps;
      if (!m.evaluate(i, j, g, st.data(), out)) out.fn_el = 0;
      w += 0.5 * (out.fn_el + f_prev) * dmax / nsteps;
      if (k == nsteps && k_load) *k_load = (out.fn_el - f_prev) / (dmax / nsteps);
      f_prev = out.fn_el;
    }
    if (f_end) *f_end = f_prev;
    if (k_unload) {
      const double h = 1e-3 * dmax / nsteps;
      g.delta = dmax - h;
      if (!m.evaluate(i, j, g, st.data(), out)) out.fn_el = 0;
      *k_unload = (f_prev - out.fn_el) / h;
    }
    return w;
  };
  // Bracket the overlap that stores the kinetic energy, then bisect.
  double lo = 0, hi = 1e-9 * g.rstar;
  while (load_to(hi, 100, nullptr, nullptr, nullptr) < target) {
    lo = hi;
    hi *= 2;
    if (hi > g.rstar) break;  // softer than any sensible contact: report at r*
  }
  for (int it = 0; it < 50 && hi <= g.rstar; ++it) {
    const double mid = 0.5 * (lo + hi);
    (load_to(mid, 100, nullptr, nullptr, nullptr) < target ? lo : hi) = mid;
  }
  double f, kl, ku;
  load_to(std::min(hi, g.rstar), 400, &f, &kl, &ku);
  const double k = std::max(kl, ku);
  PairTimes t;
  t.collision = k > 0 ? M_PI * std::sqrt(g.mstar / k) : INFINITY;

  // The rolling spring at that overlap (rolling's own stiffness, such as SDS's k_r or Walton's
  // bending k_theta, need not follow kn): a relative rotation rate u about an axis in the
  // tangent plane for one step of length h, from the loaded state, for h = 0 and h = h1. The
  // moments differ by the spring's k_rot u h1 (the dashpots' parts cancel); u is small
  // enough that no limit is reached. Half period pi sqrt(I_eff / k_rot), I_eff = Ii Ij /
  // (Ii + Ij), the relative rotation's inertia (Ii for a wall).
  const std::vector<std::byte> loaded = st;
  PairGeom p = g;
  p.vn = 0;
  p.vt = {};
  const double u = 1e-9, h1 = 1e-6;
  p.wrel = {u, 0, 0};
  Vec3 mr[2];
  for (int q = 0; q < 2; ++q) {
    st = loaded;
    p.dt = q ? h1 : 0.0;
    PairForce out;
    mr[q] = m.evaluate(i, j, p, st.data(), out) ? out.mr : Vec3{};
  }
  const double k_rot = norm(mr[1] - mr[0]) / (u * h1);
  const double I_eff = std::isfinite(g.Ij) ? g.Ii * g.Ij / (g.Ii + g.Ij) : g.Ii;
  if (k_rot > 0) t.rolling = M_PI * std::sqrt(I_eff / k_rot);
  return t;
}

}  // namespace

TimestepAudit audit_timestep(const System& s, const std::vector<double>& rmin, double v) {
  TimestepAudit a;
  a.dt = s.cfg.dt;
  a.velocity = v;
  const int n = int(s.materials.size());
  char buf[512];
  // Rayleigh.
  for (int m = 0; m < n; ++m) {
    const Material& mat = s.materials[m];
    if (!(rmin[m] > 0) || !(mat.E > 0) || !(mat.density > 0)) continue;
    const double G = mat.E / (2 * (1 + mat.nu));
    const double tr = M_PI * rmin[m] * std::sqrt(mat.density / G) / (0.1631 * mat.nu + 0.8766);
    if (a.rayleigh == 0 || tr < a.rayleigh) { a.rayleigh = tr; a.rayleigh_material = mat.name; }
  }
  // Collisions: particle-particle for materials with particles, particle-wall for wall materials.
  std::vector<bool> wall_mat(n, false);
  for (const Wall& w : s.walls) wall_mat[w.material] = true;
  for (int i = 0; i < n; ++i) {
    if (!(rmin[i] > 0)) continue;
    const double mi = s.materials[i].density * 4.0 / 3.0 * M_PI * std::pow(rmin[i], 3);
    for (int j = 0; j < n; ++j) {
      auto note = [&](const PairTimes& t, const std::string& label) {
        if (t.collision < (a.collision > 0 ? a.collision : INFINITY)) { a.collision = t.collision; a.collision_pair = label; }
        if (t.rolling < (a.rolling > 0 ? a.rolling : INFINITY)) { a.rolling = t.rolling; a.rolling_pair = label; }
      };
      if (rmin[j] > 0 && j >= i) {
        const double mj = s.materials[j].density * 4.0 / 3.0 * M_PI * std::pow(rmin[j], 3);
        note(pair_times(*s.model, i, j, rmin[i], rmin[j], mi, mj, v), s.materials[i].name + "-" + s.materials[j].name);
      }
      if (wall_mat[j])
        note(pair_times(*s.model, i, j, rmin[i], 0, mi, INFINITY, v),
             s.materials[i].name + "-wall(" + s.materials[j].name + ")");
    }
  }
  auto raise = [&](TimestepAudit::Level l, const std::string& msg) {
    if (l > a.level) a.level = l;
    a.messages.push_back(msg);
  };
  if (a.rayleigh > 0) {
    const double f = a.dt / a.rayleigh;
    std::snprintf(buf, sizeof buf, "dt = %.3g s is %.1f%% of the Rayleigh time %.3g s (%s)", a.dt, 100 * f,
                  a.rayleigh, a.rayleigh_material.c_str());
    if (f > kErrorRayleigh) raise(TimestepAudit::Error, std::string(buf) + ": above the hard bound of 50%");
    else if (f > kWarnRayleigh) raise(TimestepAudit::Warn, std::string(buf) + ": above the safe 20%");
  }
  // A time to resolve (a collision, a spring's half period): steps of dt across it.
  auto steps_across = [&](const double t, const std::string& what) {
    const double steps = t / a.dt;
    std::snprintf(buf, sizeof buf, "%.1f steps per %s", steps, what.c_str());
    if (steps < kErrorStepsPerCollision) raise(TimestepAudit::Error, std::string(buf) + ": below the hard bound of 8");
    else if (steps < kWarnStepsPerCollision) raise(TimestepAudit::Warn, std::string(buf) + ": below the safe 20");
  };
  char what[256];
  if (a.collision > 0 && std::isfinite(a.collision)) {
    std::snprintf(what, sizeof what, "collision (t_c = %.3g s for %s at %.3g m/s)", a.collision,
                  a.collision_pair.c_str(), v);
    steps_across(a.collision, what);
  }
  if (a.rolling > 0 && std::isfinite(a.rolling)) {
    std::snprintf(what, sizeof what, "half period of the rolling spring (%.3g s for %s)", a.rolling,
                  a.rolling_pair.c_str());
    steps_across(a.rolling, what);
  }
  return a;
}

}  // namespace cohdem
