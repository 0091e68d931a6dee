// Contact history (tangential spring f_s and its stiffness, EPSD rolling spring, MEPA's plastic overlap) survives
// neighbor-list rebuilds and particle re-sorting in the middle of a contact.
//
// The reference is the same motion without any rebuild (a skin large enough that none is
// needed). History is keyed by particle ids and copied across each rebuild, so a run with
// rebuilds must give exactly the same forces at every step: the tangential force is then
// continuous across the rebuild and equal to the force without rebuild. A run whose history
// is wiped at the rebuilds shows what a lost spring looks like (and that the comparison sees
// it). Each particle here has a single contact, so no sum changes order when the list does,
// and equality is bitwise.
//
// Contacts: sphere A slides on the plane z = 0 (launched at 0.02 m/s, mu = 0.3: it slides
// for 2 v0/(7 mu g) ~ 2 ms with the tangential spring at its Coulomb limit, then rolls with
// the spring sticking and the EPSD spring at its limit); sphere B sits on a frozen sphere C
// and is nudged sideways, so its pair contact carries a sticking tangential spring and a
// loaded rolling spring while it begins to roll over.
//
// A pair lives in the row of the particle with the lower index. B is added before C (B holds
// the pair's row), and the cell sort puts C, lower in z, before B: the first forced re-sort
// moves the pair to C's row and its history must be rewritten as seen from C (the springs change sign).
// The forces must still be the reference's bit for bit (the contact law is evaluated from the
// other side, with the same magnitudes), and the flip must have happened (NeighborStats).
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "fixture.hpp"

using namespace cohdem;
using namespace cohdem::testing;

namespace {

constexpr double kR = 0.01, kRho = 2500, kG = 9.81;

enum class Mode {
  Reference,     ///< no rebuild at all
  Forced,        ///< nl.build every 50 steps (no re-sort)
  ForcedResort,  ///< nl.build with re-sorting every 50 steps
  Natural,       ///< fast far particles trigger rebuilds; cfg.sort_every = 1 re-sorts each time
  Wiped,         ///< like Forced, but the history is erased after each rebuild (negative control)
};

struct Trace {
  std::vector<Vec3> fa, ta, fb, tb;  // force (minus weight) and torque on A and B per step
  uint64_t builds = 0, lost = 0, flipped = 0;
  bool permuted = false;  // A or B changed local index at some point
};

Trace run(const std::string& model, Mode mode) {
  // hertz_mindlin: E = 1e8 Pa gives ~4e4 N/m at the resting overlap, like kn above. MEPA
  // (n = 3/2, the ring shear ore's exponent): k1 = 2.5e7 N/m^1.5 rests a sphere at 2.6 um
  // (1.5 k1 delta^0.5 = 6e4 N/m), with the plastic overlap, the adhesive branch and the
  // tangential stiffness k1 delta^(1/2) in its history.
  ParamSet p = model == "mepa" ? params({{"k1", 2.5e7}, {"k2", 1.25e8}, {"kadh", 2.5e7}, {"n", 1.5}, {"gamma_n", 0.5},
                                         {"mu", 0.3}, {"mu_r", 0.05}, {"eta_r", 0.3}})
                               : params({{"kn", 4e4}, {"e", 0.5}, {"mu", 0.3}, {"damp_t", 1.0}, {"mu_r", 0.05}, {"eta_r", 0.3}});
  auto s = make_system({{"glass", kRho, 1e8, 0.25}}, model, "epsd", p, 2.5e-5, {0, 0, -kG}, 5e-3);
  s->cfg.sort_every = mode == Mode::Natural ? 1 : 0;
  // The natural rebuilds are the global trigger's (far particles flying off): the local
  // check (SimConfig::local_rebuild) would keep the lists, as nothing nears anything.
  s->cfg.local_rebuild = 0;
  s->walls.push_back(plane({0, 0, 0}, {0, 0, 1}, 0));
  s->add_particle(0, kR, {0, 0, kR}, {0.02, 0, 0});                   // A (id 0)
  // C and B lie at lower x than A: the cell sort puts them first, so re-sorting moves A.
  s->add_particle(0, kR, {-0.1, 0, 3 * kR}, {0.01, 0, 0});              // B (id 1)
  const size_t c = s->add_particle(0, kR, {-0.1, 0, kR});               // C (id 2), frozen
  s->particles.flag[c] = kFrozen;
  // Two frozen particles out of reach (ids 3 and 4, between C and A; walls leave frozen
  // particles alone) span z from -0.6 kR to 5 kR: two layers of cells (at least 2.5 kR each),
  // whose boundary, at 2.2 kR, lies between C and B, so the cell sort puts C before B.
  for (const Vec3& x : {Vec3{-0.05, 0, -0.6 * kR}, Vec3{-0.05, 0, 5 * kR}})
    s->particles.flag[s->add_particle(0, kR, x)] = kFrozen;
  if (mode == Mode::Natural) {
    // Far particles (ids 5..8), at lower x than A-C (so the cell sort puts them first), flying
    // off upwards and sideways at 6 m/s: relative to the frozen C they move ~6.2 m/s, so the
    // list is rebuilt every ~skin/6.2 m/s ~ 0.8 ms (NeighborList::needs_rebuild), and as they
    // change cells the sort order changes.
    for (int k = 0; k < 4; ++k)
      s->add_particle(0, kR, {-0.5 - 0.1 * k, 0.1 * k, 0.02}, {0.5 * k, 0, 6.0});
  }
  s->prepare();
  Trace tr;
  const double m = s->particles.mass[0];
  for (int k = 0; k < 3000; ++k) {
    s->step_once();
    if (k % 50 == 25 && (mode == Mode::Forced || mode == Mode::ForcedResort || mode == Mode::Wiped)) {
      s->nl.build(s->particles, s->walls, s->cfg.domain, s->cfg.skin, s->reach(), mode == Mode::ForcedResort);
      if (mode == Mode::Wiped) {
        s->nl.hist.resize(s->nl.pair_count());
        s->nl.whist.resize(s->nl.wall_entry_count());
      }
    }
    const size_t a = index_of(*s, 0), b = index_of(*s, 1);
    tr.permuted = tr.permuted || a != 0 || b != 1;
    const Vec3 w = s->cfg.gravity * m;
    tr.fa.push_back(s->particles.force[a] - w);
    tr.ta.push_back(s->particles.torque[a]);
    tr.fb.push_back(s->particles.force[b] - w);
    tr.tb.push_back(s->particles.torque[b]);
  }
  tr.builds = s->nl.stats.builds;
  tr.lost = s->nl.stats.lost_contacts;
  tr.flipped = s->nl.stats.flipped;
  return tr;
}

/// First step at which two traces differ (bitwise), or -1.
int first_difference(const Trace& x, const Trace& y) {
  for (size_t k = 0; k < x.fa.size(); ++k)
    if (!(x.fa[k] == y.fa[k] && x.ta[k] == y.ta[k] && x.fb[k] == y.fb[k] && x.tb[k] == y.tb[k])) return int(k);
  return -1;
}

}  // namespace

TEST(History, SurvivesRebuildsAndResorting) {
  for (const char* model : {"linear", "hertz_mindlin", "mepa"}) {
    const Trace ref = run(model, Mode::Reference);
    ASSERT_EQ(ref.builds, 1u) << model << ": the reference must not rebuild";
    // The contacts carry history: A slides then rolls (|F_t| > 0 throughout), B is loaded.
    EXPECT_GT(std::fabs(ref.fa[10].x), 0.0);
    EXPECT_GT(std::fabs(ref.fa[2000].x), 0.0);
    EXPECT_GT(norm(ref.tb[1000]), 0.0);

    for (Mode mode : {Mode::Forced, Mode::ForcedResort, Mode::Natural}) {
      const Trace t = run(model, mode);
      const std::string tag = std::string(model) + (mode == Mode::Forced         ? " forced rebuilds"
                                                    : mode == Mode::ForcedResort ? " forced rebuilds + re-sort"
                                                                                 : " natural rebuilds, sort_every=1");
      EXPECT_GT(t.builds, 50u) << tag;
      EXPECT_EQ(t.lost, 0u) << tag;
      if (mode != Mode::Forced) EXPECT_TRUE(t.permuted) << tag << ": re-sorting did not move A or B";
      // The first re-sort of the forced mode comes with B and C in contact (the natural
      // mode's first sort is at the start, before they touch).
      if (mode == Mode::ForcedResort)
        EXPECT_GT(t.flipped, 0u) << tag << ": no history was read from the other side (B-C not swapped)";
      if (mode == Mode::Forced) EXPECT_EQ(t.flipped, 0u) << tag << ": without a re-sort no pair changes rows";
      EXPECT_EQ(first_difference(ref, t), -1) << tag;
      report(("history: first step differing from no-rebuild run, " + tag).c_str(), first_difference(ref, t), -1, 0,
             "==");
    }
    // Negative control: with the history erased at the rebuilds the tangential force jumps
    // (the spring restarts from zero), so the comparison above would catch a lost history.
    const Trace w = run(model, Mode::Wiped);
    const int k = first_difference(ref, w);
    EXPECT_EQ(k, 26) << model << ": wiping the history must show at the first forced rebuild";
  }
}

// A force evaluation without a time step (System::prepare: the start of a run, or a change of
// the particles or walls in the middle of one) must not advance the springs: their
// displacement is the integral of the sliding and rolling velocities over time, and no time
// passes. At the start the springs are therefore zero (the tangential spring's displacement is
// the integral of v_t over zero time), and a prepare() in the middle of a run is the same
// instant evaluated again.
//
// Sphere B touches the frozen sphere A with overlap delta0 (no normal velocity), slides past
// it at v0 and spins about an axis in the tangent plane; e = 1 (no dashpot), gamma_r = 0 (no
// rolling dashpot), mu and mu_r large (the springs stick). `press`: gravity g along -x holds B
// on A at the overlap m g / kn, so that the contact lasts (kn 10 N/m); otherwise kn 1e4 N/m
// and delta0 = 1e-5 m.
namespace {

struct Pair {
  std::unique_ptr<System> s;
  double kn, kt, delta0;
};
constexpr double kV0 = 0.01, kW0 = 3.0, kDt = 1e-6, kRp = 1e-3;

Pair sliding_pair(bool press) {
  const double kn = press ? 10.0 : 1e4, g = 9.81, rho = 2500;
  const double m = rho * 4.0 / 3.0 * M_PI * kRp * kRp * kRp;
  const double delta0 = press ? m * g / kn : 1e-5;
  Pair p{make_system({{"glass", rho, 0, 0}}, "linear", "sds",
                     params({{"kn", kn}, {"e", 1.0}, {"mu", 10.0}, {"k_r", kn / 20}, {"gamma_r", 0.0}, {"mu_r", 10.0}}),
                     kDt, press ? Vec3{-g, 0, 0} : Vec3{}),
         kn, 2.0 / 7.0 * kn, delta0};
  const size_t a = p.s->add_particle(0, kRp, {0.01, 0.01, 0.01}, {}, {});
  p.s->particles.flag[a] = kFrozen;
  p.s->add_particle(0, kRp, {0.01 + 2 * kRp - delta0, 0.01, 0.01}, {0, kV0, 0}, {0, 0, kW0});
  return p;
}

/// B's contact force minus its weight, split along the current normal (A to B) and across it.
std::pair<double, Vec3> normal_and_tangential(const System& s) {
  const size_t a = index_of(s, 0), b = index_of(s, 1);
  const Vec3 n = normalized(s.particles.x[b] - s.particles.x[a]);
  const Vec3 f = s.particles.force[b] - s.cfg.gravity * s.particles.mass[b];
  return {dot(f, n), f - n * dot(f, n)};
}

}  // namespace

TEST(History, FirstForcesHoldTheSpringsAtZero) {
  Pair p = sliding_pair(false);
  System& s = *p.s;
  s.prepare();
  const auto [fn, ft] = normal_and_tangential(s);
  // The normal force alone, kn delta0 = 0.1 N. A spring advanced by one step would add
  // kt v_t dt = 2.0e-5 N across the normal, and its moment; 1e-12 N is rounding.
  EXPECT_NEAR(fn, p.kn * p.delta0, 1e-12);
  EXPECT_LE(norm(ft), 1e-12) << "tangential force before any time has passed";
  EXPECT_LE(norm(s.particles.torque[index_of(s, 1)]), 1e-15) << "moment before any time has passed";
  report("history: tangential force at the first evaluation, N", norm(ft), 0, 1e-12);

  // One step later the spring holds one step's sliding, -kt v_t dt along y. B's contact point
  // moves at v_t = v0 - (r - delta0/2) w0 (the spin about z at cohdem's lever arm; A is
  // frozen), and no tangential force acted in the first half-step, so the midpoint velocities
  // are the initial ones. 1e-5 relative: the normal turns by v0 dt / 2r = 5e-6 rad in the step.
  s.step_once();
  const double vt = kV0 - (kRp - 0.5 * p.delta0) * kW0;
  const double ratio = normal_and_tangential(s).second.y / (-p.kt * vt * kDt);
  EXPECT_NEAR(ratio, 1.0, 1e-5) << "the spring after one step (2 if the first evaluation had advanced it)";
  report("history: tangential force after one step / (-kt v_t dt)", ratio, 1.0, 1e-5, "rel");
}

TEST(History, PrepareInTheMiddleOfARunDoesNotAdvanceTheSprings) {
  auto trace = [](bool again) {
    Pair p = sliding_pair(true);
    System& s = *p.s;
    s.prepare();
    for (int k = 0; k < 200; ++k) {
      if (again && k == 100) s.prepare();  // the same instant, evaluated again
      s.step_once();
    }
    return std::pair{normal_and_tangential(s).second, s.particles.torque[index_of(s, 1)]};
  };
  const auto [f0, t0] = trace(false);
  const auto [f1, t1] = trace(true);
  // After 200 steps the springs hold 200 steps of sliding and rolling: one step's increment
  // more would be 0.5 % of them. The two runs differ only in the rounding of turning a spring
  // into the plane it is already in: 1e-9 relative.
  ASSERT_GT(norm(f0), 0.0);
  ASSERT_GT(norm(t0), 0.0);
  EXPECT_LE(norm(f1 - f0), 1e-9 * norm(f0));
  EXPECT_LE(norm(t1 - t0), 1e-9 * norm(t0));
  report("history: tangential force, prepare() at step 100 against none (rel)", norm(f1 - f0) / norm(f0), 0, 1e-9);
}
