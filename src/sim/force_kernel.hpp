// The bulk force loop, compiled once per contact law (included only by registry.cpp).
//
// Pass 1 (parallel over i): every pair row of i; results go to per-pair buffers, no races.
// Pass 2 (parallel over particles): each particle sums its pair results in list order, then
//   evaluates its wall contacts. The order of every sum is fixed by the list, so results are
//   bit-identical for any thread count.
#pragma once
#include <cmath>
#include <limits>

#include "models/model_impl.hpp"
#include "sim/force_context.hpp"

namespace cohdem {

template <class Law>
void ContactModelImpl<Law>::compute(ForceContext& c) const {
  ParticleStore& P = c.p;
  NeighborList& nl = c.nl;
  const long n = long(P.size());
  auto* hs = reinterpret_cast<State*>(nl.hist.data.data());
  auto* ws = reinterpret_cast<State*>(nl.whist.data.data());
  uint8_t* live = nl.hist.live.data();
  uint8_t* wlive = nl.whist.live.data();
  constexpr double inf = std::numeric_limits<double>::infinity();
  const double dt = c.dt;

#pragma omp parallel for schedule(dynamic, 256)
  for (long i = 0; i < n; ++i) {
    const Vec3 xi = P.x[i];
    const double ri = P.radius[i];
    const int si = P.species[i];
    const bool fi = P.flag[i] == kFree;
    for (uint32_t k = nl.start[i]; k < nl.start[i + 1]; ++k) {
      const uint32_t j = nl.jdx[k];
      const Vec3 d = xi - (P.x[j] + nl.shift[nl.image[k]]);
      const double rsum = ri + P.radius[j];
      const double dist2 = norm2(d);
      if (!live[k] && dist2 >= rsum * rsum) continue;
      const double dist = std::sqrt(dist2);
      PairGeom g;
      g.n = d / dist;
      g.delta = rsum - dist;
      g.ri = ri;
      g.rj = P.radius[j];
      g.rstar = ri * g.rj / rsum;
      const bool fj = P.flag[j] == kFree;
      g.mi = fi ? P.mass[i] : inf;
      g.mj = fj ? P.mass[j] : inf;
      g.Ii = fi ? P.inertia[i] : inf;
      g.Ij = fj ? P.inertia[j] : inf;
      g.mstar = 1.0 / ((fi ? 1.0 / g.mi : 0.0) + (fj ? 1.0 / g.mj : 0.0));
      const Vec3 vij = P.v[i] - P.v[j];
      g.vn = dot(vij, g.n);
      const double li = ri - 0.5 * g.delta, lj = g.rj - 0.5 * g.delta;
      const Vec3 vrel = vij - cross(P.omega[i] * li + P.omega[j] * lj, g.n);
      g.vt = vrel - g.n * dot(vrel, g.n);
      g.wrel = P.omega[i] - P.omega[j];
      g.dt = dt;
      PairForce out;
      const bool alive = Law::evaluate(p(si, P.species[j]), g, hs[k], out);
      live[k] = alive;
      if (alive) {
        c.f_pair[k] = out.f;
        c.ti_pair[k] = out.ti;
        c.tj_pair[k] = out.tj;
        if (c.a_pair) c.a_pair[k] = out.a;
      }
    }
  }

#pragma omp parallel for schedule(static)
  for (long i = 0; i < n; ++i) {
    Vec3 F, T;
    for (uint32_t k = nl.start[i]; k < nl.start[i + 1]; ++k)
      if (live[k]) { F += c.f_pair[k]; T += c.ti_pair[k]; }
    for (uint32_t q = nl.rstart[i]; q < nl.rstart[i + 1]; ++q) {
      const uint32_t k = nl.rpair[q];
      if (live[k]) { F -= c.f_pair[k]; T += c.tj_pair[k]; }
    }
    for (uint32_t e = nl.wstart[i]; e < nl.wstart[i + 1]; ++e) {
      const Wall& w = c.walls[nl.wall[e]];
      PairGeom g;
      double delta;
      if (!w.contact(P.x[i], P.radius[i], g.n, delta) || (!wlive[e] && delta <= 0)) {
        if (wlive[e]) { ws[e] = State{}; wlive[e] = 0; }
        continue;
      }
      g.delta = delta;
      g.ri = P.radius[i];
      g.rj = 0;
      g.rstar = g.ri;
      g.mi = g.mstar = P.mass[i];
      g.mj = g.Ij = inf;
      g.Ii = P.inertia[i];
      const double li = g.ri - delta;
      const Vec3 cp = P.x[i] - g.n * li;
      const Vec3 vw = w.velocity_at(cp, c.t);
      g.vn = dot(P.v[i] - vw, g.n);
      const Vec3 vrel = P.v[i] - vw - cross(P.omega[i] * li, g.n);
      g.vt = vrel - g.n * dot(vrel, g.n);
      g.wrel = P.omega[i] - w.omega;
      g.dt = dt;
      PairForce out;
      const bool alive = Law::evaluate(p(P.species[i], w.material), g, ws[e], out);
      wlive[e] = alive;
      if (alive) {
        F += out.f;
        T += out.ti;
        c.f_wall[e] = out.f;
        c.tw_wall[e] = out.tj;
        c.c_wall[e] = cp;
        if (c.a_wall) c.a_wall[e] = out.a;
      }
    }
    P.force[i] = F;
    P.torque[i] = T;
  }
}

}  // namespace cohdem
