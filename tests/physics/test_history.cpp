// Contact history (tangential spring f_s and its stiffness, EPSD rolling spring) survives
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
  ParamSet p = params({{"kn", 4e4}, {"e", 0.5}, {"mu", 0.3}, {"damp_t", 1.0}, {"mu_r", 0.05}, {"eta_r", 0.3}});
  // hertz_mindlin: E = 1e8 Pa gives ~4e4 N/m at the resting overlap, like kn above.
  auto s = make_system({{"glass", kRho, 1e8, 0.25}}, model, "epsd", p, 2.5e-5, {0, 0, -kG}, 5e-3);
  s->cfg.sort_every = mode == Mode::Natural ? 1 : 0;
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
  for (const char* model : {"linear", "hertz_mindlin"}) {
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
