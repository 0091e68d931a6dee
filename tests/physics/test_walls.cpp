// Walls: moving walls drive particles through friction, curved walls bounce with the set
// restitution, and the wall totals balance what the particles receive.
//
// Sphere (m, R, I = 2/5 m R^2) at rest on a wall whose surface moves at U along x (a plane
// translating, or the bottom of a drum rotating about its axis). Friction F along x at the
// contact point (-R z from the centre) gives m v' = F and I w_y' = -R F, so the angular
// momentum about the contact line, I w_y + m R v, stays 0: w_y = -5 v/(2 R). The slip of the
// contact point over the wall, v - R w_y - U = 7/2 v - U, vanishes when
//   v = 2 U/7,  w_y = -5 U/(7 R),  at t1 = 2 U/(7 mu g) (sliding at F = mu m g until then),
// after which the sphere rolls with the wall at constant speed (no rolling resistance).
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "fixture.hpp"

using namespace cohdem;
using namespace cohdem::testing;

namespace {

constexpr double kR = 0.01, kRho = 2500, kKn = 1e7, kG = 9.81;

struct DragResult {
  double t1 = NAN, v1 = NAN, w1 = NAN, v_later = NAN;
};

/// Sphere starts at rest at its equilibrium overlap on wall 0 (the surface below it moving at
/// U along x); returns the end of sliding (interpolated) and the speed `later` s after it.
DragResult drag(System& s, double U, double later) {
  auto& P = s.particles;
  s.prepare();
  // Slip of the contact point over the wall, with the engine's lever arm R - delta, which is
  // the height z of the centre above the lowest point of the wall in both set-ups (plane at
  // z = 0; drum with its axis at height R_c, where delta = R + (R_c - z) - R_c).
  auto slip = [&] { return P.v[0].x - P.x[0].z * P.omega[0].y - U; };
  DragResult r;
  const double dt = s.cfg.dt, t1_ref = 2 * U / (7 * 0.3 * kG);
  double sl_prev = slip(), v_prev = P.v[0].x, w_prev = P.omega[0].y, t_prev = s.time;
  while (s.time < 3 * t1_ref) {
    s.step_once();
    const double sl = slip();
    if (sl >= 0) {
      const double f = sl_prev / (sl_prev - sl);
      r.t1 = t_prev + f * dt;
      r.v1 = v_prev + f * (P.v[0].x - v_prev);
      r.w1 = w_prev + f * (P.omega[0].y - w_prev);
      break;
    }
    sl_prev = sl; v_prev = P.v[0].x; w_prev = P.omega[0].y; t_prev = s.time;
  }
  s.run(uint64_t(later / dt));
  r.v_later = P.v[0].x;
  return r;
}

void check_drag(const DragResult& r, double U, double later, const std::string& tag) {
  const double mu = 0.3, t1 = 2 * U / (7 * mu * kG), v1 = 2 * U / 7, w1 = -5 * U / (7 * kR);
  ASSERT_FALSE(std::isnan(r.t1)) << tag;
  // Slip is linear in time while sliding, so the interpolated end is exact but for the lever
  // arm R - delta (delta/R = 1e-6) and, on the drum, the curvature (the sphere moves
  // ~mu g t1^2/2 ~ 6 um along a 0.1 m radius: a slope of 6e-5). Tolerance 2e-3 relative; the
  // later speed may ring a little after the switch to sticking (damp_t = 1): 2e-3. (In the
  // drum the sphere then swings as a pendulum: rolling up the wall by v1 t it slows by
  // 5/7 g (v1 t/(R_c - R)) t, 5e-4 of v1 at t = 2 ms, so it is checked that soon.)
  EXPECT_NEAR(r.t1 / t1, 1.0, 2e-3) << tag;
  EXPECT_NEAR(r.v1 / v1, 1.0, 2e-3) << tag;
  EXPECT_NEAR(r.w1 / w1, 1.0, 2e-3) << tag;
  EXPECT_NEAR(r.v_later / v1, 1.0, 2e-3) << tag;
  report(("wall drag: end of sliding t1 (s) " + tag).c_str(), r.t1, t1, 2e-3, "rel");
  report(("wall drag: speed 2U/7 (m/s) " + tag).c_str(), r.v1, v1, 2e-3, "rel");
  report(("wall drag: spin -5U/(7R) (rad/s) " + tag).c_str(), r.w1, w1, 2e-3, "rel");
  report(("wall drag: speed " + std::to_string(later).substr(0, 5) + " s later (m/s) " + tag).c_str(), r.v_later,
         v1, 2e-3, "rel");
}

std::unique_ptr<System> resting_system(double dt) {
  return make_system({{"glass", kRho, 0, 0}}, "linear", "none",
                     params({{"kn", kKn}, {"e", 0.5}, {"mu", 0.3}, {"damp_t", 1.0}}), dt, {0, 0, -kG}, 1e-3);
}

}  // namespace

TEST(Walls, TranslatingPlaneDragsSphereToTwoSevenths) {
  const double m = sphere_mass(kRho, kR), dt = M_PI * std::sqrt(m / kKn) / 20, U = 0.1;
  auto s = resting_system(dt);
  Wall w = plane({0, 0, 0}, {0, 0, 1}, 0);
  w.velocity = {U, 0, 0};
  s->walls.push_back(w);
  s->add_particle(0, kR, {0, 0, kR - m * kG / kKn});
  check_drag(drag(*s, U, 0.02), U, 0.02, "translating plane U=0.1");
}

TEST(Walls, RotatingDrumDragsSphereToTwoSevenths) {
  const double m = sphere_mass(kRho, kR), dt = M_PI * std::sqrt(m / kKn) / 20;
  const double Rc = 0.1, Omega = -0.2;  // about +y: the bottom of the drum moves at -Omega Rc = +0.02 m/s along x
  auto s = resting_system(dt);
  Wall w = cylinder({0, 0, Rc}, {0, 1, 0}, Rc, true, 0);
  w.omega = {0, Omega, 0};
  s->walls.push_back(w);
  s->add_particle(0, kR, {0, 0, kR - m * kG / kKn});
  const double U = -Omega * Rc;
  check_drag(drag(*s, U, 0.002), U, 0.002, "rotating drum U=0.02");
}

// Radial impacts on a cylinder from inside and from outside: the overlap r + s - R_c (inside)
// or r - (s - R_c) (outside), s the distance from the axis, changes at the radial speed, so the
// impact is the 1-D damped oscillator of test_impacts and e is the set restitution.
TEST(Walls, CylinderInsideAndOutsideRestitution) {
  const double r = 0.01, rho = 2500, kn = 1e6, Rc = 0.05, v = 1.0;
  const double m = sphere_mass(rho, r), w0 = std::sqrt(kn / m), dt = M_PI / w0 / 1000;
  for (bool inside : {true, false}) {
    for (double e : {0.3, 0.8}) {
      auto s = make_system({{"glass", rho, 0, 0}}, "linear", "none", params({{"kn", kn}, {"e", e}, {"mu", 0.3}}), dt);
      s->walls.push_back(cylinder({0, 0, 0}, {0, 0, 1}, Rc, inside, 0));
      const double g = 0.37 * v * dt;
      // Moving along x towards the wall (radially), from inside or outside.
      const double x0 = inside ? Rc - r - g : Rc + r + g;
      s->add_particle(0, r, {x0, 0, 0}, {inside ? v : -v, 0, 0});
      auto& P = s->particles;
      const ImpactTrace tr = trace_impact(
          *s,
          [&] {
            const double d = std::hypot(P.x[0].x, P.x[0].y);
            return inside ? r + d - Rc : r - (d - Rc);
          },
          [&] { return std::fabs(s->walls[0].force.x); }, 1000000);
      ASSERT_TRUE(tr.separated);
      const double e_meas = std::fabs(P.v[0].x) / v;
      const double l = std::log(e), zeta = -l / std::sqrt(M_PI * M_PI + l * l);
      const double tol = zeta * w0 * dt;  // as in test_impacts
      const std::string tag = std::string(inside ? "inside" : "outside") + " e=" + std::to_string(e).substr(0, 3);
      EXPECT_NEAR(e_meas, e, tol) << tag;
      EXPECT_LT(std::fabs(P.v[0].y), 1e-12) << tag;  // radial impact: no sideways kick
      report(("cylinder restitution " + tag).c_str(), e_meas, e, tol);
    }
  }
}

// Wall::force and Wall::torque (about Wall::center) must equal minus the total force and the
// total moment (about the same point) that the particles receive from that wall. Two
// particles per wall, spinning and moving into a rotating drum (inside, bounded) and a
// translating, spinning plane, with friction and EPSD rolling resistance, no gravity, no
// particle-particle contact: each particle's force and torque come from its wall only.
TEST(Walls, WallTotalsBalanceParticleLoads) {
  const double r = 0.005, Rc = 0.05, zp = -0.2;
  auto s = make_system({{"steel", 7800, 2e9, 0.3}}, "hertz_mindlin", "epsd",
                       params({{"e", 0.6}, {"mu", 0.4}, {"mu_r", 0.1}, {"eta_r", 0.3}}), 2e-7);
  Wall drum = cylinder({0, 0, 0}, {0, 0, 1}, Rc, true, 0);
  drum.zmin = -0.05;
  drum.zmax = 0.05;
  drum.omega = {0, 0, 5};
  s->walls.push_back(drum);
  Wall table = plane({0.3, 0, zp}, {0, 0, 1}, 0);
  table.center = {0.3, 0.02, zp};
  table.velocity = {0.3, -0.1, 0};
  table.omega = {0, 0, 4};
  s->walls.push_back(table);
  const double d = 1e-5;  // initial overlap
  // id 0, 1: in the drum, near its wall, moving outwards and spinning.
  s->add_particle(0, r, {Rc - r + d, 0, 0.01}, {0.5, 0.2, 0.1}, {10, -20, 30});
  s->add_particle(0, r, {0, -(Rc - r + d), -0.01}, {0.1, -0.4, 0}, {-5, 0, 15});
  // id 2, 3: on the table, moving into it and spinning.
  s->add_particle(0, r, {0.25, 0.03, zp + r - d}, {0.2, 0.1, -0.3}, {0, 40, -10});
  s->add_particle(0, r, {0.35, -0.02, zp + r - d}, {-0.3, 0, -0.2}, {25, 5, 0});
  s->prepare();
  double worst_f = 0, worst_t = 0;
  int steps_with_contacts = 0;
  for (int k = 0; k < 400; ++k) {
    s->step_once();
    if (s->contact_count() == 4) ++steps_with_contacts;
    for (size_t w = 0; w < 2; ++w) {
      const Wall& W = s->walls[w];
      Vec3 F, T;
      double fs = 0, ts = 0;
      for (size_t i = 0; i < s->particles.size(); ++i) {
        const uint64_t id = s->particles.id[i];
        if ((w == 0) != (id < 2)) continue;
        const Vec3 f = s->particles.force[i], t = s->particles.torque[i];
        F += f;
        T += cross(s->particles.x[i] - W.center, f) + t;
        fs += norm(f);
        ts += norm(cross(s->particles.x[i] - W.center, f)) + norm(t);
      }
      if (fs == 0) continue;
      // Round-off: a handful of operations on each term; 1e-13 of the summed magnitudes.
      worst_f = std::max(worst_f, norm(W.force + F) / fs);
      worst_t = std::max(worst_t, norm(W.torque + T) / ts);
    }
  }
  EXPECT_GT(steps_with_contacts, 50);
  EXPECT_LT(worst_f, 1e-13);
  EXPECT_LT(worst_t, 1e-13);
  report("wall force balance |W.force + sum F_i|/sum|F_i|", worst_f, 0.0, 1e-13, "<");
  report("wall torque balance |W.torque + sum(x_i-c) x F_i + T_i|/sum", worst_t, 0.0, 1e-13, "<");
}
