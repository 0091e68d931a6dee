// Conservation laws and static balance.
//
//  - Momentum: in a triply periodic box without gravity or walls, every contact force acts as
//    +f on one sphere and -f on the other (Newton's third law), so the total linear momentum is
//    constant; in floating point it drifts only by round-off.
//  - Energy: a frictionless, undamped (e = 1, mu = 0) linear-spring gas conserves
//    KE + sum over contacts of 1/2 kn delta^2; velocity Verlet keeps it to O((omega_0 dt)^2).
//  - Statics: a sphere resting on a plane and a two-sphere stack load the plane with m g and
//    2 m g (Wall::force), the stack's contact carrying m g.
#include <gtest/gtest.h>

#include <cmath>

#include "fixture.hpp"

using namespace cohdem;
using namespace cohdem::testing;

namespace {

constexpr double kL = 0.02;  // periodic box edge, m (200 spheres: solids fraction ~0.1)

/// A periodic box of ~n randomly placed spheres (r = 0.8..1.2 mm) with random velocities of
/// about `v` m/s in each direction.
void fill_periodic_gas(System& s, uint64_t n, double v) {
  s.cfg.domain.lo = {0, 0, 0};
  s.cfg.domain.hi = {kL, kL, kL};
  s.cfg.domain.periodic = {true, true, true};
  InsertSpec spec;
  spec.region.kind = Region::Kind::Box;
  spec.region.lo = {0, 0, 0};
  spec.region.hi = {kL, kL, kL};
  spec.size.kind = SizeDistribution::Kind::Uniform;
  spec.size.rmin = 0.8e-3;
  spec.size.rmax = 1.2e-3;
  spec.count = n;
  ASSERT_EQ(s.insert(spec), n);
  Rng rng(7);
  for (auto& vel : s.particles.v) vel = {v * rng.normal(), v * rng.normal(), v * rng.normal()};
}

/// Elastic energy 1/2 kn delta^2 over all overlapping pairs (minimum image; L > 2 r_max + ...).
double spring_energy(const System& s, double kn) {
  const auto& P = s.particles;
  double e = 0;
  for (size_t i = 0; i < P.size(); ++i)
    for (size_t j = i + 1; j < P.size(); ++j) {
      Vec3 d = P.x[i] - P.x[j];
      for (int k = 0; k < 3; ++k) d[k] -= kL * std::nearbyint(d[k] / kL);
      const double delta = P.radius[i] + P.radius[j] - norm(d);
      if (delta > 0) e += 0.5 * kn * delta * delta;
    }
  return e;
}

}  // namespace

// Frictional, damped, rolling-resisted Hertz-Mindlin collisions in a triply periodic box.
TEST(Conservation, MomentumInPeriodicBox) {
  const double E = 1e7, nu = 0.2, rho = 2500;
  // Hertz contact time at 1 m/s for r = 1 mm: ~2e-4 s; dt = 1e-5 s.
  auto s = make_system({{"soft", rho, E, nu}}, "hertz_mindlin", "epsd",
                       params({{"e", 0.7}, {"mu", 0.5}, {"mu_r", 0.1}, {"eta_r", 0.3}}), 1e-5, {0, 0, 0},
                       2e-4);
  fill_periodic_gas(*s, 200, 0.5);
  s->prepare();
  const Vec3 p0 = s->momentum();
  double scale = 0;
  for (size_t i = 0; i < s->particles.size(); ++i) scale += s->particles.mass[i] * norm(s->particles.v[i]);
  const uint64_t steps = 3000;
  double worst = 0;
  uint64_t contacts = 0, across = 0;
  for (uint64_t k = 0; k < steps; ++k) {
    s->step_once();
    contacts += s->pair_contact_count();
    for (size_t q = 0; q < s->nl.pair_count(); ++q) across += s->nl.hist.live[q] && s->nl.image[q] != kNoImage;
    worst = std::max(worst, norm(s->momentum() - p0) / scale);
  }
  std::printf("[info] momentum test: %llu contact-steps, %llu across the periodic boundary, %llu builds\n",
              (unsigned long long)contacts, (unsigned long long)across, (unsigned long long)s->nl.stats.builds);
  // Sanity: the gas did collide (also through the periodic boundaries) and rebuilt its lists.
  EXPECT_GT(contacts, 1000u);
  EXPECT_GT(across, 10u);
  EXPECT_GT(s->nl.stats.builds, 5u);
  // Round-off: each half kick rounds every velocity (relative 1.1e-16) and each force sum
  // rounds; over 3000 steps with two kicks each, a bound of steps * 2 * 2.2e-16 ~ 1.3e-12
  // of sum |m v| holds even if all errors added up. Tolerance 2e-12.
  EXPECT_LT(worst, 2e-12);
  report("momentum drift |P(t)-P(0)|/sum|m v|, periodic Hertz-Mindlin gas", worst, 0.0, 2e-12, "<");
}

TEST(Conservation, EnergyOfElasticFrictionlessGas) {
  const double kn = 1e4, rho = 2500;
  const double m_min = sphere_mass(rho, 0.8e-3);
  const double w0 = std::sqrt(kn / (m_min / 2));  // fastest contact: two smallest spheres
  const double dt = M_PI / w0 / 100;              // t_c/100 for the stiffest-per-mass pair
  auto s = make_system({{"glass", rho, 0, 0}}, "linear", "none", params({{"kn", kn}, {"e", 1.0}, {"mu", 0.0}}), dt,
                       {0, 0, 0}, 2e-4);
  fill_periodic_gas(*s, 250, 1.0);
  s->prepare();
  auto total = [&] { return s->kinetic_energy() + spring_energy(*s, kn); };
  const double e0 = total();
  double worst = 0;
  uint64_t contacts = 0;
  for (int k = 0; k < 4000; ++k) {
    s->step_once();
    contacts += s->pair_contact_count();
    if (k % 10 == 0) worst = std::max(worst, std::fabs(total() - e0) / e0);
  }
  std::printf("[info] energy test: %llu contact-steps (a contact lasts ~100 steps), %llu builds\n",
              (unsigned long long)contacts, (unsigned long long)s->nl.stats.builds);
  EXPECT_GT(contacts, 5000u);
  // Bound: velocity Verlet's energy error on a contact is bounded by ~(omega_0 dt)^2/4 of
  // the contact's energy (and the kinks at contact start/end add errors of the same order
  // per collision, of either sign). Even if the errors of all collisions in the run added up
  // with one sign it would stay below (omega_0 dt)^2 = (pi/100)^2 ~ 1e-3 of the total for a
  // gas where each sphere collides a few times. Tolerance (pi/100)^2.
  const double bound = std::pow(M_PI / 100, 2);
  EXPECT_LT(worst, bound);
  report("energy drift |E(t)-E(0)|/E(0), elastic frictionless gas, dt=t_c/100", worst, 0.0, bound, "<");
}

TEST(Conservation, RestingSphereAndStackCarryWeight) {
  const double r = 0.01, rho = 2500, kn = 1e5, g = 9.81;
  const double m = sphere_mass(rho, r);
  const double tc = M_PI * std::sqrt(m / kn);
  auto s = make_system({{"glass", rho, 0, 0}}, "linear", "none", params({{"kn", kn}, {"e", 0.3}, {"mu", 0.5}}),
                       tc / 40, {0, 0, -g});
  s->walls.push_back(plane({0, 0, 0}, {0, 0, 1}, 0));
  s->add_particle(0, r, {0, 0, r});  // touching, unloaded: it sinks to m g/kn and settles
  s->run(uint64_t(100 * 40));        // 100 contact times; e = 0.3 decays ~ e^(2 t/t_c)-fold
  // e = 0.3 damps the contact oscillation by a factor 0.3 per half period: after 100 t_c the
  // residual is ~0.3^200; what remains is round-off. Tolerance 1e-9 relative.
  EXPECT_NEAR(s->walls[0].force.z / (-m * g), 1.0, 1e-9);
  EXPECT_NEAR(s->walls[0].force.x, 0.0, 1e-12);
  report("resting sphere: wall force / (-m g)", s->walls[0].force.z / (-m * g), 1.0, 1e-9, "rel");

  // Two-sphere stack (touching, aligned on the vertical: it stays aligned exactly).
  s->add_particle(0, r, {0, 0, 3 * r});
  s->prepare();
  s->run(uint64_t(200 * 40));  // the slower mode of the stack has ~1.6 t_c period
  EXPECT_NEAR(s->walls[0].force.z / (-2 * m * g), 1.0, 1e-9);
  const size_t top = index_of(*s, 1);
  // The top sphere's contact carries its weight: total force on it is zero.
  EXPECT_NEAR(s->particles.force[top].z / (m * g), 0.0, 1e-9);
  report("two-sphere stack: wall force / (-2 m g)", s->walls[0].force.z / (-2 * m * g), 1.0, 1e-9, "rel");
}
