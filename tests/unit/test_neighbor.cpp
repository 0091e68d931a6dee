// Neighbor list against brute force: every pair within r_i + r_j + skin must be listed
// exactly once (with the right periodic image), for a polydisperse packing with size ratio 3,
// with and without periodic directions, and after re-sorting.
#include <gtest/gtest.h>
#include <omp.h>

#include <array>
#include <cmath>
#include <map>
#include <set>
#include <tuple>

#include "core/rng.hpp"
#include "neighbor/neighbor_list.hpp"
#include "sim/screen.hpp"

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

// A cube of side L from the origin, periodic where asked.
Domain cube(const double L, const std::array<bool, 3> periodic) {
  Domain d;
  d.lo = {0, 0, 0};
  d.hi = {L, L, L};
  d.periodic = periodic;
  return d;
}

void check(bool periodic, bool resort) {
  const double L = 0.02, skin = 2e-4;
  ParticleStore p = random_particles(1500, L, 2.5e-4, 7.5e-4, periodic ? 3 : 4);  // size ratio 3
  const Domain d = cube(L, {periodic, periodic, false});
  NeighborList nl;
  nl.hist.stride = nl.whist.stride = 8;
  nl.build(p, {}, d, skin, 0.0, resort);
  const auto ref = brute(p, d, skin);
  std::set<std::pair<uint64_t, uint64_t>> seen;
  for (size_t i = 0; i < p.size(); ++i)
    for (uint32_t k = nl.start[i]; k < nl.start[i + 1]; ++k) {
      const uint32_t j = nl.jdx[k];
      EXPECT_LT(i, size_t(j)) << "pair not in the row of its lower index";
      const std::pair<uint64_t, uint64_t> key = std::minmax(p.id[i], p.id[j]);
      EXPECT_TRUE(seen.insert(key).second) << "pair listed twice";
      auto it = ref.find(key);
      ASSERT_NE(it, ref.end()) << "listed pair beyond the cutoff";
      // The stored image gives the minimum-image distance.
      EXPECT_NEAR(norm(p.x[i] - p.x[j] - nl.shift[nl.image[k]]), it->second, 1e-15);
    }
  EXPECT_EQ(seen.size(), ref.size()) << "pairs within the cutoff missing from the list";
  // The force loop skips adding the in-place image's shift (kNoShift): it must be +0 exactly.
  for (int c = 0; c < 3; ++c) {
    EXPECT_EQ(nl.shift[kNoShift][c], 0.0);
    EXPECT_FALSE(std::signbit(nl.shift[kNoShift][c]));
  }
  // Transposed index covers every pair once.
  EXPECT_EQ(nl.rpair.size(), nl.jdx.size());
}

// A box periodic in x and z, ncut cutoffs long there (one to four cells across), 12 mm in y,
// with n polydisperse spheres (radii 0.25-0.75 mm, ids from id0 down by step), one in ten
// frozen.
struct NarrowBox {
  ParticleStore p;
  Domain d;
  double skin = 2e-4;
};
NarrowBox narrow_box(const double ncut, const uint64_t seed, const size_t n_or_0, const uint64_t id0,
                     const uint64_t step) {
  NarrowBox b;
  const double rmax = 7.5e-4, cut = 2 * rmax + b.skin;
  const Vec3 L{ncut * cut, 0.012, ncut * cut};
  Rng rng(seed);
  // By default four times the density of the bed above.
  const size_t n = n_or_0 > 0 ? n_or_0 : size_t(6000 * L.x * L.y * L.z / (0.02 * 0.02 * 0.02)) + 40;
  for (size_t i = 0; i < n; ++i) {
    b.p.add(id0 - step * i, 0, rng.uniform(2.5e-4, rmax), 1000, {rng.uniform(0, L.x), rng.uniform(0, L.y), rng.uniform(0, L.z)});
    if (i % 10 == 3) b.p.flag[i] = kFrozen;
  }
  b.d.lo = {0, 0, 0};
  b.d.hi = L;
  b.d.periodic = {true, false, true};
  return b;
}

// Every image: in a periodic direction only 1.2 to 4.5 cutoffs long, one or two cells wide
// (a cell's neighbours at -1 and +1 are then one cell under two images, each searched once)
// or three and four (each pair of cells searched once, from the cell behind). A pair of particles
// may then lie within the cutoff under two images (1.2 cutoffs: at d and L - d), and is
// listed once per image. One particle in ten is frozen: pairs of two fixed bodies are not
// listed. Compared as multisets of (lower id, higher id, distance to 1e-12 m) against all
// pairs and images by brute force.
void check_images(const double ncut, const bool resort) {
  NarrowBox box = narrow_box(ncut, uint64_t(ncut * 10) + resort, 0, 5000, 3);
  ParticleStore& p = box.p;
  const Domain& d = box.d;
  const double skin = box.skin;
  const Vec3 L = d.hi;
  const size_t n = p.size();
  NeighborList nl;
  nl.hist.stride = nl.whist.stride = 8;
  nl.build(p, {}, d, skin, 0.0, resort);
  using Key = std::tuple<uint64_t, uint64_t, long long>;
  std::multiset<Key> want, got;
  for (size_t a = 0; a < p.size(); ++a)
    for (size_t b = a + 1; b < p.size(); ++b) {
      if (p.flag[a] != kFree && p.flag[b] != kFree) continue;
      for (int sx = -1; sx <= 1; ++sx)
        for (int sz = -1; sz <= 1; ++sz) {
          const double dist = norm(p.x[a] - p.x[b] - Vec3{sx * L.x, 0, sz * L.z});
          if (dist < p.radius[a] + p.radius[b] + skin)
            want.insert({std::min(p.id[a], p.id[b]), std::max(p.id[a], p.id[b]), std::llround(dist * 1e12)});
        }
    }
  for (size_t i = 0; i < p.size(); ++i)
    for (uint32_t k = nl.start[i]; k < nl.start[i + 1]; ++k) {
      const uint32_t j = nl.jdx[k];
      EXPECT_LT(i, size_t(j)) << "pair not in the row of its lower index";
      const double dist = norm(p.x[i] - p.x[j] - nl.shift[nl.image[k]]);
      got.insert({std::min(p.id[i], p.id[j]), std::max(p.id[i], p.id[j]), std::llround(dist * 1e12)});
    }
  EXPECT_EQ(got.size(), want.size()) << ncut << " cutoffs";
  EXPECT_TRUE(got == want) << ncut << " cutoffs: listed pairs and images differ from brute force";
  size_t two_images = 0;  // pairs listed under two images (the narrowest box has some)
  for (auto it = want.begin(); it != want.end(); ++it) {
    auto nx = std::next(it);
    two_images += nx != want.end() && std::get<0>(*nx) == std::get<0>(*it) && std::get<1>(*nx) == std::get<1>(*it);
  }
  if (ncut < 2) EXPECT_GT(two_images, 0u) << "the narrow box should hold pairs seen under two images";
  EXPECT_GT(want.size(), n / 2) << "too few pairs to test";
}

// 3000 polydisperse spheres in a 20 mm box periodic in x, re-sorted into cell order by a
// build, then each moved by up to 0.8 mm along each axis: a bed that has left the cell order
// of its last re-sort, as between re-sorts.
struct MovedBed {
  ParticleStore p;
  Domain d;
};
MovedBed moved_bed(const uint64_t seed, const uint64_t move_seed, const double skin) {
  const double L = 0.02;
  MovedBed b{random_particles(3000, L, 2.5e-4, 7.5e-4, seed), cube(L, {true, false, false})};
  NeighborList sorter;
  sorter.hist.stride = sorter.whist.stride = 8;
  sorter.build(b.p, {}, b.d, skin, 0.0, true);  // cell order = index order
  Rng rng(move_seed);
  for (Vec3& x : b.p.x) x = x + Vec3{rng.uniform(-8e-4, 8e-4), rng.uniform(-8e-4, 8e-4), rng.uniform(-8e-4, 8e-4)};
  return b;
}

}  // namespace

TEST(NeighborList, MatchesBruteForceSizeRatio3) { check(false, false); }
TEST(NeighborList, EveryImageInNarrowPeriodicBoxes) {
  for (const double ncut : {1.2, 2.5, 3.5, 4.5})
    for (const bool resort : {false, true}) check_images(ncut, resort);
}
TEST(NeighborList, MatchesBruteForcePeriodic) { check(true, false); }
TEST(NeighborList, MatchesBruteForceAfterResort) { check(true, true); }

// The pair search four candidates at a time (AVX2, src/neighbor/search_avx2.cpp) and the
// portable loop give the same lists bit for bit: the same rows, partners, images and
// transposed index, in the same order. Boxes as above (one particle in ten frozen, periodic
// in x and z, one to four cells across), and a polydisperse bed re-sorted, then moved by up
// to half a cell so that the cell order is no longer the index order (candidates ahead of a
// particle then include lower indices, whose pairs go to the other row, seen from there).
TEST(NeighborList, Avx2SearchGivesThePortableListsBitForBit) {
  if (!avx2_available()) GTEST_SKIP() << "this CPU has no AVX2";
  const bool was = screen_avx2_enabled();
  auto lists = [](ParticleStore p, const Domain& d, const double skin, const bool resort, const bool avx2) {
    set_screen_avx2(avx2);
    NeighborList nl;
    nl.hist.stride = nl.whist.stride = 8;
    nl.build(p, {}, d, skin, 0.0, resort);
    return std::make_tuple(nl.start, nl.jdx, nl.image, nl.rstart, nl.rpair, nl.dep_lo, p.id);
  };
  size_t cases = 0;
  for (const double ncut : {1.2, 2.5, 4.5}) {
    const NarrowBox box = narrow_box(ncut, uint64_t(ncut * 10) + 77, 1500, 9000, 5);
    const ParticleStore& p = box.p;
    for (const bool resort : {false, true}) {
      const auto a = lists(p, box.d, box.skin, resort, false), b = lists(p, box.d, box.skin, resort, true);
      EXPECT_TRUE(a == b) << ncut << " cutoffs, resort " << resort;
      EXPECT_GT(std::get<1>(a).size(), p.size() / 2);
      ++cases;
    }
  }
  {
    const double skin = 2e-4;
    const MovedBed bed = moved_bed(5, 6, skin);
    const ParticleStore& p = bed.p;
    const Domain& d = bed.d;
    const auto a = lists(p, d, skin, false, false), b = lists(p, d, skin, false, true);
    EXPECT_TRUE(a == b) << "moved bed";
    EXPECT_GT(std::get<1>(a).size(), p.size());
    ++cases;
  }
  set_screen_avx2(was);
  EXPECT_EQ(cases, 7u);
}

// The lists do not depend on the threads that build them: on several threads the cell order
// is cut into one part a thread where the particle order cuts it into equal shares, and each
// thread bins, copies and searches its part (NeighborList::build, steps 3 and 4). Built on
// one thread and on two, three and five (parallel_min = 0), compared whole: rows, partners,
// images, transposed rows, the lowest rows and, after a re-sort, the particle order. The
// cases: particles in random order (a bad estimate of the parts: cells of the parts
// uneven, some parts without particles at five threads), the narrow periodic boxes (every
// image), a box periodic in z (the folded re-sort), and a bed moved off its cell order;
// with a plane and a cylinder wall, whose entries (built by ranges of the particles on
// several threads) are compared too.
TEST(NeighborList, ListsAreTheSameOnAnyThreadCount) {
  // Walls too: a floor 1 mm into the box and a cylinder about the box's axis (radius 8 mm),
  // each within reach of some particles and not of others.
  Wall floor, drum;
  floor.point = {0, 0, 0.001};
  floor.normal = {0, 0, 1};
  drum.shape = WallShape::Cylinder;
  drum.point = {0.01, 0.01, 0};
  drum.normal = {0, 0, 1};
  drum.radius = 0.008;
  const std::vector<Wall> walls{floor, drum};
  auto lists = [&](ParticleStore p, const Domain& d, const double skin, const bool resort, const int threads) {
    omp_set_num_threads(threads);
    NeighborList nl;
    nl.parallel_min = 0;
    nl.hist.stride = nl.whist.stride = 8;
    nl.build(p, walls, d, skin, 0.0, resort);
    omp_set_num_threads(1);
    return std::make_tuple(nl.start, nl.jdx, nl.image, nl.rstart, nl.rpair, nl.dep_lo, p.id, nl.wstart, nl.wall);
  };
  size_t cases = 0;
  auto compare = [&](const ParticleStore& p, const Domain& d, const double skin, const bool resort, const char* what) {
    const auto one = lists(p, d, skin, resort, 1);
    EXPECT_GT(std::get<1>(one).size(), p.size() / 2) << what;
    EXPECT_GT(std::get<8>(one).size(), p.size() / 20) << what << ": too few wall entries to test";
    for (const int t : {2, 3, 5}) EXPECT_TRUE(lists(p, d, skin, resort, t) == one) << what << ", resort " << resort << ", " << t << " threads";
    ++cases;
  };
  const double L = 0.02, skin = 2e-4;
  for (const bool resort : {false, true}) {
    compare(random_particles(3000, L, 2.5e-4, 7.5e-4, 8), cube(L, {false, false, false}), skin, resort, "random order");
    compare(random_particles(3000, L, 2.5e-4, 7.5e-4, 9), cube(L, {true, true, true}), skin, resort, "periodic in z");
    const NarrowBox box = narrow_box(1.2, 81, 1500, 9000, 5);
    compare(box.p, box.d, box.skin, resort, "narrow box");
  }
  const MovedBed bed = moved_bed(10, 11, skin);
  compare(bed.p, bed.d, skin, false, "moved bed");
  EXPECT_EQ(cases, 7u);
}

// The rebuild criterion bounds the relative displacement of any two particles by the smaller
// of twice the largest displacement and the diagonal of the displacements' bounding box
// (NeighborList::needs_rebuild). Checked here: (1) a bed translated as a whole needs no
// rebuild however far it goes, unless it has frozen particles (they stay behind); (2) it is
// safe: in adversarial trials (a common drift, an unlisted pair driven together), whenever a
// pair touches that is not in the list built at the reference, a rebuild is asked for.
namespace {

struct Bed {
  ParticleStore p;
  Domain d;
  NeighborList nl;
  double skin = 2e-4;
  Bed(bool periodic, uint64_t seed) : p(random_particles(1200, 0.02, 2.5e-4, 7.5e-4, seed)) {
    d.lo = {0, 0, 0};
    d.hi = {0.02, 0.02, 0.02};
    d.periodic = {periodic, periodic, periodic};
    nl.hist.stride = nl.whist.stride = 8;
    nl.build(p, {}, d, skin, 0.0, false);
  }
};

}  // namespace

TEST(NeighborList, RebuildCriterionIgnoresCommonTranslation) {
  Bed b(true, 11);
  const std::vector<Vec3> x0 = b.p.x;
  // 25 skins along a diagonal: the old criterion (twice the largest displacement) would have
  // rebuilt 50 times over; nothing moved relative to anything.
  const Vec3 u{3e-3, -2e-3, 1.5e-3};
  for (size_t i = 0; i < b.p.size(); ++i) b.p.x[i] = x0[i] + u;
  EXPECT_FALSE(b.nl.needs_rebuild(b.p, {}, b.skin));
  // One particle 0.6 skin further along: relative displacement 0.6 skin, still safe...
  b.p.x[5] += Vec3{0.6 * b.skin, 0, 0};
  EXPECT_FALSE(b.nl.needs_rebuild(b.p, {}, b.skin));
  // ... and 1.1 skin: a pair may now be missed.
  b.p.x[5] += Vec3{0.5 * b.skin, 0, 0};
  EXPECT_TRUE(b.nl.needs_rebuild(b.p, {}, b.skin));
  // With a frozen particle the translation itself is relative motion: 0.6 skin is safe,
  // 1.1 skin is not.
  Bed f(true, 12);
  const std::vector<Vec3> y0 = f.p.x;
  f.p.flag[7] = kFrozen;
  for (size_t i = 0; i < f.p.size(); ++i)
    if (i != 7) f.p.x[i] = y0[i] + Vec3{0.6 * f.skin, 0, 0};
  EXPECT_FALSE(f.nl.needs_rebuild(f.p, {}, f.skin));
  for (size_t i = 0; i < f.p.size(); ++i)
    if (i != 7) f.p.x[i] = y0[i] + Vec3{1.1 * f.skin, 0, 0};
  EXPECT_TRUE(f.nl.needs_rebuild(f.p, {}, f.skin));
}

// NeighborList::rebuild_measure is the number the rebuild trigger compares with the skin
// (System::step_pair forecasts it): checked against its definition on hand-made
// displacements, and against rebuild_due on random ones, with and without a wall that has
// moved since the build.
TEST(NeighborList, RebuildMeasureIsWhatTheTriggerComparesWithTheSkin) {
  Bed b(true, 41);
  const double s = b.skin;
  // One particle moved by 0.3 skin along x, the others at rest: the largest displacement
  // is 0.3 skin, the displacements' box 0.3 skin long, so two particles moved by at most
  // min(2 x 0.3, 0.3) = 0.3 skin relative to each other.
  Drift d;
  for (size_t i = 0; i < b.p.size(); ++i) d.add(Vec3{i == 3 ? 0.3 * s : 0.0, 0, 0});
  EXPECT_DOUBLE_EQ(b.nl.rebuild_measure(d, {}), 0.3 * s);
  // Everyone moved by the same 0.7 skin: nothing moved relative to anything (box of size 0)...
  Drift t;
  for (size_t i = 0; i < b.p.size(); ++i) t.add(Vec3{0, 0.7 * s, 0});
  EXPECT_EQ(b.nl.rebuild_measure(t, {}), 0.0);
  // ...unless a particle is frozen: the box holds the origin, 0.7 skin long.
  t.frozen = true;
  EXPECT_DOUBLE_EQ(b.nl.rebuild_measure(t, {}), 0.7 * s);
  // Radius growth counts twice (both particles of a pair may have grown).
  Drift g = d;
  g.grow = 0.05 * s;
  EXPECT_DOUBLE_EQ(b.nl.rebuild_measure(g, {}), 0.3 * s + 0.1 * s);

  // With a wall (a floor, built with the lists), the absolute displacement counts against it:
  // the common translation of 0.7 skin is 0.7 skin towards or away from the wall, plus the
  // wall's own motion along its normal since the build.
  Wall floor;
  floor.shape = WallShape::Plane;
  floor.point = {0, 0, -0.01};
  floor.normal = {0, 0, 1};
  std::vector<Wall> walls{floor};
  NeighborList nw;
  nw.hist.stride = nw.whist.stride = 8;
  nw.build(b.p, walls, b.d, s, 0.0, false);
  Drift t2;
  for (size_t i = 0; i < b.p.size(); ++i) t2.add(Vec3{0, 0.7 * s, 0});
  EXPECT_DOUBLE_EQ(nw.rebuild_measure(t2, walls), 0.7 * s);
  walls[0].point += Vec3{0.1 * s, 0, 0.2 * s};  // moved 0.2 skin along its normal
  EXPECT_DOUBLE_EQ(nw.rebuild_measure(t2, walls), 0.7 * s + 0.2 * s);

  // Random displacements (some particles frozen, some grown), with and without the moved
  // wall: rebuild_due is exactly the measure above the skin, for skins on both sides.
  Rng rng(5);
  int due = 0, not_due = 0;
  for (int trial = 0; trial < 200; ++trial) {
    Drift r;
    const double amp = s * rng.uniform(0, 1.5);
    for (size_t i = 0; i < 50; ++i)
      r.add(Vec3{amp * rng.uniform(-1, 1), amp * rng.uniform(-1, 1), amp * rng.uniform(-1, 1)},
            trial % 4 == 0 ? 0.1 * s * rng.uniform() : 0.0);
    r.frozen = trial % 3 == 0;
    for (const bool with_wall : {false, true}) {
      const std::vector<Wall>& w = with_wall ? walls : std::vector<Wall>{};
      const NeighborList& nl = with_wall ? nw : b.nl;
      const double m = nl.rebuild_measure(r, w);
      for (const double skin : {0.5 * s, s, 2 * s, m, std::nextafter(m, 0.0)}) {
        const bool want = m > skin;
        EXPECT_EQ(nl.rebuild_due(r, w, skin), want) << "trial " << trial << ", skin " << skin;
        (want ? due : not_due) += 1;
      }
    }
  }
  EXPECT_GT(due, 100);
  EXPECT_GT(not_due, 100);
}

TEST(NeighborList, RebuildCriterionNeverMissesAContact) {
  // Adversarial trials: a common drift of up to 10 skins, small jitter for everyone, and one
  // unlisted pair (the closest: gap >= skin at the build) driven together by 0.8 to 1.3 times
  // its gap; in every other trial one of the two is frozen and the drift itself points at it.
  // Whenever a pair touches that is not in the list, the criterion must ask for a rebuild.
  Rng rng(21);
  int quiet = 0, missed_trials = 0;
  for (int trial = 0; trial < 60; ++trial) {
    Bed b(trial % 3 != 0, 100 + trial);
    const double skin = b.skin;
    std::set<std::pair<uint64_t, uint64_t>> listed;
    for (size_t i = 0; i < b.p.size(); ++i)
      for (uint32_t k = b.nl.start[i]; k < b.nl.start[i + 1]; ++k) listed.insert(std::minmax(b.p.id[i], b.p.id[b.nl.jdx[k]]));
    std::map<uint64_t, size_t> index_of;
    for (size_t i = 0; i < b.p.size(); ++i) index_of[b.p.id[i]] = i;
    // The closest unlisted pair.
    double gmin = 1e9;
    size_t ia = 0, ic = 0;
    for (const auto& [key, dist] : brute(b.p, b.d, 3 * skin)) {
      if (listed.count(key)) continue;
      const size_t a = index_of[key.first], c = index_of[key.second];
      const double g = dist - b.p.radius[a] - b.p.radius[c];
      if (g < gmin) { gmin = g; ia = a; ic = c; }
    }
    ASSERT_LT(gmin, 1e9);
    ASSERT_GE(gmin, skin * (1 - 1e-9));
    Vec3 dir = b.p.x[ic] - b.p.x[ia];  // from a to c, minimum image
    const Vec3 L = b.d.length();
    for (int k = 0; k < 3; ++k)
      if (b.d.periodic[k]) dir[k] -= L[k] * std::round(dir[k] / L[k]);
    dir = normalized(dir);
    const bool frozen = trial % 2 == 1;
    const double s = gmin * rng.uniform(0.8, 1.3);
    Vec3 u{rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)};
    u = u * (10 * skin * rng.uniform(0, 1));
    if (frozen) u = dir * (-10 * skin * rng.uniform(0, 1));  // c drifts towards the frozen a
    if (frozen) b.p.flag[ia] = kFrozen;
    const std::vector<Vec3> x0 = b.p.x;
    for (size_t i = 0; i < b.p.size(); ++i) {
      if (b.p.flag[i] == kFrozen) continue;
      const Vec3 jit{rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)};
      b.p.x[i] = x0[i] + u + jit * (0.1 * skin);
    }
    if (frozen) {
      b.p.x[ic] = x0[ic] + u - dir * s;
    } else {
      b.p.x[ia] = x0[ia] + u + dir * (0.5 * s);
      b.p.x[ic] = x0[ic] + u - dir * (0.5 * s);
    }
    bool missed = false;  // a touching pair that is not listed
    for (const auto& [key, dist] : brute(b.p, b.d, 0.0)) missed = missed || !listed.count(key);
    const bool rebuild = b.nl.needs_rebuild(b.p, {}, skin);
    missed_trials += missed;
    quiet += !rebuild;
    EXPECT_TRUE(rebuild || !missed) << "trial " << trial << ": a touching pair is not listed, and no rebuild was asked for";
  }
  // Both sides exercised (seeded: the counts are fixed for this seed).
  EXPECT_GT(quiet, 5) << "too few trials in which no rebuild was needed";
  EXPECT_GT(missed_trials, 10) << "too few trials that really needed a rebuild";
}

// The lists keep the radii they were built with only where radii can change between builds
// (a thermal model's expansion keeps the thermal fields: ParticleStore::thermal()); there the
// rebuild trigger counts radius growth, and so it does after a thermal run's reference (a
// checkpoint's) is rebuilt into a store without the fields, until the next build. The
// physical requirement: two particles that touch only because they grew, with no pair in the
// list, must make the trigger ask for a rebuild.
TEST(NeighborList, ReferenceRadiiOnlyWhereRadiiCanChange) {
  const double skin = 2e-4;
  Bed mech(true, 31);
  EXPECT_FALSE(mech.nl.tracks_radii());
  EXPECT_TRUE(mech.nl.reference().r.empty());

  ParticleStore q = random_particles(1200, 0.02, 2.5e-4, 7.5e-4, 31);
  q.enable_thermal(293.15);
  NeighborList nl;
  nl.hist.stride = nl.whist.stride = 8;
  nl.build(q, {}, mech.d, skin, 0.0, false);
  ASSERT_TRUE(nl.tracks_radii());
  EXPECT_EQ(nl.reference().r, q.radius);
  EXPECT_EQ(nl.start, mech.nl.start);  // the same lists either way
  EXPECT_EQ(nl.jdx, mech.nl.jdx);

  // The closest unlisted pair (gap >= skin at the build).
  std::set<std::pair<size_t, size_t>> listed;
  for (size_t i = 0; i < q.size(); ++i)
    for (uint32_t k = nl.start[i]; k < nl.start[i + 1]; ++k) listed.insert({i, size_t(nl.jdx[k])});
  std::map<uint64_t, size_t> index_of;
  for (size_t i = 0; i < q.size(); ++i) index_of[q.id[i]] = i;
  double gmin = 1e9;
  size_t a = 0, c = 0;
  for (const auto& [key, dist] : brute(q, mech.d, 3 * skin)) {
    const size_t ia = index_of[key.first], ic = index_of[key.second];
    if (listed.count(std::minmax(ia, ic))) continue;
    const double g = dist - q.radius[ia] - q.radius[ic];
    if (g < gmin) { gmin = g; a = ia; c = ic; }
  }
  ASSERT_LT(gmin, 1e9);
  ASSERT_GE(gmin, skin * (1 - 1e-9));
  const NeighborList::Reference built = nl.reference();
  // Growth of 0.2 skin each (the gap shrinks by 0.4 skin): safe, no rebuild.
  ParticleStore g = q;
  g.radius[a] += 0.2 * skin;
  g.radius[c] += 0.2 * skin;
  EXPECT_FALSE(nl.needs_rebuild(g, {}, skin));
  // Growth of 0.6 gap each: the pair overlaps by 0.2 gap and is not listed.
  g = q;
  g.radius[a] += 0.6 * gmin;
  g.radius[c] += 0.6 * gmin;
  ASSERT_EQ(brute(g, mech.d, 0.0).count(std::minmax(g.id[a], g.id[c])), 1u);
  EXPECT_TRUE(nl.needs_rebuild(g, {}, skin));

  // The same state in a store without the thermal fields (a mechanical case resuming the
  // thermal run's checkpoint): rebuilt from the thermal reference, the lists are the thermal
  // run's and still count the growth since; the next build drops the radii.
  ParticleStore m = g;
  m.disable_thermal();
  NeighborList r;
  r.hist.stride = r.whist.stride = 8;
  std::vector<Wall> none;
  r.rebuild_at(m, none, mech.d, skin, 0.0, built);
  EXPECT_EQ(r.start, nl.start);
  EXPECT_EQ(r.jdx, nl.jdx);
  EXPECT_EQ(m.radius, g.radius);  // the current radii are left as they are
  ASSERT_TRUE(r.tracks_radii());
  EXPECT_TRUE(r.needs_rebuild(m, {}, skin)) << "radius growth since the reference's build not counted";
  r.build(m, {}, mech.d, skin, 0.0, false);
  EXPECT_FALSE(r.tracks_radii());
  bool now_listed = false;
  for (uint32_t k = r.start[std::min(a, c)]; k < r.start[std::min(a, c) + 1]; ++k)
    now_listed = now_listed || r.jdx[k] == std::max(a, c);
  EXPECT_TRUE(now_listed);
  // A mechanical reference (no radii) rebuilds a mechanical store's lists exactly.
  NeighborList r2;
  r2.hist.stride = r2.whist.stride = 8;
  r2.rebuild_at(mech.p, none, mech.d, skin, 0.0, mech.nl.reference());
  EXPECT_FALSE(r2.tracks_radii());
  EXPECT_EQ(r2.start, mech.nl.start);
  EXPECT_EQ(r2.jdx, mech.nl.jdx);
}

// The local check (NeighborList::recheck): where the global trigger fires, blocks of two
// cutoffs of the build's positions are compared with their neighbours, and the lists are
// kept where no two particles of neighbouring blocks, and no two particles at all beyond a
// block's edge less the contact range, can have closed their gap. The physical requirement
// (brute force over all pairs): after any sequence of displacements, whenever the lists are
// kept (no trigger, or a check that keeps them), every touching pair is listed. Adversarial
// trials: stages of a simple shear in x across z (discontinuous across a periodic z: the
// blocks must wrap), jitter, a frozen base in some trials, and each stage the closest
// unlisted pair driven together by 0.8 to 1.3 times its gap; where z is not periodic, a
// rising floor and the closest particle not listed with it driven onto it. (The shear is 0
// at z = 0, across the periodic boundary it jumps.)
TEST(NeighborList, LocalCheckNeverMissesAContact) {
  Rng rng(77);
  int kept = 0, caught = 0, builds = 0;
  for (int trial = 0; trial < 20; ++trial) {
    Bed b(true, 300 + trial);
    b.d.periodic[2] = trial % 3 == 0;
    const bool frozen_base = trial % 4 == 1;
    if (frozen_base)
      for (size_t i = 0; i < b.p.size(); ++i)
        if (b.p.x[i].z < 0.002) b.p.flag[i] = kFrozen;
    const double skin = b.skin;
    // Where z is not periodic, a floor 0.1 mm below the bed's cube, rising by up to 0.2 skin
    // every other stage, and then the free particle closest to it among those not listed
    // with it driven down by 0.8 to 1.3 times its gap.
    std::vector<Wall> walls;
    if (!b.d.periodic[2]) {
      Wall f;
      f.shape = WallShape::Plane;
      f.point = {0, 0, -1e-4};
      f.normal = {0, 0, 1};
      walls.push_back(f);
    }
    b.nl.build(b.p, walls, b.d, skin, 0.0, false);
    std::set<std::pair<uint64_t, uint64_t>> listed;
    auto relist = [&] {
      listed.clear();
      for (size_t i = 0; i < b.p.size(); ++i)
        for (uint32_t k = b.nl.start[i]; k < b.nl.start[i + 1]; ++k)
          listed.insert(std::minmax(b.p.id[i], b.p.id[b.nl.jdx[k]]));
    };
    relist();
    std::map<uint64_t, size_t> index_of;
    for (size_t i = 0; i < b.p.size(); ++i) index_of[b.p.id[i]] = i;
    const Vec3 L = b.d.length();
    for (int stage = 0; stage < 6; ++stage) {
      // The shear: top and bottom part by 0.5 to 2 skins this stage.
      const double g = rng.uniform(0.5, 2.0) * skin / L.z;
      const double jitter = rng.uniform(0, 0.06) * skin;
      for (size_t i = 0; i < b.p.size(); ++i) {
        if (b.p.flag[i] == kFrozen) continue;
        const Vec3 jit{rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)};
        b.p.x[i] += Vec3{g * b.p.x[i].z, 0, 0} + jit * jitter;
      }
      // The closest unlisted pair, driven together.
      double gmin = 1e9;
      size_t ia = 0, ic = 0;
      Vec3 dir;
      for (const auto& [key, dist] : brute(b.p, b.d, 3 * skin)) {
        if (listed.count(key)) continue;
        const size_t a = index_of[key.first], c = index_of[key.second];
        const double gap = dist - b.p.radius[a] - b.p.radius[c];
        if (gap < gmin) { gmin = gap; ia = a; ic = c; }
      }
      if (gmin < 1e9 && gmin > 0) {
        dir = b.p.x[ic] - b.p.x[ia];
        for (int k = 0; k < 3; ++k)
          if (b.d.periodic[k]) dir[k] -= L[k] * std::round(dir[k] / L[k]);
        dir = normalized(dir);
        const double s = gmin * rng.uniform(0.8, 1.3);
        if (b.p.flag[ia] != kFrozen) b.p.x[ia] += dir * (0.5 * s);
        if (b.p.flag[ic] != kFrozen) b.p.x[ic] -= dir * (0.5 * s);
      }
      if (!walls.empty() && stage % 2 == 1) {
        walls[0].point.z += rng.uniform(0, 0.2) * skin;
        double wmin = 1e9;
        size_t iw = 0;
        for (size_t i = 0; i < b.p.size(); ++i) {
          if (b.p.flag[i] != kFree || b.nl.wstart[i + 1] > b.nl.wstart[i]) continue;
          const double gap = b.p.x[i].z - walls[0].point.z - b.p.radius[i];
          if (gap > 0 && gap < wmin) { wmin = gap; iw = i; }
        }
        if (wmin < 1e9) b.p.x[iw].z -= wmin * rng.uniform(0.8, 1.3);
      }
      bool missed = false;  // a touching pair that is not listed (two frozen particles never are)
      for (size_t i = 0; i < b.p.size() && !walls.empty(); ++i)  // or a free particle touching the floor
        missed = missed || (b.p.flag[i] == kFree && b.nl.wstart[i + 1] == b.nl.wstart[i] &&
                            b.p.x[i].z - walls[0].point.z < b.p.radius[i]);
      for (const auto& [key, dist] : brute(b.p, b.d, 0.0))
        missed = missed || (!listed.count(key) &&
                            (b.p.flag[index_of[key.first]] != kFrozen || b.p.flag[index_of[key.second]] != kFrozen));
      const bool due = b.nl.needs_rebuild(b.p, walls, skin);
      const bool keep = !due || b.nl.recheck(b.p, walls, skin);
      EXPECT_TRUE(keep ? !missed : true) << "trial " << trial << ", stage " << stage
                                         << ": a touching pair is not listed, and the lists were kept";
      kept += due && keep;
      caught += missed && !keep;
      if (!keep) {
        b.nl.build(b.p, walls, b.d, skin, 0.0, false);
        ++builds;
        relist();
        index_of.clear();
        for (size_t i = 0; i < b.p.size(); ++i) index_of[b.p.id[i]] = i;
      }
    }
  }
  std::printf("[info] local check trials: %d stages kept by a check, %d misses caught, %d builds\n", kept, caught, builds);
  // Both sides exercised (seeded: the counts are fixed for this seed).
  EXPECT_GE(kept, 6) << "too few stages kept by the local check";
  EXPECT_GT(caught, 10) << "too few stages that really needed a build";
  EXPECT_GT(builds, 20);
}

// A simple shear whose top and bottom part by 1.6 skins: the global trigger fires (the
// displacements' box is 1.6 skins long), but particles of neighbouring blocks (two blocks of
// at least two cutoffs, 3.4 mm: five of 4 mm over the bed's 20 mm) moved by at most 0.64
// skin relative to each other, so the check keeps the lists and carries that bound; the
// trigger then adds the displacements since the check to it. A wall counts, of each particle
// not listed with it, the displacement less its room (its gap at the build beyond the skin):
// a floor 1 cm below the bed keeps the lists, a side wall 0.1 mm from it does not (the top's
// particles along it moved 1.6 skins with little room). Off (local_cutoffs 0) and with radii
// that change, no check.
TEST(NeighborList, LocalCheckCarriesItsBounds) {
  Bed b(false, 61);
  const double skin = b.skin, H = b.d.hi.z;
  auto plane_at = [](const Vec3& point, const Vec3& normal) {
    Wall w;
    w.shape = WallShape::Plane;
    w.point = point;
    w.normal = normal;
    return w;
  };
  std::vector<Wall> walls{plane_at({0, 0, -0.01}, {0, 0, 1})};
  b.nl.build(b.p, walls, b.d, skin, 0.0, false);
  const std::vector<Vec3> x0 = b.p.x;
  double zlo = 1e9, zhi = -1e9;
  for (const Vec3& x : x0) { zlo = std::min(zlo, x.z); zhi = std::max(zhi, x.z); }
  const double g = 1.6 * skin / H;
  for (size_t i = 0; i < b.p.size(); ++i) b.p.x[i] += Vec3{g * x0[i].z, 0, 0};
  // The wall bound by brute force: over the particles not listed with the wall (gap at the
  // build above the skin), the displacement less the gap beyond the skin.
  auto wall_bound = [&](const Wall& w) {
    double m = -INFINITY;
    for (size_t i = 0; i < b.p.size(); ++i) {
      const double gap = dot(x0[i] - w.point, w.normal) - b.p.radius[i];
      if (gap > skin) m = std::max(m, norm(b.p.x[i] - x0[i]) - (gap - skin));
    }
    return m;
  };
  ASSERT_TRUE(b.nl.needs_rebuild(b.p, walls, skin));
  const uint64_t epoch = b.nl.epoch;
  b.nl.local_cutoffs = 0;
  EXPECT_FALSE(b.nl.recheck(b.p, walls, skin));
  EXPECT_EQ(b.nl.stats.checks, 0u);  // off: none ran
  EXPECT_EQ(b.nl.epoch, epoch);
  b.nl.local_cutoffs = 2;
  ASSERT_TRUE(b.nl.recheck(b.p, walls, skin));
  EXPECT_EQ(b.nl.stats.checks, 1u);
  EXPECT_EQ(b.nl.stats.deferred, 1u);
  EXPECT_NE(b.nl.epoch, epoch);
  const NeighborList::Reference& r = b.nl.reference();
  // Blocks of at least 2 x (2 x 7.5e-4 + 2e-4) = 3.4 mm: the bed's height in five.
  const double edge = (zhi - zlo) / std::floor((zhi - zlo) / (2 * (2 * 7.5e-4 + skin)));
  EXPECT_GT(r.carried_pair, 0.0);
  EXPECT_LE(r.carried_pair, g * 2 * edge * (1 + 1e-6));
  EXPECT_LE(r.carried_pair, NeighborList::kRecheckRoom * skin);
  ASSERT_EQ(r.carried_wall.size(), 1u);
  // (Gaps and displacements are differences of coordinates of about 1 cm: round-off of
  // 1e-18 m, far below the tolerance of 1e-12 skin.)
  EXPECT_NEAR(r.carried_wall[0], wall_bound(walls[0]), 1e-12 * skin);
  EXPECT_LT(r.carried_wall[0], -0.005);  // every particle far further from the floor than it moved
  EXPECT_EQ(r.from, b.p.x);
  EXPECT_EQ(b.nl.drift_origin(), r.from.data());
  // Nothing moved since the check: the measure is what the check carried.
  Drift none;
  for (size_t i = 0; i < b.p.size(); ++i) b.nl.add_drift(none, b.p, i);
  EXPECT_EQ(b.nl.rebuild_measure(none, {}), r.carried_pair);
  EXPECT_EQ(b.nl.rebuild_measure(none, walls), r.carried_pair);
  // 0.1 skin more for one particle since the check: added to both bounds; the floor moved
  // up by its room and 0.8 skin more: its bound (0.9 skin) passes the pairs' (at most 0.74).
  b.p.x[7] += Vec3{0, 0.1 * skin, 0};
  Drift more;
  for (size_t i = 0; i < b.p.size(); ++i) b.nl.add_drift(more, b.p, i);
  EXPECT_NEAR(b.nl.rebuild_measure(more, {}), r.carried_pair + 0.1 * skin, 1e-12 * skin);
  std::vector<Wall> raised = walls;
  raised[0].point.z += -r.carried_wall[0] + 0.8 * skin;
  EXPECT_NEAR(b.nl.rebuild_measure(more, raised), 0.9 * skin, 1e-9 * skin);
  // A build starts from its own positions again.
  b.nl.build(b.p, walls, b.d, skin, 0.0, false);
  EXPECT_TRUE(b.nl.reference().from.empty());
  EXPECT_EQ(b.nl.reference().carried_pair, 0.0);
  EXPECT_TRUE(b.nl.reference().carried_wall.empty());
  EXPECT_EQ(b.nl.drift_origin(), b.nl.reference().x.data());
  // A shear of 3.2 skins: neighbouring blocks part by 1.28 skins: a build is due.
  const std::vector<Vec3> x1 = b.p.x;
  for (size_t i = 0; i < b.p.size(); ++i) b.p.x[i] += Vec3{2 * g * x1[i].z, 0, 0};
  ASSERT_TRUE(b.nl.needs_rebuild(b.p, walls, skin));
  EXPECT_FALSE(b.nl.recheck(b.p, walls, skin));
  // A side wall 0.1 mm from the bed: the first shear again, and the particles along it at
  // the top moved 1.6 skins with less room than that.
  Bed c(false, 61);
  std::vector<Wall> side{walls[0], plane_at({-1e-4, 0, 0}, {1, 0, 0})};
  c.nl.build(c.p, side, c.d, skin, 0.0, false);
  for (size_t i = 0; i < c.p.size(); ++i) c.p.x[i] += Vec3{g * x0[i].z, 0, 0};
  ASSERT_TRUE(c.nl.needs_rebuild(c.p, side, skin));
  EXPECT_GT(wall_bound(side[1]), NeighborList::kRecheckRoom * skin);
  EXPECT_FALSE(c.nl.recheck(c.p, side, skin));
  // Radii that change between builds (thermal fields): no check.
  ParticleStore q = b.p;
  q.enable_thermal(293.15);
  NeighborList t;
  t.hist.stride = t.whist.stride = 8;
  t.build(q, walls, b.d, skin, 0.0, false);
  for (size_t i = 0; i < q.size(); ++i) q.x[i] += Vec3{g * x1[i].z, 0, 0};
  ASSERT_TRUE(t.needs_rebuild(q, {}, skin));
  EXPECT_FALSE(t.recheck(q, {}, skin));
}

// The local check's bound, computed by brute force from its definition and compared to the
// last bit (min, max and the same norms: exact): each particle in the block of its position
// at the build (the periodic bed's box cut into 5 slabs a direction, of 4 mm >= two cutoffs
// of 3.4 mm), and over every two blocks that are neighbours (a block with itself included,
// across the periodic faces too) the smaller of their joint displacement box's diagonal and
// the sum of their largest displacements; the global bound the smaller of twice the largest
// displacement and the diagonal of all. The displacements: a smooth periodic field of 0.25
// skin (kept) or 0.6 skin (not kept) with jitter. On one to four threads, and again after a
// build that re-sorts the particles (the check sorts them by block once per build and keeps
// that order until the next: an order from the build before would put them in the wrong
// blocks, and the bound would differ).
TEST(NeighborList, LocalCheckBoundIsItsDefinitionOnAnyThreadCountAfterEveryBuild) {
  Bed b(true, 91);
  const double skin = b.skin, L = 0.02;
  double rmax = 0;
  for (size_t i = 0; i < b.p.size(); ++i) rmax = std::max(rmax, b.p.radius[i]);
  const double edge = L / 5;
  ASSERT_EQ(std::floor(L / (2 * (2 * rmax + skin))), 5.0);  // the check's blocks: 5 a direction
  auto brute = [&](const std::vector<Vec3>& x0, const std::vector<Vec3>& x) {
    constexpr int kN = 5;
    std::vector<std::array<double, 7>> blk(kN * kN * kN, {INFINITY, INFINITY, INFINITY, -INFINITY, -INFINITY, -INFINITY, 0});
    Vec3 glo{INFINITY, INFINITY, INFINITY}, ghi{-INFINITY, -INFINITY, -INFINITY};
    double gd2 = 0;
    for (size_t i = 0; i < x.size(); ++i) {
      int k[3];
      for (int d = 0; d < 3; ++d) k[d] = std::min(kN - 1, std::max(0, int(x0[i][d] / edge)));
      std::array<double, 7>& r = blk[size_t((k[2] * kN + k[1]) * kN + k[0])];
      const Vec3 u = x[i] - x0[i];
      for (int d = 0; d < 3; ++d) {
        r[size_t(d)] = std::min(r[size_t(d)], u[d]);
        r[size_t(d) + 3] = std::max(r[size_t(d) + 3], u[d]);
      }
      r[6] = std::max(r[6], norm2(u));
      glo = {std::min(glo.x, u.x), std::min(glo.y, u.y), std::min(glo.z, u.z)};
      ghi = {std::max(ghi.x, u.x), std::max(ghi.y, u.y), std::max(ghi.z, u.z)};
      gd2 = std::max(gd2, norm2(u));
    }
    double local2 = 0;
    for (int a = 0; a < kN * kN * kN; ++a)
      for (int e = 0; e < kN * kN * kN; ++e) {
        bool near = true;  // neighbours: at most one slab apart in each direction, periodically
        for (int d = 0, da = a, de = e; d < 3; ++d, da /= kN, de /= kN) {
          const int g = std::abs(da % kN - de % kN);
          near = near && std::min(g, kN - g) <= 1;
        }
        const std::array<double, 7>&A = blk[size_t(a)], &E = blk[size_t(e)];
        if (!near || !(A[3] >= A[0]) || !(E[3] >= E[0])) continue;
        const Vec3 jl{std::min(A[0], E[0]), std::min(A[1], E[1]), std::min(A[2], E[2])};
        const Vec3 jh{std::max(A[3], E[3]), std::max(A[4], E[4]), std::max(A[5], E[5])};
        const double sum = std::sqrt(A[6]) + std::sqrt(E[6]);
        local2 = std::max(local2, std::min(norm2(jh - jl), sum * sum));
      }
    const double global = std::min(2 * std::sqrt(gd2), norm(ghi - glo));
    const double far = edge * (1 - 1e-9) - 1e-12 * L - 2 * rmax;
    return std::min(global, std::max(std::sqrt(local2), global - (far - skin)));
  };
  Rng rng(5);
  auto displace = [&](const double amp) {
    const double k = 2 * M_PI / L;
    for (size_t i = 0; i < b.p.size(); ++i) {
      const Vec3 x = b.p.x[i];
      const Vec3 jit{rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)};
      b.p.x[i] += Vec3{std::sin(k * x.z), std::cos(k * x.x), std::sin(k * x.y + 1)} * (amp * skin) + jit * (0.02 * skin);
    }
  };
  b.nl.parallel_min = 0;
  int kept = 0, failed = 0;
  for (int build = 0; build < 3; ++build) {
    const std::vector<uint64_t> before = b.p.id;
    if (build > 0) b.nl.build(b.p, {}, b.d, skin, 0.0, true);  // re-sorted: the particles' order changes
    if (build > 0) EXPECT_NE(b.p.id, before);
    const std::vector<Vec3> at_build = b.p.x;
    for (const double amp : {0.25, 0.6}) {
      b.p.x = at_build;
      displace(amp);
      const double want = brute(b.nl.reference().x, b.p.x);
      for (int threads = 1; threads <= 4; ++threads) {
        omp_set_num_threads(threads);
        // A check from the build's positions whatever a kept one before moved the drift origin to.
        const bool keep = b.nl.recheck(b.p, {}, skin);
        omp_set_num_threads(1);
        EXPECT_EQ(keep, want <= NeighborList::kRecheckRoom * skin) << "build " << build << ", " << threads << " threads";
        if (keep) EXPECT_EQ(b.nl.reference().carried_pair, want) << "build " << build << ", " << threads << " threads";
        kept += keep;
        failed += !keep;
      }
    }
    b.p.x = at_build;
    displace(0.25);  // moved on before the next build re-sorts
    for (size_t i = 0; i < b.p.size(); i += 2) b.p.x[i] += Vec3{0.3 * skin, -0.2 * skin, 0.1 * skin};
  }
  EXPECT_EQ(kept, 12);
  EXPECT_EQ(failed, 12);
}
