// Analytic checks of heat conduction and thermal expansion (docs/packed-beds.md, "Checks").
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>

#include "io/checkpoint.hpp"
#include "physics/fixture.hpp"
#include "thermal/thermal.hpp"

using namespace cohdem;
using namespace cohdem::testing;

namespace {

Material glass(double k, double c, double alpha, double T_ref, double E = 0, double nu = 0.25) {
  Material m{"glass", 2500, E, nu};
  m.conductivity = k;
  m.heat_capacity = c;
  m.expansion = alpha;
  m.T_ref = T_ref;
  return m;
}

/// N spheres of radius r in a row along x between walls at x = 0 and x = L, every contact
/// (pairs and both walls) with overlap delta; linear springs make that an equilibrium.
std::unique_ptr<System> chain(int N, double r, double delta, const Material& m, double dt) {
  auto s = make_system({m}, "linear", "none", params({{"kn", 1e4}, {"e", 0.5}, {"mu", 0.5}}), dt);
  s->cfg.threads = 1;  // a handful of particles: threads only add overhead
  double x = r - delta;
  for (int k = 0; k < N; ++k) {
    s->add_particle(0, r, {x, 0, 0});
    if (k + 1 < N) x += 2 * r - delta;
  }
  s->walls.push_back(plane({0, 0, 0}, {1, 0, 0}, 0));
  s->walls.push_back(plane({x + r - delta, 0, 0}, {-1, 0, 0}, 0));
  return s;
}

ThermalSettings settings(double S, std::vector<WallThermal> walls = {}) {
  ThermalSettings t;
  t.enabled = true;
  t.time_scale = S;
  t.walls = std::move(walls);
  return t;
}

WallThermal fixed(double T) { return {true, Schedule::constant(T)}; }

}  // namespace

TEST(Thermal, ScheduleIsPiecewiseLinearAndPeriodic) {
  Schedule s{{0, 1, 3}, {10, 20, 0}, 4};
  EXPECT_DOUBLE_EQ(s.at(0.5), 15);
  EXPECT_DOUBLE_EQ(s.at(2), 10);
  EXPECT_DOUBLE_EQ(s.at(3.5), 0);      // held between the last time and the period
  EXPECT_DOUBLE_EQ(s.at(4.5), 15);     // repeated
  EXPECT_DOUBLE_EQ(s.at(-3.5), 15);
  Schedule once{{1, 2}, {5, 7}, 0};
  EXPECT_DOUBLE_EQ(once.at(0), 5);
  EXPECT_DOUBLE_EQ(once.at(9), 7);
  EXPECT_DOUBLE_EQ(Schedule::constant(300).at(123), 300);
}

// Series resistances: 1/H_w + (N-1)/H_p + 1/H_w with H = 2 k_s a, a = sqrt(R* delta),
// R* = r/2 between spheres and r at a wall. The explicit scheme's fixed point is the exact
// steady state, so the check is tight.
TEST(Thermal, ConductionChainReachesSeriesResistanceSteadyState) {
  const int N = 5;
  const double r = 1e-3, delta = 1e-6, k = 1.5, Th = 400, Tc = 300;
  auto s = chain(N, r, delta, glass(k, 1000, 0, 300), 1e-6);
  s->cfg.initial_temperature = 300;
  s->thermal = std::make_shared<ThermalModel>(settings(2e7, {fixed(Th), fixed(Tc)}), s->materials);
  s->prepare();
  s->run(4000);
  const double Hp = 2 * k * std::sqrt(0.5 * r * delta), Hw = 2 * k * std::sqrt(r * delta);
  const double Q = (Th - Tc) / (2 / Hw + (N - 1) / Hp);
  double T = Th - Q / Hw;
  // Particles may be re-sorted in memory: go by x.
  std::vector<size_t> order(N);
  for (int i = 0; i < N; ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return s->particles.x[a].x < s->particles.x[b].x; });
  for (int q = 0; q < N; ++q) {
    EXPECT_NEAR(s->particles.temperature[order[q]], T, 1e-9 * Th) << "particle " << q;
    T -= Q / Hp;
  }
  EXPECT_NEAR(s->thermal->wall_heat[0], Q, 1e-9 * Q);
  EXPECT_NEAR(s->thermal->wall_heat[1], -Q, 1e-9 * Q);
  // Nothing moved: the chain is in equilibrium.
  EXPECT_LT(s->kinetic_energy(), 1e-20);
}

// Two spheres, adiabatic walls: d(T1 - T2)/dt = -(T1 - T2)/tau, tau = m c / (2 H S).
TEST(Thermal, TwoTouchingSpheresRelaxWithTheAnalyticTimeConstant) {
  const double r = 1e-3, delta = 1e-6, k = 1.0, c = 800, S = 1e5, dt = 1e-6;
  auto s = chain(2, r, delta, glass(k, c, 0, 300), dt);
  s->thermal = std::make_shared<ThermalModel>(settings(S), s->materials);
  s->particles.temperature = {400, 300};
  s->prepare();
  const double H = 2 * k * std::sqrt(0.5 * r * delta);
  const double m = s->particles.mass[0];
  const double tau = m * c / (2 * H * S);
  const double E0 = thermal_energy(*s);
  const uint64_t steps = uint64_t(std::llround(tau / dt));
  ASSERT_GT(steps, 500u);
  s->run(steps);
  const double d = s->particles.temperature[0] - s->particles.temperature[1];
  const double dT = s->particles.x[0].x < s->particles.x[1].x ? d : -d;
  EXPECT_NEAR(dT, 100 * std::exp(-double(steps) * dt / tau), 100 * 2e-3);
  EXPECT_NEAR(thermal_energy(*s), E0, 1e-12 * E0);  // heat is exchanged, never lost
}

// Spot radius from the force (Hertz): equals the overlap radius for the law's own modulus and
// scales as E_c^(-1/3) with a conduction modulus.
TEST(Thermal, HertzForceSpotRadius) {
  const double r = 1e-3, E = 1e8;
  for (double Ec : {0.0, 8e8}) {
    Material m = glass(1.0, 800, 0, 300, E);
    m.E_conduction = Ec;
    auto s = make_system({m}, "hertz_mindlin", "none", params({{"e", 0.5}, {"mu", 0.5}}), 1e-7);
    s->cfg.threads = 1;
    s->add_particle(0, r, {0, 0, 0});
    s->add_particle(0, r, {2 * r - 2e-6, 0, 0});
    ThermalSettings t = settings(1);
    t.contact_radius = ThermalSettings::SpotRadius::HertzForce;
    s->thermal = std::make_shared<ThermalModel>(t, s->materials);
    s->prepare();
    const double a_overlap = std::sqrt(0.5 * r * 2e-6);
    const double want = 2 * 1.0 * a_overlap * (Ec > 0 ? 0.5 : 1.0);
    double h = 0;
    for (double v : s->thermal->h_pair) h = std::max(h, v);
    EXPECT_NEAR(h, want, 1e-6 * want) << "E_c = " << Ec;
  }
}

// A free particle heated at specific power P: T = T0 + P t / c, r = r0 (1 + alpha (T - T_ref)),
// mass unchanged, inertia 2/5 m r^2.
TEST(Thermal, FreeParticleExpandsWithConstantMass) {
  const double r0 = 1e-3, c = 1000, alpha = 1e-5, P = 1e5, dt = 1e-4;
  auto s = make_system({glass(1.0, c, alpha, 300)}, "linear", "none", params({{"kn", 1e4}, {"e", 0.5}, {"mu", 0.5}}), dt);
  s->cfg.initial_temperature = 300;
  s->cfg.threads = 1;
  s->add_particle(0, r0, {0, 0, 0});
  const double m0 = s->particles.mass[0];
  ThermalSettings t = settings(1);
  t.sources.push_back({"heater", std::nullopt, -1, Schedule::constant(P)});
  s->thermal = std::make_shared<ThermalModel>(t, s->materials);
  s->prepare();
  s->run(1000);
  const double dT = P * 1000 * dt / c;  // 10 K
  EXPECT_NEAR(s->particles.temperature[0], 300 + dT, 1e-9);
  EXPECT_NEAR(s->particles.radius[0], r0 * (1 + alpha * dT), 1e-15);
  EXPECT_DOUBLE_EQ(s->particles.radius0[0], r0);
  EXPECT_DOUBLE_EQ(s->particles.mass[0], m0);
  EXPECT_NEAR(s->particles.inertia[0], 0.4 * m0 * std::pow(r0 * (1 + alpha * dT), 2), 1e-20);
  // bit for bit the solid sphere's formula, which the contact lanes compute instead of reading
  EXPECT_EQ(s->particles.inertia[0], sphere_inertia(s->particles.mass[0], s->particles.radius[0]));
  EXPECT_NEAR(s->thermal->source_power, P * m0, 1e-9 * P * m0);
  // Cooling below the reference temperature shrinks it.
  s->thermal = std::make_shared<ThermalModel>(
      [&] { ThermalSettings u = settings(1); u.sources.push_back({"cooler", std::nullopt, -1, Schedule::constant(-P)}); return u; }(),
      s->materials);
  s->run(2000);
  EXPECT_NEAR(s->particles.radius[0], r0 * (1 - alpha * dT), 1e-15);
}

// Simple-cubic lattice of n^3 Hertzian spheres (radius r0, just touching each other and the
// walls of a rigid box of the same material, side 2 n r0), heated uniformly by dT. Each row of
// n spheres is an independent chain with one force F along it:
//   2 delta_w + (n - 1) delta_p = 2 n r0 alpha dT   (the spheres grew, the box did not)
//   F = 4/3 E* sqrt(R*) delta^(3/2) with R* = r/2 (pairs) and r (walls), so
//   delta_w = 2^(-1/3) delta_p,  delta_p = 2 n r0 alpha dT / (n - 1 + 2^(2/3)),
//   F = 4/3 E* sqrt(r/2) delta_p^(3/2),   r = r0 (1 + alpha dT);
// each wall carries n^2 F, i.e. F per particle touching it. Frictionless: with friction the
// side walls would hold back the outer rows as they shift (locked-in wall shear, the effect the
// packed-bed runs show) and the end walls would carry less. Cooling back opens every contact.
TEST(Thermal, ConfinedSimpleCubicLatticeWallForcePerParticle) {
  const int n = 3;
  const double r0 = 1e-3, E = 1e8, nu = 0.25, alpha = 1e-5, dT = 100, c = 1000, dt = 4e-6;
  auto s = make_system({glass(0.0, c, alpha, 300, E, nu)}, "hertz_mindlin", "none",
                       params({{"e", 0.3}, {"mu", 0.0}}), dt, {0, 0, 0}, 0.2 * r0);
  s->cfg.initial_temperature = 300;
  s->cfg.threads = 1;
  const double L = 2 * n * r0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) s->add_particle(0, r0, {(2 * i + 1) * r0, (2 * j + 1) * r0, (2 * k + 1) * r0});
  for (int d = 0; d < 3; ++d) {
    Vec3 nrm{};
    nrm[d] = 1;
    s->walls.push_back(plane({0, 0, 0}, nrm, 0));
    Vec3 p{};
    p[d] = L;
    s->walls.push_back(plane(p, -nrm, 0));
  }
  const double t_heat = 0.01;
  ThermalSettings t = settings(1);
  t.sources.push_back({"heat", std::nullopt, -1, Schedule{{0, t_heat, t_heat + 1e-12}, {c * dT / t_heat, c * dT / t_heat, 0}, 0}});
  s->thermal = std::make_shared<ThermalModel>(t, s->materials);
  s->prepare();
  const double m0 = s->particles.mass[0];
  s->run(uint64_t(2 * t_heat / dt));
  // The step that ends the heating is cut by the schedule: take the temperature reached.
  const double T1 = s->particles.temperature[0];
  ASSERT_NEAR(T1, 300 + dT, 1e-3);
  for (double T : s->particles.temperature) ASSERT_EQ(T, T1);
  const double Estar = E / (2 * (1 - nu * nu));
  const double r = r0 * (1 + alpha * (T1 - 300));
  const double dp = 2 * n * (r - r0) / (n - 1 + std::pow(2.0, 2.0 / 3.0));
  const double F = 4.0 / 3.0 * Estar * std::sqrt(0.5 * r) * std::pow(dp, 1.5);
  for (const Wall& w : s->walls) EXPECT_NEAR(std::fabs(dot(w.force, w.normal)) / (n * n), F, 2e-3 * F);
  EXPECT_DOUBLE_EQ(s->particles.mass[0], m0);
  // Cool back to the reference temperature: the stresses relax completely (elastic contacts).
  s->thermal = std::make_shared<ThermalModel>(
      [&] {
        ThermalSettings u = settings(1);
        u.sources.push_back({"cool", std::nullopt, -1, Schedule{{0, s->time + t_heat, s->time + t_heat + 1e-12}, {-c * dT / t_heat, -c * dT / t_heat, 0}, 0}});
        return u;
      }(),
      s->materials);
  s->run(uint64_t(2 * t_heat / dt));
  for (double T : s->particles.temperature) ASSERT_NEAR(T, 300, 1e-3);
  for (const Wall& w : s->walls) EXPECT_LT(norm(w.force), 1e-6 * F);
}

// Results do not depend on the thread count (per-particle gathers in list order).
TEST(Thermal, IndependentOfThreadCount) {
  auto run = [](int threads) {
    auto s = chain(6, 1e-3, 1e-6, glass(1.0, 1000, 1e-5, 300), 1e-6);
    s->cfg.threads = threads;
    s->cfg.parallel_min = 0;  // threads even for six particles
    s->thermal = std::make_shared<ThermalModel>(settings(2e7, {fixed(500), {}}), s->materials);
    s->prepare();
    s->run(300);
    std::vector<double> T(s->particles.temperature);
    return T;
  };
  EXPECT_EQ(run(1), run(2));
}

// The thermal fields (reference radius, temperature, heat flow) exist only in runs with a
// thermal model: a mechanical run carries none of their 24 bytes a particle. Once kept, they
// follow their particles through a re-sort and a removal, and a checkpoint carries them
// between runs: a thermal case resuming a mechanical run's checkpoint starts every particle at
// its initial temperature with its current radius as the reference (what the particles had
// when every run kept the fields), and a mechanical case drops a thermal run's.
TEST(Thermal, FieldsOnlyInThermalRunsAndFollowTheirParticles) {
  const double r = 1e-3;
  auto mech = chain(5, r, 1e-6, glass(1.0, 1000, 1e-5, 300), 1e-6);
  mech->prepare();
  mech->run(10);
  const size_t n = mech->particles.size();
  EXPECT_FALSE(mech->particles.thermal());
  EXPECT_TRUE(mech->particles.radius0.empty() && mech->particles.temperature.empty() &&
              mech->particles.heat_flow.empty());

  // Mechanical checkpoint into a thermal system: initial temperature, reference radius = radius.
  const auto path = std::filesystem::temp_directory_path() /
                    ("cohdem_test_thermal_fields_" + std::to_string(::getpid()) + ".bin");
  write_checkpoint(path, *mech);
  // A thermal model attached to a system prepared without one: its particles start at the
  // initial temperature (no heat flows between equal temperatures).
  mech->thermal = std::make_shared<ThermalModel>(settings(1), mech->materials);
  mech->run(2);
  ASSERT_TRUE(mech->particles.thermal());
  ASSERT_EQ(mech->particles.temperature.size(), n);
  for (double T : mech->particles.temperature) EXPECT_EQ(T, mech->cfg.initial_temperature);
  auto hot = chain(5, r, 1e-6, glass(1.0, 1000, 1e-5, 300), 1e-6);
  hot->cfg.initial_temperature = 350;
  hot->thermal = std::make_shared<ThermalModel>(settings(1), hot->materials);
  read_checkpoint(path, *hot);
  ASSERT_TRUE(hot->particles.thermal());
  ASSERT_EQ(hot->particles.temperature.size(), n);
  for (size_t i = 0; i < n; ++i) {
    EXPECT_EQ(hot->particles.temperature[i], 350);
    EXPECT_EQ(hot->particles.radius0[i], hot->particles.radius[i]);
    EXPECT_EQ(hot->particles.heat_flow[i], 0);
  }

  // Distinct values by id, then a permutation (a re-sort) and a removal: each stays with its id.
  ParticleStore& P = hot->particles;
  for (size_t i = 0; i < n; ++i) {
    P.temperature[i] = 300 + double(P.id[i]);
    P.radius0[i] = r * (1 + 1e-3 * double(P.id[i]));
    P.heat_flow[i] = -double(P.id[i]);
  }
  std::vector<uint32_t> perm(n);
  for (size_t k = 0; k < n; ++k) perm[k] = uint32_t(n - 1 - k);
  P.permute(perm);
  std::vector<uint8_t> remove(n, 0);
  remove[1] = 1;
  P.erase_if_flagged(remove);
  ASSERT_EQ(P.size(), n - 1);
  ASSERT_EQ(P.temperature.size(), n - 1);
  for (size_t i = 0; i < P.size(); ++i) {
    EXPECT_EQ(P.temperature[i], 300 + double(P.id[i]));
    EXPECT_EQ(P.radius0[i], r * (1 + 1e-3 * double(P.id[i])));
    EXPECT_EQ(P.heat_flow[i], -double(P.id[i]));
  }
  // A particle added to a thermal run gets the fields at once.
  hot->add_particle(0, r, {0, 0, 0.1});
  EXPECT_EQ(P.temperature.back(), 350);
  EXPECT_EQ(P.radius0.back(), r);

  // A thermal run's checkpoint into a mechanical system: the fields are dropped.
  hot->prepare();
  write_checkpoint(path, *hot);
  auto cold = chain(5, r, 1e-6, glass(1.0, 1000, 1e-5, 300), 1e-6);
  read_checkpoint(path, *cold);
  std::filesystem::remove(path);
  EXPECT_FALSE(cold->particles.thermal());
  EXPECT_TRUE(cold->particles.temperature.empty() && cold->particles.radius0.empty());
  EXPECT_EQ(cold->particles.size(), hot->particles.size());
}
