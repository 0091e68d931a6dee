#include "neighbor/neighbor_list.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "core/error.hpp"

namespace cohdem {

namespace {

struct Key {
  uint64_t a, b;
  uint32_t slot;
  bool operator<(const Key& o) const { return a != o.a ? a < o.a : b < o.b; }
};

/// Live history entries of a list, keyed for lookup after the rebuild.
std::vector<Key> live_keys(const HistoryArray& h, const std::vector<uint64_t>& key_a,
                           const std::vector<uint64_t>& key_b) {
  std::vector<Key> keys;
  for (size_t k = 0; k < h.live.size(); ++k)
    if (h.live[k]) keys.push_back({key_a[k], key_b[k], uint32_t(k)});
  std::sort(keys.begin(), keys.end());
  return keys;
}

/// Copies history of matching keys from `old` into the freshly sized `nu`.
uint64_t carry_over(const std::vector<Key>& keys, const HistoryArray& old, HistoryArray& nu,
                    const std::vector<uint64_t>& na, const std::vector<uint64_t>& nb) {
  if (keys.empty()) return 0;
  uint64_t found = 0;
  for (size_t k = 0; k < na.size(); ++k) {
    const Key q{na[k], nb[k], 0};
    auto it = std::lower_bound(keys.begin(), keys.end(), q);
    if (it != keys.end() && it->a == q.a && it->b == q.b) {
      std::memcpy(nu.at(k), old.data.data() + size_t(it->slot) * old.stride, old.stride);
      nu.live[k] = 1;
      ++found;
    }
  }
  return keys.size() - found;
}

}  // namespace

void NeighborList::build(ParticleStore& p, const std::vector<Wall>& walls, const Domain& dom, double skin,
                         double reach, bool resort) {
  const size_t n = p.size();
  const Vec3 L = dom.length();

  // 0. Keys of live contacts, taken before particles move in memory.
  std::vector<Key> pkeys, wkeys;
  {
    std::vector<uint64_t> a(jdx.size()), b(jdx.size());
    for (size_t i = 0; i + 1 < start.size(); ++i)
      for (uint32_t k = start[i]; k < start[i + 1]; ++k) { a[k] = p.id[i]; b[k] = p.id[jdx[k]]; }
    pkeys = live_keys(hist, a, b);
    std::vector<uint64_t> wa(wall.size()), wb(wall.size());
    for (size_t i = 0; i + 1 < wstart.size(); ++i)
      for (uint32_t k = wstart[i]; k < wstart[i + 1]; ++k) { wa[k] = p.id[i]; wb[k] = wall[k]; }
    wkeys = live_keys(whist, wa, wb);
  }
  HistoryArray old_hist = std::move(hist), old_whist = std::move(whist);
  hist.stride = old_hist.stride;
  whist.stride = old_whist.stride;

  // 1. Wrap periodic coordinates (only here, so stored image codes stay valid between builds).
  for (int d = 0; d < 3; ++d) {
    if (!dom.periodic[d]) continue;
    for (size_t i = 0; i < n; ++i) {
      double& c = p.x[i][d];
      if (c < dom.lo[d] || c >= dom.hi[d]) c -= L[d] * std::floor((c - dom.lo[d]) / L[d]);
      if (c >= dom.hi[d]) c = dom.lo[d];  // round-off guard
    }
  }

  // 2. Grid.
  double rmax = 0;
  for (double r : p.radius) rmax = std::max(rmax, r);
  const double cutoff = 2 * rmax + skin + reach;
  Vec3 lo = dom.lo, hi = dom.hi;
  for (int d = 0; d < 3; ++d) {
    if (dom.periodic[d]) {
      if (L[d] <= cutoff)
        throw RunError("periodic length " + std::to_string(L[d]) + " m in direction " + "xyz"[d] +
                       " must exceed the interaction cutoff " + std::to_string(cutoff) + " m");
      continue;
    }
    lo[d] = INFINITY; hi[d] = -INFINITY;
    for (size_t i = 0; i < n; ++i) { lo[d] = std::min(lo[d], p.x[i][d]); hi[d] = std::max(hi[d], p.x[i][d]); }
    if (n == 0) { lo[d] = 0; hi[d] = 1; }
    hi[d] += 1e-9 * (1 + std::fabs(hi[d]));
  }
  std::array<int, 3> nc{};
  std::array<double, 3> cell{};
  double cell_min = std::max(cutoff, 1e-12);
  for (;;) {  // cap the cell count at a few per particle (a stray particle must not blow it up)
    double total = 1;
    for (int d = 0; d < 3; ++d) {
      const double ext = std::max(hi[d] - lo[d], 1e-12);
      nc[d] = std::max(1, int(std::min(ext / cell_min, 1e6)));
      cell[d] = ext / nc[d];
      total *= nc[d];
    }
    if (total <= 4.0 * double(n) + 64) break;
    cell_min *= 1.25;
  }
  const size_t ncell = size_t(nc[0]) * nc[1] * nc[2];
  auto cell_index = [&](const Vec3& x) {
    std::array<int, 3> c;
    for (int d = 0; d < 3; ++d) c[d] = std::clamp(int((x[d] - lo[d]) / cell[d]), 0, nc[d] - 1);
    return (size_t(c[2]) * nc[1] + c[1]) * nc[0] + c[0];
  };

  // 3. Bin (counting sort); optionally re-sort particles so cell neighbours are memory neighbours.
  auto bin = [&]() {
    cell_of_.resize(n);
    cell_start_.assign(ncell + 1, 0);
    for (size_t i = 0; i < n; ++i) { cell_of_[i] = uint32_t(cell_index(p.x[i])); ++cell_start_[cell_of_[i] + 1]; }
    for (size_t c = 0; c < ncell; ++c) cell_start_[c + 1] += cell_start_[c];
    cell_list_.resize(n);
    std::vector<uint32_t> fill(cell_start_.begin(), cell_start_.end() - 1);
    for (size_t i = 0; i < n; ++i) cell_list_[fill[cell_of_[i]]++] = uint32_t(i);
  };
  bin();
  if (resort && n > 0) {
    p.permute(cell_list_);
    bin();
  }

  for (int sx = -1; sx <= 1; ++sx)
    for (int sy = -1; sy <= 1; ++sy)
      for (int sz = -1; sz <= 1; ++sz)
        shift[(sx + 1) * 9 + (sy + 1) * 3 + (sz + 1)] = {sx * L.x, sy * L.y, sz * L.z};

  // 4. Pairs: scan the 27 neighbouring cells of each particle, keep j > i (local index),
  //    then orient each pair so its first particle has the lower id.
  struct Raw { uint32_t i, j; uint8_t img; };
  std::vector<Raw> raw;
  raw.reserve(n * 8);
  std::vector<uint32_t> count(n + 1, 0);
  for (size_t a = 0; a < n; ++a) {
    const size_t ca = cell_of_[a];
    const int cx = int(ca % nc[0]), cy = int((ca / nc[0]) % nc[1]), cz = int(ca / (size_t(nc[0]) * nc[1]));
    for (int oz = -1; oz <= 1; ++oz) {
      int z = cz + oz, sz = 0;
      if (z < 0 || z >= nc[2]) {
        if (!dom.periodic[2]) continue;
        sz = z < 0 ? -1 : 1; z -= sz * nc[2];
      }
      for (int oy = -1; oy <= 1; ++oy) {
        int y = cy + oy, sy = 0;
        if (y < 0 || y >= nc[1]) {
          if (!dom.periodic[1]) continue;
          sy = y < 0 ? -1 : 1; y -= sy * nc[1];
        }
        for (int ox = -1; ox <= 1; ++ox) {
          int xx = cx + ox, sx = 0;
          if (xx < 0 || xx >= nc[0]) {
            if (!dom.periodic[0]) continue;
            sx = xx < 0 ? -1 : 1; xx -= sx * nc[0];
          }
          // Duplicate visits of one cell with the same image happen when nc < 3 in a
          // non-periodic direction only if offsets coincide; they cannot, as out-of-range
          // offsets are skipped there. In periodic directions each offset has its own image.
          const size_t cb = (size_t(z) * nc[1] + y) * nc[0] + xx;
          const uint8_t img = uint8_t((sx + 1) * 9 + (sy + 1) * 3 + (sz + 1));
          const Vec3& sh = shift[img];
          for (uint32_t q = cell_start_[cb]; q < cell_start_[cb + 1]; ++q) {
            const uint32_t b = cell_list_[q];
            if (b <= a) continue;
            if (p.flag[a] != kFree && p.flag[b] != kFree) continue;  // two fixed bodies
            const Vec3 d = p.x[a] - (p.x[b] + sh);
            const double rc = p.radius[a] + p.radius[b] + skin + reach;
            if (norm2(d) >= rc * rc) continue;
            if (p.id[a] < p.id[b]) raw.push_back({uint32_t(a), b, img});
            else raw.push_back({b, uint32_t(a), uint8_t(26 - img)});
            ++count[raw.back().i + 1];
          }
        }
      }
    }
  }
  // A nonperiodic direction with a single cell visits offsets -1 and +1 not at all, and a
  // periodic direction with nc = 1 or 2 visits the same cell under distinct images: correct.
  start.assign(n + 1, 0);
  for (size_t i = 0; i < n; ++i) start[i + 1] = start[i] + count[i + 1];
  jdx.resize(raw.size());
  image.resize(raw.size());
  {
    std::vector<uint32_t> fill(start.begin(), start.end() - 1);
    for (const Raw& r : raw) { const uint32_t k = fill[r.i]++; jdx[k] = r.j; image[k] = r.img; }
  }
  rstart.assign(n + 1, 0);
  for (uint32_t j : jdx) ++rstart[j + 1];
  for (size_t i = 0; i < n; ++i) rstart[i + 1] += rstart[i];
  rslot.resize(jdx.size());
  {
    std::vector<uint32_t> fill(rstart.begin(), rstart.end() - 1);
    for (size_t i = 0; i < n; ++i)
      for (uint32_t k = start[i]; k < start[i + 1]; ++k) rslot[k] = fill[jdx[k]]++;
  }
  in_f.assign(jdx.size(), Vec3{});
  in_tj.assign(jdx.size(), Vec3{});
  dep_lo.resize(n);
  dep_hi.resize(n);
  for (size_t i = 0; i < n; ++i) dep_lo[i] = dep_hi[i] = uint32_t(i);
  for (size_t i = 0; i < n; ++i)
    for (uint32_t k = start[i]; k < start[i + 1]; ++k) {
      const uint32_t j = jdx[k];
      dep_lo[j] = std::min(dep_lo[j], uint32_t(i));
      dep_hi[j] = std::max(dep_hi[j], uint32_t(i));
    }

  // 5. Wall candidates.
  wstart.assign(n + 1, 0);
  wall.clear();
  for (size_t i = 0; i < n; ++i) {
    if (p.flag[i] == kFree) {
      for (size_t w = 0; w < walls.size(); ++w) {
        Vec3 nn;
        double delta;
        // Bounded walls: test with the bounds widened by the cutoff so an approaching
        // particle is listed before it reaches an edge.
        Wall wide = walls[w];
        const double m = p.radius[i] + skin + reach;
        wide.rmin = std::max(0.0, wide.rmin - m); wide.rmax += m; wide.zmin -= m; wide.zmax += m;
        if (wide.contact(p.x[i], p.radius[i], nn, delta) && delta > -(skin + reach)) wall.push_back(uint16_t(w));
      }
    }
    wstart[i + 1] = uint32_t(wall.size());
  }

  // 6. Carry history over.
  hist.resize(jdx.size());
  whist.resize(wall.size());
  {
    std::vector<uint64_t> a(jdx.size()), b(jdx.size());
    for (size_t i = 0; i < n; ++i)
      for (uint32_t k = start[i]; k < start[i + 1]; ++k) { a[k] = p.id[i]; b[k] = p.id[jdx[k]]; }
    stats.lost_contacts += carry_over(pkeys, old_hist, hist, a, b);
    std::vector<uint64_t> wa(wall.size()), wb(wall.size());
    for (size_t i = 0; i < n; ++i)
      for (uint32_t k = wstart[i]; k < wstart[i + 1]; ++k) { wa[k] = p.id[i]; wb[k] = wall[k]; }
    stats.lost_contacts += carry_over(wkeys, old_whist, whist, wa, wb);
  }

  // 7. Reference state for the rebuild trigger.
  x_ref_ = p.x;
  r_ref_ = p.radius;
  wall_ref_.resize(walls.size());
  for (size_t w = 0; w < walls.size(); ++w) wall_ref_[w] = walls[w].point;
  ++stats.builds;
}

bool NeighborList::needs_rebuild(const ParticleStore& p, const std::vector<Wall>& walls, double skin) const {
  if (x_ref_.size() != p.size()) return true;
  const long n = long(p.size());
  double dmax2 = 0, grow = 0;
#pragma omp parallel for reduction(max : dmax2, grow) schedule(static)
  for (long i = 0; i < n; ++i) {
    if (p.flag[i] == kFrozen) continue;
    dmax2 = std::max(dmax2, norm2(p.x[i] - x_ref_[i]));
    grow = std::max(grow, p.radius[i] - r_ref_[i]);
  }
  const double dmax = std::sqrt(dmax2) + grow;
  if (2 * dmax > skin) return true;
  for (size_t w = 0; w < walls.size(); ++w)
    if (dmax + walls[w].geometric_displacement(walls[w].point - wall_ref_[w]) > skin) return true;
  return false;
}

size_t NeighborList::live_contacts() const {
  size_t c = 0;
  for (uint8_t l : hist.live) c += l;
  for (uint8_t l : whist.live) c += l;
  return c;
}

}  // namespace cohdem
