// The force loop's screenings (src/sim/screen.hpp): the AVX2 one, four entries at a time,
// and the AVX-512 one, eight at a time, must each pick the same entries in the same order,
// with the same pair vectors and squared distances bit for bit, as the scalar one, entry by
// entry. Checked on random lists: rows of 0 to 19 entries (the wide paths mark a row's
// entries with their row four or eight at a time), partners in place and through periodic
// images, contacts, near misses, live entries apart, coordinates of -0, and batches that cut
// rows, stop below a block's end and reach the list's end (whose last entries the wide paths
// screen singly). The AVX-512 test skips where the CPU lacks AVX-512.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <vector>

#include "core/rng.hpp"
#include "sim/screen.hpp"

using namespace cohdem;

namespace {

struct RandomList {
  std::vector<Vec3> x, shift;
  std::vector<double> radius;
  std::vector<uint32_t> start, jdx;
  std::vector<uint8_t> image, live;

  explicit RandomList(uint64_t seed, long n = 400) {
    Rng rng(seed);
    // Particles on a 8 x 8 x 8 box of unit spheres (radii 0.4-0.6), some coordinates -0.
    for (long i = 0; i < n; ++i) {
      Vec3 p{rng.uniform(0, 8), rng.uniform(0, 8), rng.uniform(0, 8)};
      if (rng.uniform(0, 1) < 0.05) p.x = -0.0;
      if (rng.uniform(0, 1) < 0.05) p.z = -0.0;
      x.push_back(p);
      radius.push_back(rng.uniform(0.4, 0.6));
    }
    // 27 images of a periodic box of 8, kNoShift in place (+0, +0, +0).
    for (int a = -1; a <= 1; ++a)
      for (int b = -1; b <= 1; ++b)
        for (int c = -1; c <= 1; ++c) shift.push_back({8.0 * c, 8.0 * b, 8.0 * a});
    EXPECT_EQ(shift[kNoShift].x, 0.0);
    start.push_back(0);
    for (long i = 0; i < n; ++i) {
      const int len = int(rng.uniform(0, 20));  // 0..19 entries
      for (int e = 0; e < len; ++e) {
        // Partners near i (a contact or a near miss) or anywhere; a few through an image.
        uint32_t j = uint32_t(rng.uniform(0, double(n)));
        if (j >= uint32_t(n)) j = uint32_t(n - 1);
        const bool near = rng.uniform(0, 1) < 0.5;
        if (near) {
          // Move j next to i at a distance around its contact distance.
          const double d = (radius[size_t(i)] + radius[j]) * rng.uniform(0.9, 1.1);
          x[j] = {x[size_t(i)].x + d, x[size_t(i)].y, x[size_t(i)].z};
          if (rng.uniform(0, 1) < 0.2) x[j] = {x[size_t(i)].x, x[size_t(i)].y, x[size_t(i)].z - d};
          // Both at x = -0 now and then: d_x = -0 - (-0) = +0 in place, -0 had +0 been added
          // to x_j as a shift (a path that adds shifts to a whole group must skip the lanes
          // without one).
          if (rng.uniform(0, 1) < 0.1) x[size_t(i)].x = x[j].x = -0.0;
        }
        jdx.push_back(j);
        image.push_back(rng.uniform(0, 1) < 0.15 ? uint8_t(rng.uniform(0, 26.99)) : kNoShift);
        live.push_back(rng.uniform(0, 1) < 0.1 ? 1 : 0);
      }
      start.push_back(uint32_t(jdx.size()));
    }
  }
  ScreenInput input() {
    return {start.data(), jdx.data(), image.data(), live.data(), shift.data(), x.data(), radius.data(),
            uint32_t(jdx.size())};
  }
};

using ScreenFn = uint32_t (*)(const ScreenInput&, long, long, long, uint32_t, uint32_t, ScreenHits&);

/// Runs the scalar screening and `wide` (the AVX2 one unless given) on one batch; returns the
/// number of entries picked (both agree).
uint32_t compare_batch(RandomList& L, long i0, long i1, long b, uint32_t kb, uint32_t ke, ScreenFn wide = screen_avx2) {
  ScreenHits a, v;
  std::memset(&a, 0xAB, sizeof a);
  std::memset(&v, 0xCD, sizeof v);
  const ScreenInput in = L.input();
  const uint32_t na = screen_scalar(in, i0, i1, b, kb, ke, a);
  const uint32_t nv = wide(in, i0, i1, b, kb, ke, v);
  EXPECT_EQ(na, nv) << "rows " << i0 << ".." << i1 << " entries " << kb << ".." << ke;
  for (uint32_t h = 0; h < std::min(na, nv); ++h) {
    EXPECT_EQ(a.k[h], v.k[h]) << "hit " << h;
    EXPECT_EQ(a.row[h], v.row[h]) << "hit " << h;
    // Bitwise (memcmp): the sign of a zero counts.
    EXPECT_EQ(0, std::memcmp(&a.dx[h], &v.dx[h], 8)) << "dx of hit " << h;
    EXPECT_EQ(0, std::memcmp(&a.dy[h], &v.dy[h], 8)) << "dy of hit " << h;
    EXPECT_EQ(0, std::memcmp(&a.dz[h], &v.dz[h], 8)) << "dz of hit " << h;
    EXPECT_EQ(0, std::memcmp(&a.d2[h], &v.d2[h], 8)) << "d2 of hit " << h;
  }
  return na;
}

/// The random lists' batches through the scalar screening and `wide`, compared hit by hit.
void compare_random_lists(const ScreenFn wide) {
  uint64_t picked = 0, batches = 0, shifted_hits = 0;
  for (uint64_t seed = 1; seed <= 20; ++seed) {
    RandomList L(seed);
    const long n = long(L.x.size());
    const uint32_t total = uint32_t(L.jdx.size());
    // The force loop's batching: kBatch-sized windows (and smaller ones, to cut more rows),
    // over the whole list and over a block [a, b) that stops short of the end.
    for (const uint32_t size : {kBatch, 37u, 5u}) {
      for (const long b : {n, n / 2}) {
        long i = 0;
        for (uint32_t k = 0; i < b;) {
          const uint32_t ke = std::min(k + size, L.start[size_t(b)]);
          long i1 = i;
          while (i1 < b && L.start[size_t(i1 + 1)] <= ke) ++i1;
          picked += compare_batch(L, i, i1, b, k, ke, wide);
          ++batches;
          i = i1;
          k = ke;
        }
      }
    }
    for (uint32_t k = 0; k < total; ++k) shifted_hits += L.image[k] != kNoShift;
  }
  // The random lists must exercise what they claim: picks, batches, images.
  EXPECT_GT(picked, 10000u);
  EXPECT_GT(batches, 1000u);
  EXPECT_GT(shifted_hits, 1000u);
}

/// Lists of 1 to 19 entries in one row, all live: the wide paths read whole groups (of four
/// or eight) only inside the list, and screen its last entries singly.
void compare_list_ends(const ScreenFn wide) {
  for (uint32_t len = 1; len <= 19; ++len) {
    RandomList L(100 + len, 4);
    L.start = {0, len, len, len, len};
    L.jdx.assign(len, 1);
    L.image.assign(len, kNoShift);
    L.live.assign(len, 1);
    EXPECT_EQ(compare_batch(L, 0, 3, 4, 0, len, wide), len);
  }
}

}  // namespace

TEST(Screening, Avx2PicksWhatTheScalarScreeningPicks) {
  if (!avx2_available()) GTEST_SKIP() << "this CPU or build has no AVX2 screening (not x86-64 with AVX2)";
  compare_random_lists(screen_avx2);
}

TEST(Screening, Avx512PicksWhatTheScalarScreeningPicks) {
  // Eight entries at a time: groups that span more rows (rows of 0 to 19 entries), a batch's
  // end inside a group (the lanes past it masked off), periodic images and live entries.
  if (!avx512_available()) GTEST_SKIP() << "this CPU, operating system or build has no AVX-512 screening";
  compare_random_lists(screen_avx512);
}

TEST(Screening, ListEndScreenedSingly) {
  if (!avx2_available()) GTEST_SKIP() << "no AVX2 screening here";
  compare_list_ends(screen_avx2);
  if (avx512_available()) compare_list_ends(screen_avx512);
}

TEST(Screening, MaxIndexIsTheLargestEntryOrTheFloor) {
  // The two-step sweep's wait (force_kernel.hpp, run_b): the highest partner of a batch, at
  // least its last row. Both versions against std::max_element on random indices over the
  // whole uint32 range (the AVX2 one compares unsigned: values above 2^31 must not read as
  // negative), for every length 0-40 (its eight-wide part, then the rest singly) and for a
  // floor below, inside and above the entries' range.
  Rng rng(77);
  std::vector<uint32_t> p(48);
  size_t checked = 0;
  for (int rep = 0; rep < 50; ++rep) {
    const bool wide = rep % 2 == 0;
    for (uint32_t& e : p) e = wide ? uint32_t(rng.next()) : uint32_t(rng.next() % 1000);
    for (uint32_t n = 0; n <= 40; ++n) {
      const uint32_t top = n == 0 ? 0 : *std::max_element(p.begin(), p.begin() + n);
      for (const uint32_t floor : {0u, 500u, 0xFFFFFFF0u}) {
        const uint32_t want = std::max(top, floor);
        EXPECT_EQ(max_index_scalar(p.data(), n, floor), want) << "n " << n << " floor " << floor;
        if (avx2_available()) EXPECT_EQ(max_index_avx2(p.data(), n, floor), want) << "n " << n << " floor " << floor;
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 50u * 41u * 3u);
}
