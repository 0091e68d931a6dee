// The force loop's finish of free particles four at a time in AVX2 registers
// (src/sim/finish.hpp) must give the scalar finish's results bit for bit: from the force and
// torque (the particle's pair sums plus gravity; a fused call does not store them), the two
// half-kicks of velocity and spin, the drift of the position, the pair sums zeroed, and the
// drift since the list build (the
// largest squared displacement and the box of the displacements). The reference is the
// scalar finish written out with the same shared pieces the kernel uses (Vec3 arithmetic,
// open_free, Drift::add). It must also stop at the first group of four it may not take (a
// particle that is not free, or one with wall entries) and leave that group untouched.
#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <vector>

#include "sim/finish.hpp"
#include "sim/screen.hpp"

using namespace cohdem;

namespace {

struct Particles {
  std::vector<Vec3> x, v, omega, ref;
  std::vector<PairResult> rev;
  std::vector<double> mass, inertia;
  std::vector<uint8_t> flag;
  std::vector<uint32_t> wstart;
};

Particles make(const size_t n) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0), pos(0.5, 2.0);
  auto vec = [&] { return Vec3{u(rng), u(rng), u(rng)}; };
  Particles p;
  for (size_t i = 0; i < n; ++i) {
    p.x.push_back(vec() * 3.0);
    p.ref.push_back(p.x.back() + vec() * 1e-3);
    p.v.push_back(vec());
    p.omega.push_back(vec() * 10.0);
    p.rev.push_back({vec() * 5.0, vec() * 0.1});
    p.mass.push_back(pos(rng) * 1e-3);
    p.inertia.push_back(pos(rng) * 1e-8);
    p.flag.push_back(kFree);
  }
  p.wstart.assign(n + 1, 0);
  return p;
}

FinishFree view(Particles& p, const Vec3& grav, const double kick_h, const double open_dt) {
  return {p.x.data(), p.v.data(), p.omega.data(), p.rev.data(), p.mass.data(),
          p.inertia.data(), p.flag.data(), p.wstart.data(), p.ref.data(), grav, kick_h, open_dt};
}

// The scalar finish of a local free particle with no wall entries and the fused opening
// (src/sim/force_kernel.hpp, `finish`).
void finish_scalar(Particles& p, const size_t i, const Vec3& grav, const double kick_h, const double open_dt,
                   Drift& d) {
  Vec3 F = p.rev[i].f, T = p.rev[i].tj;
  p.rev[i] = PairResult{};
  F += grav * p.mass[i];
  const double hm = kick_h / p.mass[i], hI = kick_h / p.inertia[i];
  Vec3 vi = p.v[i] + F * hm, wi = p.omega[i] + T * hI;
  open_free(vi, wi, p.x[i], F, T, hm, hI, open_dt);
  d.add(p.x[i] - p.ref[i]);
  p.v[i] = vi;
  p.omega[i] = wi;
}

template <class T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

}  // namespace

TEST(FinishFour, SameBitsAsTheScalarFinishAndStopsWhereItMayNot) {
  if (!avx2_available()) GTEST_SKIP() << "no AVX2 on this CPU: the scalar finish runs alone";
  constexpr size_t n = 23;
  const Vec3 grav{0.4383711467890774, 0.1, -0.898794046299167};
  const double kick_h = 0.5e-4, open_dt = 1e-4;
  Particles a = make(n);
  a.flag[9] = kFrozen;                              // group [8, 12) may not be taken
  for (size_t i = 15; i <= n; ++i) a.wstart[i] = 2;  // particle 14 has wall entries: [12, 16) neither
  Particles b = a;
  const Particles before = a;

  Drift da, db;
  const FinishFree fa = view(a, grav, kick_h, open_dt);
  EXPECT_EQ(finish_free_avx2(fa, 0, long(n), da), 8);    // stops at the frozen particle's group
  EXPECT_EQ(finish_free_avx2(fa, 12, long(n), da), 12);  // at once: 14 has wall entries
  EXPECT_EQ(finish_free_avx2(fa, 16, long(n), da), 20);  // three left: not a group
  EXPECT_EQ(finish_free_avx2(fa, 20, long(n), da), 20);
  for (size_t i = 0; i < 8; ++i) finish_scalar(b, i, grav, kick_h, open_dt, db);
  for (size_t i = 16; i < 20; ++i) finish_scalar(b, i, grav, kick_h, open_dt, db);

  EXPECT_TRUE(same_bits(a.x, b.x));
  EXPECT_TRUE(same_bits(a.v, b.v));
  EXPECT_TRUE(same_bits(a.omega, b.omega));
  EXPECT_TRUE(same_bits(a.rev, b.rev));
  // The particles it did not take are as they were (the scalar finish takes them).
  for (size_t i : {8, 9, 10, 11, 12, 13, 14, 15, 20, 21, 22}) {
    EXPECT_TRUE(std::memcmp(&a.x[i], &before.x[i], sizeof(Vec3)) == 0) << i;
    EXPECT_TRUE(std::memcmp(&a.v[i], &before.v[i], sizeof(Vec3)) == 0) << i;
    EXPECT_TRUE(std::memcmp(&a.rev[i], &before.rev[i], sizeof(PairResult)) == 0) << i;
  }
  // The drift: the same largest squared displacement to the bit, the same box (min and max
  // are exact in any order).
  EXPECT_EQ(da.dmax2, db.dmax2);
  EXPECT_GT(da.dmax2, 0.0);
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(da.lo[k], db.lo[k]) << k;
    EXPECT_EQ(da.hi[k], db.hi[k]) << k;
    EXPECT_LT(da.lo[k], da.hi[k]) << k;
  }
  EXPECT_FALSE(da.frozen);
}

// Each lane's part in the drift: particle t of a group of four displaced far more than the
// others along one component, either way, so that its lane alone decides the box's bound on
// that side and the largest squared displacement. Its displacement is one whose squared
// length depends on the order of the sum ((dx dx + dy dy) + dz dz differs from
// dx dx + (dy dy + dz dz)), so the sum's order is checked too.
TEST(FinishFour, EveryLaneDecidesTheDriftWhereItIsTheLargest) {
  if (!avx2_available()) GTEST_SKIP() << "no AVX2 on this CPU: the scalar finish runs alone";
  const Vec3 grav{0.0, 0.0, -9.81};
  const double kick_h = 0.5e-4, open_dt = 1e-4;
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(0.1, 0.5);
  auto order_matters = [](const Vec3& d) {
    return (d.x * d.x + d.y * d.y) + d.z * d.z != d.x * d.x + (d.y * d.y + d.z * d.z);
  };
  for (size_t t = 0; t < 4; ++t)
    for (int c = 0; c < 3; ++c)
      for (const double s : {-1.0, 1.0}) {
        Particles a = make(4);
        Particles probe = a;
        Drift unused;
        for (size_t i = 0; i < 4; ++i) finish_scalar(probe, i, grav, kick_h, open_dt, unused);
        // After the finish, particle t lies 0.1-0.5 from its reference along each component
        // and 1.1-1.5 along c, signed by s (the others 1e-3 or less), at a displacement (as
        // the finish computes it) whose squared length depends on the order of the sum.
        do {
          Vec3 disp{u(rng), u(rng), u(rng)};
          disp[c] = s * (1.0 + disp[c]);
          a.ref[t] = probe.x[t] - disp;
        } while (!order_matters(probe.x[t] - a.ref[t]));
        Particles b = a;
        Drift da, db;
        EXPECT_EQ(finish_free_avx2(view(a, grav, kick_h, open_dt), 0, 4, da), 4);
        for (size_t i = 0; i < 4; ++i) finish_scalar(b, i, grav, kick_h, open_dt, db);
        EXPECT_EQ(da.dmax2, db.dmax2) << "particle " << t << " component " << c << " sign " << s;
        for (int k = 0; k < 3; ++k) {
          EXPECT_EQ(da.lo[k], db.lo[k]) << "particle " << t << " component " << c << " sign " << s;
          EXPECT_EQ(da.hi[k], db.hi[k]) << "particle " << t << " component " << c << " sign " << s;
        }
        EXPECT_EQ(s < 0 ? da.lo[c] : da.hi[c], b.x[t][c] - b.ref[t][c]);
      }
}
