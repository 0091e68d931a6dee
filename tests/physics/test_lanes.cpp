// The linear law's contacts evaluated four at a time in AVX2 lanes (src/sim/lanes.hpp) must
// give the scalar law's results bit for bit: forces, torques, histories and which contacts
// live, contact by contact, and so whole runs. Checked on a bed that reaches every branch the
// scalar code has: two species with their own parameters per material pair (kt given or from
// kt_ratio, limit_damping on and off, tangential damping), frozen partners, periodic images,
// histories turned out of the tangent plane by small and by large angles, zero histories,
// sliding and sticking contacts, and live entries whose spheres have parted (history reset).
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <cstring>

#include "fixture.hpp"
#include "sim/force_kernel.hpp"
#include "sim/lanes.hpp"
#include "sim/screen.hpp"

using namespace cohdem;
using namespace cohdem::testing;

namespace {

constexpr double kL = 0.03;  // periodic cell in x and y, m

// 500 spheres of two species dropped onto a floor in a periodic cell (gravity 200 m/s^2, to
// settle in a few thousand steps), one in ten frozen;
// material pairs with parameters of their own.
std::unique_ptr<System> make_bed(int threads) {
  auto s = make_system({{"a", 2500, 0, 0}, {"b", 1500, 0, 0}}, "linear", "none",
                       params({{"kn", 2e3}, {"e", 0.5}, {"mu", 0.5}}), 1e-5, {0, 0, -200.0}, 3e-4);
  // a-a: the defaults (kt = 2/7 kn); a-b: kt given, limit_damping, tangential damping;
  // b-b: another restitution and friction, tangential damping.
  const ParamSet aa = params({{"kn", 2e3}, {"e", 0.5}, {"mu", 0.5}});
  const ParamSet ab = params({{"kn", 3e3}, {"e", 0.2}, {"mu", 0.3}, {"kt", 1.1e3}, {"limit_damping", 1}, {"damp_t", 0.5}});
  const ParamSet bb = params({{"kn", 1e3}, {"e", 0.9}, {"mu", 0.8}, {"damp_t", 1.0}});
  s->set_model(make_contact_model("linear", "none"), {aa, ab, ab, bb});
  s->cfg.threads = threads;
  s->cfg.parallel_min = 0;
  s->cfg.domain.lo = {0, 0, 0};
  s->cfg.domain.hi = {kL, kL, 0};
  s->cfg.domain.periodic = {true, true, false};
  s->rng = Rng(11);
  s->walls.push_back(plane({0, 0, 0}, {0, 0, 1}, 0));
  for (int sp = 0; sp < 2; ++sp) {
    InsertSpec spec;
    spec.region.lo = {0, 0, 0};
    spec.region.hi = {kL, kL, 0.02};
    spec.size.kind = SizeDistribution::Kind::Uniform;
    spec.size.rmin = 1.0e-3;
    spec.size.rmax = 1.5e-3;
    spec.count = 250;
    spec.species = sp;
    EXPECT_EQ(s->insert(spec), 250u);
  }
  Rng rng(5);
  auto& P = s->particles;
  for (size_t i = 0; i < P.size(); ++i) {
    P.v[i] = Vec3{rng.normal(), rng.normal(), rng.normal()} * 0.3;
    P.omega[i] = Vec3{rng.normal(), rng.normal(), rng.normal()} * 300.0;
    if (i % 10 == 3) P.flag[i] = kFrozen;
  }
  s->prepare();
  return s;
}

struct Result {
  std::vector<Vec3> f, t, x, v, w;
  std::vector<std::byte> hist;
  std::vector<uint8_t> live;
};

Result state_of(const System& s) {
  return {s.particles.force, s.particles.torque, s.particles.x, s.particles.v, s.particles.omega, s.nl.hist.data,
          s.nl.hist.live};
}

// One call of the force loop (no kicks), scalar or in lanes.
Result force_call(System& s, bool lanes) {
  set_screen_avx2(lanes);
  const size_t n = s.particles.size();
  std::vector<PairResult> pair(s.nl.pair_count()), rev(n);
  std::vector<Vec3> fw(s.nl.wall_entry_count()), tw(fw.size()), cw(fw.size());
  ForceContext c{s.particles, s.nl, s.walls, s.cfg.dt, s.time, pair, rev, fw, tw, cw, s.cfg.gravity};
  c.keep_pair = false;
  s.model->compute(c);
  return state_of(s);
}

size_t differing(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  size_t d = 0;
  for (size_t i = 0; i < a.size(); ++i) d += std::memcmp(&a[i], &b[i], sizeof(Vec3)) != 0;
  return d;
}

bool avx2_here() {
  const bool was = screen_avx2_enabled();
  set_screen_avx2(true);
  const bool ok = screen_avx2_enabled();
  set_screen_avx2(was);
  return ok;
}

}  // namespace

TEST(Lanes, LinearLawContactByContactAsTheScalarLaw) {
  if (!avx2_here()) GTEST_SKIP() << "no AVX2 on this CPU or build: the scalar law runs alone";
  const bool was = screen_avx2_enabled();
  auto s = make_bed(1);
  s->run(3000);  // settling: contacts with histories, frozen partners, images
  auto& nl = s->nl;
  auto* fs = reinterpret_cast<Vec3*>(nl.hist.data.data());
  ASSERT_GE(nl.hist.data.size(), nl.jdx.size() * sizeof(Vec3));
  const auto& P = s->particles;
  // Histories set by hand on every entry that touches, and on some that do not (marked
  // live: the law must end them): random directions, so that most lie out of the tangent
  // plane by large angles (the exact rescaling) and some by tiny ones (the series), with
  // lengths from 1e-9 N to 1 N (sticking to sliding); one in eight zero.
  Rng rng(17);
  size_t touching = 0, parted = 0, small_turn = 0, frozen_partner = 0;
  for (size_t i = 0; i < P.size(); ++i) {
    for (uint32_t k = nl.start[i]; k < nl.start[i + 1]; ++k) {
      const uint32_t j = nl.jdx[k];
      const Vec3 d = P.x[i] - (P.x[j] + nl.shift[nl.image[k]]);
      const double dist = std::sqrt(norm2(d));
      const bool touch = dist < P.radius[i] + P.radius[j];
      if (!touch && rng.uniform(0, 1) > 0.05) continue;
      const Vec3 n = d * (1.0 / dist);
      Vec3 h{rng.normal(), rng.normal(), rng.normal()};
      if (rng.uniform(0, 1) < 0.3) {  // nearly in the plane: a turn of ~1e-3 rad
        h -= n * dot(n, h);
        h += n * (1e-3 * std::sqrt(norm2(h)));
        ++small_turn;
      }
      h *= std::pow(10.0, rng.uniform(-9, 0)) / std::sqrt(norm2(h));
      if (rng.uniform(0, 1) < 0.125) h = Vec3{};
      fs[k] = h;
      nl.hist.live[k] = 1;
      touching += touch;
      parted += !touch;
      frozen_partner += touch && (P.flag[i] == kFrozen || P.flag[j] == kFrozen);
    }
  }
  const std::vector<std::byte> hist0 = nl.hist.data;
  const std::vector<uint8_t> live0 = nl.hist.live;
  const std::vector<std::byte> whist0 = nl.whist.data;  // the floor's contacts (scalar in both)
  const std::vector<uint8_t> wlive0 = nl.whist.live;
  const std::vector<Vec3> f0 = P.force, t0 = P.torque;
  const Result a = force_call(*s, false);
  nl.hist.data = hist0;
  nl.hist.live = live0;
  nl.whist.data = whist0;
  nl.whist.live = wlive0;
  s->particles.force = f0;
  s->particles.torque = t0;
  const Result b = force_call(*s, true);
  set_screen_avx2(was);
  // Coverage: the bed must reach what it is meant to.
  size_t slid = 0;
  for (size_t k = 0; k < nl.jdx.size(); ++k) {
    const Vec3 h0 = reinterpret_cast<const Vec3*>(hist0.data())[k];
    const Vec3 h1 = reinterpret_cast<const Vec3*>(a.hist.data())[k];
    slid += a.live[k] && norm2(h1) < 0.25 * norm2(h0);  // cut to the Coulomb limit
  }
  std::printf("[info] lanes: %zu touching, %zu parted, %zu small turns, %zu frozen partners, %zu cut to the limit\n",
              touching, parted, small_turn, frozen_partner, slid);
  EXPECT_GT(touching, 500u);
  EXPECT_GT(parted, 20u);
  EXPECT_GT(small_turn, 100u);
  EXPECT_GT(frozen_partner, 20u);
  EXPECT_GT(slid, 100u);
  // Bit for bit (memcmp: the sign of a zero counts).
  EXPECT_EQ(differing(a.f, b.f), 0u);
  EXPECT_EQ(differing(a.t, b.t), 0u);
  EXPECT_TRUE(a.live == b.live);
  EXPECT_TRUE(a.hist == b.hist);
  report("lanes vs scalar linear law: particles with any differing force or torque bit", double(differing(a.f, b.f) + differing(a.t, b.t)),
         0.0, 0, "==");
}

TEST(Lanes, LinearLawRunsAsTheScalarLawOnOneAndTwoThreads) {
  if (!avx2_here()) GTEST_SKIP() << "no AVX2 on this CPU or build: the scalar law runs alone";
  const bool was = screen_avx2_enabled();
  Result r[2][2];
  for (int lanes = 0; lanes < 2; ++lanes)
    for (int nt = 1; nt <= 2; ++nt) {
      set_screen_avx2(lanes == 1);
      auto s = make_bed(nt);
      s->run(1500);
      r[lanes][nt - 1] = state_of(*s);
    }
  set_screen_avx2(was);
  omp_set_num_threads(1);
  for (int t = 0; t < 2; ++t) {
    EXPECT_EQ(differing(r[0][t].x, r[1][t].x), 0u) << t + 1 << " threads";
    EXPECT_EQ(differing(r[0][t].v, r[1][t].v), 0u) << t + 1 << " threads";
    EXPECT_EQ(differing(r[0][t].w, r[1][t].w), 0u) << t + 1 << " threads";
  }
  EXPECT_EQ(differing(r[1][0].x, r[1][1].x), 0u) << "lanes: 1 vs 2 threads";
}
