// Neighbor list against brute force: every pair within r_i + r_j + skin must be listed
// exactly once (with the right periodic image), for a polydisperse packing with size ratio 3,
// with and without periodic directions, and after re-sorting.
#include <gtest/gtest.h>

#include <map>
#include <set>

#include "core/rng.hpp"
#include "neighbor/neighbor_list.hpp"

using namespace cohdem;

namespace {

ParticleStore random_particles(size_t n, double L, double rmin, double rmax, uint64_t seed) {
  ParticleStore p;
  Rng rng(seed);
  for (size_t i = 0; i < n; ++i)
    p.add(1000 + 7 * i, 0, rng.uniform(rmin, rmax), 1000, {rng.uniform(0, L), rng.uniform(0, L), rng.uniform(0, L)});
  return p;
}

// Brute force with minimum image over periodic directions: key (id_lo, id_hi) -> distance.
std::map<std::pair<uint64_t, uint64_t>, double> brute(const ParticleStore& p, const Domain& d, double skin) {
  std::map<std::pair<uint64_t, uint64_t>, double> m;
  const Vec3 L = d.length();
  for (size_t a = 0; a < p.size(); ++a)
    for (size_t b = a + 1; b < p.size(); ++b) {
      Vec3 dx = p.x[a] - p.x[b];
      for (int k = 0; k < 3; ++k)
        if (d.periodic[k]) dx[k] -= L[k] * std::round(dx[k] / L[k]);
      const double dist = norm(dx);
      if (dist < p.radius[a] + p.radius[b] + skin)
        m[{std::min(p.id[a], p.id[b]), std::max(p.id[a], p.id[b])}] = dist;
    }
  return m;
}

void check(bool periodic, bool resort) {
  const double L = 0.02, skin = 2e-4;
  ParticleStore p = random_particles(1500, L, 2.5e-4, 7.5e-4, periodic ? 3 : 4);  // size ratio 3
  Domain d;
  d.lo = {0, 0, 0};
  d.hi = {L, L, L};
  d.periodic = {periodic, periodic, false};
  NeighborList nl;
  nl.hist.stride = nl.whist.stride = 8;
  nl.build(p, {}, d, skin, 0.0, resort);
  const auto ref = brute(p, d, skin);
  std::set<std::pair<uint64_t, uint64_t>> seen;
  for (size_t i = 0; i < p.size(); ++i)
    for (uint32_t k = nl.start[i]; k < nl.start[i + 1]; ++k) {
      const uint32_t j = nl.jdx[k];
      EXPECT_LT(p.id[i], p.id[j]) << "pair not oriented lower id first";
      const auto key = std::make_pair(p.id[i], p.id[j]);
      EXPECT_TRUE(seen.insert(key).second) << "pair listed twice";
      auto it = ref.find(key);
      ASSERT_NE(it, ref.end()) << "listed pair beyond the cutoff";
      // The stored image gives the minimum-image distance.
      EXPECT_NEAR(norm(p.x[i] - p.x[j] - nl.shift[nl.image[k]]), it->second, 1e-15);
    }
  EXPECT_EQ(seen.size(), ref.size()) << "pairs within the cutoff missing from the list";
  // Transposed index covers every pair once.
  EXPECT_EQ(nl.rpair.size(), nl.jdx.size());
}

}  // namespace

TEST(NeighborList, MatchesBruteForceSizeRatio3) { check(false, false); }
TEST(NeighborList, MatchesBruteForcePeriodic) { check(true, false); }
TEST(NeighborList, MatchesBruteForceAfterResort) { check(true, true); }
