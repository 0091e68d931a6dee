#include "neighbor/neighbor_list.hpp"

#include <omp.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <memory>

#include "core/error.hpp"
#include "core/grow.hpp"
#include "neighbor/search.hpp"
#include "sim/screen.hpp"  // screen_avx2_enabled: the one switch of the AVX2 code (COHDEM_SIMD)

namespace cohdem {

void NeighborList::build(ParticleStore& p, const std::vector<Wall>& walls, const Domain& dom, double skin,
                         double reach, bool resort) {
  const size_t n = p.size();
  const Vec3 L = dom.length();

  // 0. For the history carry-over: the old lists' live pair contacts, copied out compactly
  //    (keep_live_pairs), the old wall lists (swapped into scratch: no allocation) and the ids
  //    the old local indices referred to. The pair lists' own storage is then reused for the
  //    new lists, so a build holds one full pair list, not two (a second one, kept as
  //    scratch, cost 4 + 1 + the history's bytes per entry for the whole run: 29 with the
  //    linear law, 61 with Hertz-Mindlin + EPSD, at ~3.5 entries a particle).
  const size_t old_n = start.empty() ? 0 : start.size() - 1;
  if (ids_.size() != old_n) {  // lists built before ids were recorded: rows 0..old_n-1 are p's
    ids_.assign(p.id.begin(), p.id.begin() + std::min(old_n, n));
    ids_.resize(old_n, UINT64_MAX);
  }
  keep_live_pairs(old_n);
  old_wstart_.swap(wstart);
  old_wall_.swap(wall);
  old_whist_.swap(whist.data);
  old_wlive_.swap(whist.live);
  old_ids_.swap(ids_);

  // 1. One pass over the particles, on all threads (minimum, maximum, sum and "or" are exact
  //    reductions: the same on any number of threads): periodic coordinates wrapped (only
  //    here, so stored image codes stay valid between builds), the bounds of the others, the
  //    largest radius, whether the particles share one species, how many are attached.
  const bool per[3] = {dom.periodic[0], dom.periodic[1], dom.periodic[2]};
  const Vec3 dlo = dom.lo, dhi = dom.hi;
  double lx = INFINITY, ly = INFINITY, lz = INFINITY, hx = -INFINITY, hy = -INFINITY, hz = -INFINITY, rmax = 0;
  size_t n_att = 0;
  bool mixed = false;
  {
    Vec3* const px = p.x.data();
    const double* const pr = p.radius.data();
    const int* const ps = p.species.data();
    const uint8_t* const pf = p.flag.data();
    const int s0 = n > 0 ? ps[0] : -1;
#pragma omp parallel for schedule(static) if (long(n) > parallel_min) reduction(min : lx, ly, lz) \
    reduction(max : hx, hy, hz, rmax) reduction(+ : n_att) reduction(|| : mixed)
    for (size_t i = 0; i < n; ++i) {
      Vec3 x = px[i];
      // Outside the box in a periodic direction (rare): wrapped, and stored (a store of every
      // particle would take its line from the core that holds it).
      const bool out = (per[0] && (x.x < dlo.x || x.x >= dhi.x)) || (per[1] && (x.y < dlo.y || x.y >= dhi.y)) ||
                       (per[2] && (x.z < dlo.z || x.z >= dhi.z));
      if (out) [[unlikely]] {
        for (int d = 0; d < 3; ++d) {
          double& c = x[d];
          if (!per[d] || (c >= dlo[d] && c < dhi[d])) continue;
          c -= L[d] * std::floor((c - dlo[d]) / L[d]);
          if (c >= dhi[d]) c = dlo[d];  // round-off guard
        }
        px[i] = x;
      }
      lx = std::min(lx, x.x); ly = std::min(ly, x.y); lz = std::min(lz, x.z);
      hx = std::max(hx, x.x); hy = std::max(hy, x.y); hz = std::max(hz, x.z);
      rmax = std::max(rmax, pr[i]);
      mixed = mixed || ps[i] != s0;
      n_att += pf[i] == kAttached;
    }
  }

  // 2. Grid.
  const double cutoff = 2 * rmax + skin + reach;
  Vec3 lo = dom.lo, hi = dom.hi;
  const Vec3 xmin{lx, ly, lz}, xmax{hx, hy, hz};
  for (int d = 0; d < 3; ++d) {
    if (dom.periodic[d]) {
      if (L[d] <= cutoff)
        throw RunError("periodic length " + std::to_string(L[d]) + " m in direction " + "xyz"[d] +
                       " must exceed the interaction cutoff " + std::to_string(cutoff) + " m");
      continue;
    }
    lo[d] = xmin[d];
    hi[d] = xmax[d];
    if (n == 0) { lo[d] = 0; hi[d] = 1; }
    hi[d] += 1e-9 * (1 + std::fabs(hi[d]));
  }
  box_lo_ = lo;  // the build's bounds, for the local check's blocks (recheck)
  box_hi_ = hi;
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
  //    Periodic in z (the slowest direction of the cell order) with at least 4 planes of
  //    cells, the re-sort takes the planes folded: 0, nz - 1, 1, nz - 2, 2, ... (plane z at
  //    place 2z in the first half, 2(nz - 1 - z) + 1 in the second), so that the planes
  //    either side of the periodic seam are neighbours in memory too. In plain order the
  //    bottom plane's pairs reach the top plane, n particles away: every pair's partner lies
  //    within one plane of cells in the particle order except those, and the force loop's
  //    split (PairSlots::span, the widest reach of a row) then spans the whole system, which
  //    leaves several threads no chained finishing and no two steps in one sweep. Folded, a
  //    partner lies within two planes (plus a row and a cell) of its row, seam or not. The
  //    search numbers the cells as before (the fold is only the particles' order), and every
  //    pair is found once whatever the indices (step 4). Only where pairs can cross the seam
  //    (the particles' gap across it within the cutoff): a bed settled in a taller periodic
  //    box has none, and there the fold would only double the reach (the 10^6 gas with a gap
  //    of 1.5 d at the seam ran 0.91x on two threads folded).
  const bool fold = dom.periodic[2] && nc[2] >= 4 && n > 0 && (lz - dom.lo.z) + (dom.hi.z - hz) <= cutoff;
  const size_t plane = size_t(nc[0]) * size_t(nc[1]);
  auto folded = [&](const size_t c) {
    const size_t z = c / plane, nz = size_t(nc[2]);
    const size_t at = 2 * z < nz ? 2 * z : 2 * (nz - 1 - z) + 1;
    return at * plane + c % plane;
  };
  // On several threads the cell order is cut into parts, one a thread, where the particle
  // order (the cell order of the last re-sort) cuts it into equal shares, and each thread
  // counts, places and later copies and searches its own part's cells: the cell starts and
  // the cell list are then written where the search reads them (binned by one thread, half
  // the lines the other thread's search read came from the first core: the chute's search
  // on two threads 1.5x the time of one thread's, the seventy-first round in
  // docs/performance-history.md). Each thread reads all the particles' cells twice (4 bytes
  // a particle) and keeps those of its part, in particle order: the same cell list as one
  // thread's.
  const int nthreads = long(n) > parallel_min ? omp_get_max_threads() : 1;
  auto bin = [&](const bool by_fold = false) {
    cell_of_.resize(n);
    reserve_headroom(cell_start_, ncell + 1);
    cell_start_.resize(ncell + 1);
    cell_list_.reserve(n + kSearchPad);  // exactly (the AVX2 search's padding below; a resize past
    cell_list_.resize(n);                // the capacity would double it)
    fill_.resize(std::max(ncell, n));
    if (nthreads == 1) {
      for (size_t i = 0; i < n; ++i) {
        const size_t c = cell_index(p.x[i]);
        cell_of_[i] = uint32_t(by_fold ? folded(c) : c);
      }
      std::fill(cell_start_.begin(), cell_start_.end(), 0u);
      for (size_t i = 0; i < n; ++i) ++cell_start_[cell_of_[i] + 1];
      for (size_t c = 0; c < ncell; ++c) cell_start_[c + 1] += cell_start_[c];
      std::copy(cell_start_.begin(), cell_start_.end() - 1, fill_.begin());
      for (size_t i = 0; i < n; ++i) cell_list_[fill_[cell_of_[i]]++] = uint32_t(i);
      split_.assign({0u, uint32_t(ncell)});
      return;
    }
#pragma omp parallel num_threads(nthreads)
    {
      const size_t nt = size_t(omp_get_num_threads()), t = size_t(omp_get_thread_num());
      for (size_t i = n * t / nt, i1 = n * (t + 1) / nt; i < i1; ++i) {
        const size_t c = cell_index(p.x[i]);
        cell_of_[i] = uint32_t(by_fold ? folded(c) : c);
      }
#pragma omp barrier
#pragma omp single
      {
        split_.assign(nt + 1, 0);
        for (size_t u = 1; u < nt; ++u) split_[u] = std::max(split_[u - 1], cell_of_[n * u / nt]);
        split_[nt] = uint32_t(ncell);
        part_.assign(nt, 0);
      }  // implicit barrier
      const uint32_t c0 = split_[t], c1 = split_[t + 1];
      const uint32_t* const co = cell_of_.data();
      uint32_t* const cs = cell_start_.data();
      if (t == 0) cs[0] = 0;
      for (uint32_t c = c0; c < c1; ++c) cs[c + 1] = 0;
      for (size_t i = 0; i < n; ++i)
        if (co[i] - c0 < c1 - c0) ++cs[co[i] + 1];
      uint32_t run = 0;
      for (uint32_t c = c0; c < c1; ++c) cs[c + 1] = run += cs[c + 1];
      part_[t] = run;
#pragma omp barrier
      uint32_t off = 0;  // the particles of the parts before this one
      for (size_t u = 0; u < t; ++u) off += uint32_t(part_[u]);
      uint32_t* const fl = fill_.data();
      for (uint32_t c = c0, at = off; c < c1; ++c) {
        fl[c] = at;
        at = cs[c + 1] += off;
      }
      uint32_t* const cl = cell_list_.data();
      for (size_t i = 0; i < n; ++i)
        if (co[i] - c0 < c1 - c0) cl[fl[co[i]]++] = uint32_t(i);
    }
  };
  bin(resort && fold);
  if (resort && n > 0) {
    p.permute(cell_list_);
    bin();
  }
  one_species = n > 0 && !mixed ? p.species[0] : -1;
  attached.clear();  // ascending (after the re-sort)
  for (size_t i = 0; i < n && attached.size() < n_att; ++i)
    if (p.flag[i] == kAttached) attached.push_back(uint32_t(i));

  for (int sx = -1; sx <= 1; ++sx)
    for (int sy = -1; sy <= 1; ++sy)
      for (int sz = -1; sz <= 1; ++sz)
        shift[(sx + 1) * 9 + (sy + 1) * 3 + (sz + 1)] = {sx * L.x, sy * L.y, sz * L.z};

  // The candidates' positions and radii in cell order, for the AVX2 search (search.hpp): a
  // range of candidates is then one contiguous run of each, read four at a time. Padded past
  // the end (kSearchPad) with entries that are never picked. 32 bytes a particle, needed during the search only: they are kept in the pair history's storage,
  // whose records were copied out above (keep_live_pairs) and which is cleared for the new
  // lists below (step 6), where it is large enough (a list of 3.5 entries a particle holds
  // 84 bytes a particle with the linear law's 24-byte records); else (the first build) in
  // memory of their own, freed after the search. (Kept between builds in arrays of their
  // own, they raised the chute's peak memory by 5 %.)
  const bool simd = screen_avx2_enabled();
  SearchInput sin{};
  std::vector<double> soa;  // only where the history's storage is too small
  if (simd) {
    const size_t m = n + kSearchPad, words = 4 * m;
    double* sx = nullptr;
    if (hist.data.size() >= (words + 4) * sizeof(double)) {
      uintptr_t at = reinterpret_cast<uintptr_t>(hist.data.data());
      at = (at + 31) & ~uintptr_t(31);
      sx = reinterpret_cast<double*>(at);
    } else {
      soa.resize(words);
      sx = soa.data();
    }
    cell_list_.resize(m);
    uint32_t* const cl = cell_list_.data();
    auto copy = [&](const size_t t0, const size_t t1) {
      for (size_t t = t0; t < t1; ++t) {
        const uint32_t b = cl[t];
        sx[t] = p.x[b].x;
        sx[m + t] = p.x[b].y;
        sx[2 * m + t] = p.x[b].z;
        sx[3 * m + t] = p.radius[b];
      }
    };
    if (nthreads == 1) {
      copy(0, n);
    } else {
      // Each part's by the thread that binned it, and searches it below.
      const size_t parts = split_.size() - 1;
#pragma omp parallel num_threads(nthreads)
      for (size_t r = size_t(omp_get_thread_num()); r < parts; r += size_t(omp_get_num_threads()))
        copy(cell_start_[split_[r]], cell_start_[split_[r + 1]]);
    }
    for (size_t t = n; t < m; ++t) {
      sx[t] = sx[m + t] = sx[2 * m + t] = sx[3 * m + t] = 0.0;
      cl[t] = 0;
    }
    sin = {sx, sx + m, sx + 2 * m, sx + 3 * m, cl, p.flag.data(), shift.data()};
  }

  // 4. Pairs, by a half stencil: each particle a (cells in order, a cell's particles in
  //    order) tests the particles after it in its own cell and those of the 13 cells ahead
  //    of its cell (x + 1, the row above, the plane above; each with its periodic image), so
  //    each pair of cells related by an offset and an image is searched once, from the cell
  //    behind, and each pair of particles (under each image) is found once, whatever their
  //    indices. In a periodic direction of one or two cells, a cell's neighbours at -1 and +1
  //    are one cell under two images: both are still searched, once each, from the two sides.
  //    (The full stencil of 27 cells tested twice the candidates, and its test b > a, which
  //    discards half of them, was a coin toss for the branch predictor once the particles had
  //    left the cell order of the last re-sort: the chute's build took 6.6 ms, 3.8 ms now.)
  //    A pair goes to the row of its lower index (the force kernel's order), with the image
  //    of the higher seen from there: the pairs are keyed (lower, higher) in the order they
  //    are found, then counted into rows and placed in that order. Row order: the order of
  //    the search.
  //    With AVX2 (screen_avx2_enabled), each particle's candidates are tested four at a time
  //    from the copies in cell order above (search_avx2: the same arithmetic, keys, images
  //    and order as the loop below, so the same lists; chute build 1.21x, forty-ninth round
  //    in docs/performance-history.md).
  //    Parallel: each thread's part of the cell order (step 3) is cut into chunks of about
  //    equal particle counts, which the thread searches from the front; a thread done takes
  //    the chunks left in the other parts from their backs (below). The chunks' pairs are
  //    placed in chunk order, the order of a search on one thread, so the lists do not
  //    depend on the threads.
  const uint64_t* const id = p.id.data();
  const uint8_t* const flag = p.flag.data();
  const Vec3* const x = p.x.data();
  const double* const rad = p.radius.data();
  // The chunks: each part of the cell order (one on one thread) cut into up to 8 of about
  // equal particle counts (at least 256 particles each).
  chunk_cell_.clear();
  run_first_.clear();
  for (size_t r = 0; r + 1 < split_.size(); ++r) {
    run_first_.push_back(uint32_t(chunk_cell_.size()));
    const size_t q0 = cell_start_[split_[r]], q1 = cell_start_[split_[r + 1]];
    const size_t k = nthreads == 1 ? 1 : std::clamp<size_t>((q1 - q0) / 256, 1, 8);
    for (size_t u = 0; u < k; ++u) {
      const size_t q = q0 + (q1 - q0) * u / k;
      chunk_cell_.push_back(u == 0 ? split_[r] : std::max(chunk_cell_.back(), cell_of_[cell_list_[q]]));
    }
  }
  run_first_.push_back(uint32_t(chunk_cell_.size()));
  chunk_cell_.push_back(uint32_t(ncell));
  const int chunks = int(chunk_cell_.size()) - 1;
  if (int(tl_key_.size()) < chunks) { tl_key_.resize(size_t(chunks)); tl_img_.resize(size_t(chunks)); }
  tl_cnt_.resize(size_t(chunks));
  tl_rng_.resize(size_t(chunks));
  size_t np = 0;
  {
    // A chunk takes its cells; the cells' ranges of candidates are worked out once for
    // their particles.
    const uint32_t* const cl = cell_list_.data();
    const uint32_t* const cs = cell_start_.data();
    auto search_chunk = [&](const int ch) {
      const size_t c0 = chunk_cell_[size_t(ch)], c1 = chunk_cell_[size_t(ch) + 1];
      // Filled through vector objects of the thread's own (swapped in and out, keeping their
      // capacity): the tl_ vectors' headers share cache lines, and every growth through them
      // would bounce those lines between the cores (once, two threads took three times one
      // thread's time over the chute's pair search that way).
      std::vector<uint64_t> key;
      std::vector<uint8_t> image;
      key.swap(tl_key_[ch]);
      image.swap(tl_img_[ch]);
      // Written through raw pointers at `cnt`, room made before each particle for all its
      // candidates: each candidate is stored, and kept (cnt advanced) when it is a pair, with
      // no branch on the outcome (about one candidate in six is kept) and nothing reloaded
      // after the stores (through a vector, every push_back made the loop reload its arrays).
      // The buffers hold up to twice the pairs and one particle's candidates (9 bytes each:
      // at most about 60 bytes per particle on the chute; peak memory 17-18 bytes per particle
      // above the old search's buffers in bench/scaling.py at 32,000 and 10^6 particles).
      size_t cnt = 0;
      uint64_t* kout = key.data();
      uint8_t* iout = image.data();
      // A cell's ranges of candidates in cl: [q0, q1) seen under image img. The first is its
      // own (from the particle after a on) with x + 1 where contiguous.
      uint32_t rq0[16], rq1[16];
      uint8_t rimg[16];
      int cx = int(c0 % nc[0]), cy = int((c0 / nc[0]) % nc[1]), cz = int(c0 / (size_t(nc[0]) * nc[1]));
      for (size_t c = c0; c < c1; ++c) {
        if (c > c0 && ++cx == nc[0]) {
          cx = 0;
          if (++cy == nc[1]) { cy = 0; ++cz; }
        }
        if (cs[c] == cs[c + 1]) continue;
        int nr = 1;
        // The cells x + ox0 .. x + 1 of the cell row (y, z), seen under images sy, sz.
        auto row = [&](const int y, const int sy, const int z, const int sz, const int ox0) {
          const size_t row0 = (size_t(z) * nc[1] + y) * nc[0];
          if (cx + ox0 >= 0 && cx + 1 < nc[0]) {  // contiguous in cl, one image
            rq0[nr] = cs[row0 + cx + ox0];
            rq1[nr] = cs[row0 + cx + 2];
            rimg[nr++] = uint8_t(9 + (sy + 1) * 3 + (sz + 1));
            return;
          }
          for (int ox = ox0; ox <= 1; ++ox) {
            int xx = cx + ox, sx = 0;
            if (xx < 0 || xx >= nc[0]) {
              if (!dom.periodic[0]) continue;
              sx = xx < 0 ? -1 : 1;
              xx -= sx * nc[0];
            }
            rq0[nr] = cs[row0 + xx];
            rq1[nr] = cs[row0 + xx + 1];
            rimg[nr++] = uint8_t((sx + 1) * 9 + (sy + 1) * 3 + (sz + 1));
          }
        };
        // A neighbouring index in a direction of nc cells: wrapped (image s) where periodic,
        // false where it lies outside.
        auto wrap = [&](const int d, int& v, int& s) {
          s = 0;
          if (v >= 0 && v < nc[d]) return true;
          if (!dom.periodic[d]) return false;
          s = v < 0 ? -1 : 1;
          v -= s * nc[d];
          return true;
        };
        // Own range: the cell itself, and x + 1 when it follows in cl (else a range of its own).
        const bool x_next = cx + 1 < nc[0];
        rq1[0] = cs[c + (x_next ? 2 : 1)];
        rimg[0] = kNoShift;
        if (!x_next && dom.periodic[0]) {
          const size_t row0 = c - size_t(cx);
          rq0[nr] = cs[row0];
          rq1[nr] = cs[row0 + 1];
          rimg[nr++] = uint8_t(2 * 9 + 1 * 3 + 1);  // x + 1 wrapped: sx = +1
        }
        int y = cy + 1, sy = 0, z = cz + 1, sz = 0;
        if (wrap(1, y, sy)) row(y, sy, cz, 0, -1);  // the row above
        if (wrap(2, z, sz))                          // the plane above
          for (int oy = -1; oy <= 1; ++oy) {
            y = cy + oy;
            if (wrap(1, y, sy)) row(y, sy, z, sz, -1);
          }
        uint32_t total = rq1[0] - cs[c];
        for (int r = 1; r < nr; ++r) total += rq1[r] - rq0[r];
        for (uint32_t q = cs[c]; q < cs[c + 1]; ++q) {
          if (cnt + total + kSearchPad > key.size()) {  // room for every candidate of a (and the AVX2 search's last group)
            const size_t m = std::max<size_t>(2 * key.size(), cnt + total + 1024);
            key.resize(m);
            image.resize(m);
            kout = key.data();
            iout = image.data();
          }
          const uint32_t a = cl[q];
          const bool fixed_a = flag[a] != kFree;
          const Vec3 xa = x[a];
          const double ra = rad[a] + skin + reach;
          rq0[0] = q + 1;
          if (simd) {
            cnt = search_avx2(sin, a, xa, ra, fixed_a, nr, rq0, rq1, rimg, kout, iout, cnt);
            continue;
          }
          size_t k = cnt;
          for (int r = 0; r < nr; ++r) {
            const uint8_t img = rimg[r], back = uint8_t(26 - img);  // back: a seen from b
            const Vec3 xs = xa - shift[img];
            for (uint32_t t = rq0[r]; t < rq1[r]; ++t) {
              const uint32_t b = cl[t];
              const Vec3 d = xs - x[b];
              const double rc = ra + rad[b];
              const bool both_fixed = fixed_a && flag[b] != kFree;
              const bool lower = a < b;  // else the pair goes to b's row, seen from b
              kout[k] = lower ? uint64_t(a) << 32 | b : uint64_t(b) << 32 | a;
              iout[k] = lower ? img : back;
              k += (norm2(d) < rc * rc) & !both_fixed;
            }
          }
          cnt = k;
        }
      }
      tl_cnt_[size_t(ch)] = cnt;  // the buffers keep their length (no zero fill at the next build)
      // The chunk's range of rows and of partners, while its pairs are in cache: the rows'
      // threads below skip the chunks that hold none of theirs (one thread: all are its).
      uint32_t ilo = 0, ihi = UINT32_MAX, jlo = 0, jhi = UINT32_MAX;
      if (nthreads > 1) { ilo = jlo = UINT32_MAX; ihi = jhi = 0; }
      for (size_t e = 0; e < cnt && nthreads > 1; ++e) {
        const uint32_t i = uint32_t(kout[e] >> 32), j = uint32_t(kout[e]);
        ilo = std::min(ilo, i);
        ihi = std::max(ihi, i);
        jlo = std::min(jlo, j);
        jhi = std::max(jhi, j);
      }
      tl_rng_[size_t(ch)] = {ilo, ihi, jlo, jhi};
      key.swap(tl_key_[ch]);
      image.swap(tl_img_[ch]);
    };
    if (nthreads == 1) {
      for (int ch = 0; ch < chunks; ++ch) search_chunk(ch);
    } else {
      // Thread t searches its own part's chunks from the front: it binned and copied that
      // part's cells (step 3), and their pairs are mostly rows of its own (the rows' ranges
      // below). Done, it takes the chunks left in the other parts from their backs (cells
      // differ in cost: a chute's frozen base against its flow, a bed's floor against its
      // free surface). Each part's front and back are one word, claimed by compare-and-swap,
      // on a line of its own. Chunks handed to the threads as they came free, any chunk to
      // either thread, made about half the chunks' copies and pairs the other core's lines
      // (seventy-first round in docs/performance-history.md).
      struct alignas(64) Run {
        std::atomic<uint64_t> fb{0};  ///< front (low 32 bits) and back (high 32): chunks [front, back) left
      };
      const int nruns = int(run_first_.size()) - 1;
      const std::unique_ptr<Run[]> runs(new Run[size_t(nruns)]);
      for (int r = 0; r < nruns; ++r)
        runs[size_t(r)].fb.store(uint64_t(run_first_[size_t(r) + 1]) << 32 | run_first_[size_t(r)], std::memory_order_relaxed);
      // One chunk from the front (or the back) of run r; false when none is left.
      auto claim = [](Run& r, const bool front, int& ch) {
        uint64_t v = r.fb.load(std::memory_order_relaxed);
        for (;;) {
          const uint32_t f = uint32_t(v), b = uint32_t(v >> 32);
          if (f >= b) return false;
          const uint64_t w = front ? (uint64_t(b) << 32 | (f + 1)) : (uint64_t(b - 1) << 32 | f);
          if (r.fb.compare_exchange_weak(v, w, std::memory_order_relaxed)) {
            ch = int(front ? f : b - 1);
            return true;
          }
        }
      };
#pragma omp parallel num_threads(nthreads)
      {
        const int t = omp_get_thread_num();
        int ch;
        if (t < nruns)
          while (claim(runs[size_t(t)], true, ch)) search_chunk(ch);
        // Every other run, the runs of threads the region did not start included.
        for (int k = 1; k <= nruns; ++k)
          if ((t + k) % nruns != t)
            while (claim(runs[size_t((t + k) % nruns)], false, ch)) search_chunk(ch);
      }
    }
    std::vector<double>().swap(soa);  // before the rows and the history take their memory
    // Rows: counted, then filled in the order the pairs were found (chunk after chunk). The
    // same pass counts the transposed rows and finds each particle's lowest row (dep_lo).
    // Then the transposed slots, in ascending list order per particle.
    // Several threads: each takes the rows and transposed rows of an equal range of the
    // particles and scans the pairs of the chunks that hold any of its own (on one thread
    // these passes took 0.6 ms of the chute's 3.1 ms two-thread build; 0.35-0.45 ms now).
    // Each row is filled in the order of the pairs' discovery, each transposed row in list
    // order, the same on any number of threads.
    start.resize(n + 1);
    rstart.resize(n + 1);
    dep_lo.resize(n);
    start[0] = rstart[0] = 0;
    fill_.resize(n);
    ref_.x.resize(n);  // the reference state for the rebuild trigger (step 7), copied by range
    // The radii only where they can change between builds: a thermal model's expansion,
    // which keeps the thermal fields (8 bytes a particle, and a copy at each build, that a
    // mechanical run would carry for nothing).
    const bool keep_r = p.thermal();
    if (keep_r)
      ref_.r.resize(n);
    else
      std::vector<double>().swap(ref_.r);
    const int rows_threads = nthreads > 1 && n > 0 ? nthreads : 1;
    part_.assign(2 * size_t(rows_threads), 0);
#pragma omp parallel num_threads(rows_threads) if (rows_threads > 1)
    {
      const size_t nt = size_t(omp_get_num_threads()), t = size_t(omp_get_thread_num());
      const uint32_t lo = uint32_t(n * t / nt), hi = uint32_t(n * (t + 1) / nt), len = hi - lo;
      uint32_t* const st = start.data() + 1;  // st[i]: row i's count, then its end
      uint32_t* const rs = rstart.data() + 1;
      uint32_t* const dl = dep_lo.data();
      for (uint32_t i = lo; i < hi; ++i) { st[i] = 0; rs[i] = 0; dl[i] = i; }
      std::copy(x + lo, x + hi, ref_.x.data() + lo);  // read by the force loop's fused drift
      if (keep_r) std::copy(rad + lo, rad + hi, ref_.r.data() + lo);
      for (int ch = 0; ch < chunks; ++ch) {
        const std::array<uint32_t, 4>& rg = tl_rng_[size_t(ch)];
        if ((rg[1] < lo || rg[0] >= hi) && (rg[3] < lo || rg[2] >= hi)) continue;  // none of the range's
        const uint64_t* const ks = tl_key_[size_t(ch)].data();
        for (size_t e = 0, m = tl_cnt_[size_t(ch)]; e < m; ++e) {
          const uint32_t i = uint32_t(ks[e] >> 32), j = uint32_t(ks[e]);
          if (i - lo < len) ++st[i];
          if (j - lo < len) {
            ++rs[j];
            dl[j] = std::min(dl[j], i);
          }
        }
      }
      uint32_t sum = 0, rsum = 0;
      for (uint32_t i = lo; i < hi; ++i) { sum += st[i]; st[i] = sum; rsum += rs[i]; rs[i] = rsum; }
      part_[2 * t] = sum;
      part_[2 * t + 1] = rsum;
#pragma omp barrier
      uint32_t off = 0, roff = 0;  // the entries of the ranges before this one
      for (size_t u = 0; u < t; ++u) { off += uint32_t(part_[2 * u]); roff += uint32_t(part_[2 * u + 1]); }
      for (uint32_t i = lo; i < hi; ++i) {
        st[i] += off;
        rs[i] += roff;
      }
#pragma omp single
      {
        uint64_t total = 0;
        for (size_t u = 0; u < nt; ++u) total += part_[2 * u];
        np = size_t(total);
        reserve_headroom(jdx, np);
        reserve_headroom(image, np);
        reserve_headroom(rpair, np);
        jdx.resize(np);
        image.resize(np);
        rpair.resize(np);
      }  // implicit barrier: the lists' storage is there for every thread
      uint32_t* const fill = fill_.data();
      uint32_t* const jd = jdx.data();
      uint8_t* const im = image.data();
      for (uint32_t i = lo; i < hi; ++i) fill[i] = i == lo ? off : st[i - 1];
      for (int ch = 0; ch < chunks; ++ch) {
        if (tl_rng_[size_t(ch)][1] < lo || tl_rng_[size_t(ch)][0] >= hi) continue;  // no row of the range
        const uint64_t* const ks = tl_key_[size_t(ch)].data();
        const uint8_t* const ims = tl_img_[size_t(ch)].data();
        for (size_t e = 0, m = tl_cnt_[size_t(ch)]; e < m; ++e) {
          const uint32_t i = uint32_t(ks[e] >> 32);
          if (i - lo < len) {
            const uint32_t k = fill[i]++;
            jd[k] = uint32_t(ks[e]);
            im[k] = ims[e];
          }
        }
      }
#pragma omp barrier
      // Transposed: the pairs of the range's particles lie in rows from the lowest dep_lo of
      // the range on (each row below its partners), scanned in list order.
      uint32_t first = hi;
      for (uint32_t i = lo; i < hi; ++i) {
        fill[i] = i == lo ? roff : rs[i - 1];
        first = std::min(first, dl[i]);
      }
      uint32_t* const rp = rpair.data();
      for (uint32_t k = first < hi ? (first == 0 ? 0 : st[first - 1]) : 0, k1 = first < hi ? st[hi - 1] : 0; k < k1; ++k) {
        const uint32_t j = jd[k];
        if (j - lo < len) rp[fill[j]++] = k;
      }
    }
  }

  // 5. Wall candidates. Bounded walls are tested with their bounds widened by the largest
  //    cutoff, so an approaching particle is listed before it reaches an edge.
  wide_.assign(walls.begin(), walls.end());
  {
    const double m = rmax + skin + reach;
    for (Wall& w : wide_) { w.rmin = std::max(0.0, w.rmin - m); w.rmax += m; w.zmin -= m; w.zmax += m; }
  }
  //    Several threads: each tests an equal range of the particles into a buffer of its
  //    own, then places it after the ranges before it (the 10^6 gas's floor, tested on one
  //    thread, took 4.1-4.2 ms of a 57 ms two-thread build, 3.1-3.2 ms on two: a plane's test
  //    is bound by the memory it reads; seventy-first round).
  wstart.resize(n + 1);
  wstart[0] = 0;
  wall.clear();
  // The walls within reach of particle i, in wall order, each handed to put.
  auto walls_of = [&](const size_t i, auto&& put) {
    if (flag[i] != kFree) return;
    for (size_t w = 0; w < wide_.size(); ++w) {
      Vec3 nn;
      double delta;
      if (wide_[w].contact(x[i], rad[i], nn, delta) && delta > -(skin + reach)) put(uint16_t(w));
    }
  };
  if (wide_.empty()) {
    std::fill(wstart.begin(), wstart.end(), 0u);
  } else if (nthreads == 1) {
    for (size_t i = 0; i < n; ++i) {
      walls_of(i, [&](const uint16_t w) { wall.push_back(w); });
      wstart[i + 1] = uint32_t(wall.size());
    }
  } else {
    if (wl_buf_.size() < size_t(nthreads)) wl_buf_.resize(size_t(nthreads));
    part_.assign(size_t(nthreads) + 1, 0);
#pragma omp parallel num_threads(nthreads)
    {
      const size_t nt = size_t(omp_get_num_threads()), t = size_t(omp_get_thread_num());
      const size_t lo = n * t / nt, hi = n * (t + 1) / nt;
      std::vector<uint16_t> buf;  // the thread's own header (see the pair search's buffers)
      buf.swap(wl_buf_[t]);
      buf.clear();
      for (size_t i = lo; i < hi; ++i) {
        walls_of(i, [&](const uint16_t w) { buf.push_back(w); });
        wstart[i + 1] = uint32_t(buf.size());  // within the range, for now
      }
      part_[t + 1] = buf.size();
#pragma omp barrier
#pragma omp single
      {
        for (size_t u = 1; u <= nt; ++u) part_[u] += part_[u - 1];
        wall.resize(part_[nt]);
      }  // implicit barrier
      const uint32_t off = uint32_t(part_[t]);
      for (size_t i = lo; i < hi; ++i) wstart[i + 1] += off;
      std::copy(buf.begin(), buf.end(), wall.begin() + std::ptrdiff_t(off));
      buf.swap(wl_buf_[t]);
    }
  }

  // 6. Carry history over, from each live contact of the old lists to its entry in the new
  //    ones (contacts are a fraction of the entries: a chute's 0.5 per particle against 3.5
  //    list entries, a gas's 0.1 against 3). The old pair (io, jo) is found again by its
  //    particles' ids, which map to new indices through a table (direct while ids are dense,
  //    as they are when the System numbers them; sorted otherwise); it now lies in the row of
  //    the lower new index. When that is the other particle (a re-sort swapped the two), the
  //    history is rewritten as seen from it (hist.flip). Wall contacts keep their particle's
  //    row and their wall.
  //    Each pair is held by one old row, so the old rows can be shared among the threads:
  //    every new entry is written by the one old entry of its pair (two entries of one pair,
  //    under two periodic images in a box of one or two cells, are matched in order by the
  //    same thread), the same on any number of threads.
  reserve_headroom(hist.data, np * hist.stride);
  reserve_headroom(hist.live, np);
  reserve_headroom(whist.data, wall.size() * whist.stride);
  reserve_headroom(whist.live, wall.size());
  hist.data.resize(np * hist.stride);
  hist.live.resize(np);
  whist.data.assign(wall.size() * whist.stride, std::byte{0});
  whist.live.assign(wall.size(), 0);
  {  // zeroed by the threads, a block each (megabytes on a large bed)
    std::byte* const hd = hist.data.data();
    uint8_t* const hl = hist.live.data();
    const size_t st = hist.stride;
#pragma omp parallel if (long(n) > parallel_min)
    {
      const size_t nt = size_t(omp_get_num_threads()), t = size_t(omp_get_thread_num());
      const size_t k0 = np * t / nt, k1 = np * (t + 1) / nt;
      std::memset(hd + k0 * st, 0, (k1 - k0) * st);
      std::memset(hl + k0, 0, k1 - k0);
    }
  }
  // The old live flags are 0 or 1: summed in 32-bit lanes (a list holds fewer than 2^32 entries).
  auto count_live = [](const std::vector<uint8_t>& f) {
    uint32_t c = 0;
    const uint8_t* const q = f.data();
#pragma omp simd reduction(+ : c)
    for (size_t k = 0; k < f.size(); ++k) c += q[k];
    return uint64_t(c);
  };
  const uint64_t old_live = old_jdx_.size(), old_wlive = count_live(old_wlive_);
  if (old_live + old_wlive > 0) {
    // The particles as they were at the last build, in the same order (no re-sort, insertion
    // or removal since): every old index is its particle's new index, and no lookup is made
    // (the case of most builds: a re-sort comes every sort_every builds).
    const bool same = old_n == n && std::equal(old_ids_.begin(), old_ids_.end(), id);
    uint64_t max_id = 0;
    if (!same)
      for (size_t i = 0; i < n; ++i) max_id = std::max(max_id, id[i]);
    const bool dense = !same && max_id < 8 * uint64_t(old_n + n) + 1024;
    std::vector<std::pair<uint64_t, uint32_t>> sorted;  // only for sparse ids
    if (dense) {
      if (new_of_id_.size() < max_id + 1) new_of_id_.resize(max_id + 1, UINT32_MAX);
      for (size_t i = 0; i < n; ++i) new_of_id_[id[i]] = uint32_t(i);
    } else if (!same) {
      sorted.reserve(n);
      for (size_t i = 0; i < n; ++i) sorted.push_back({id[i], uint32_t(i)});
      std::sort(sorted.begin(), sorted.end());
    }
    auto new_index = [&](uint64_t pid) -> uint32_t {
      if (pid == UINT64_MAX) return UINT32_MAX;
      if (dense) return pid <= max_id ? new_of_id_[pid] : UINT32_MAX;
      auto it = std::lower_bound(sorted.begin(), sorted.end(), std::pair<uint64_t, uint32_t>{pid, 0});
      return it != sorted.end() && it->first == pid ? it->second : UINT32_MAX;
    };
    uint64_t found = 0, wfound = 0, flipped = 0;
    const size_t hs = hist.stride, ws = whist.stride;
#pragma omp parallel for reduction(+ : found, wfound, flipped) schedule(static) if (long(old_n) > parallel_min)
    for (size_t io = 0; io < old_n; ++io) {
      const uint32_t a = same ? uint32_t(io) : new_index(old_ids_[io]);
      if (a == UINT32_MAX) continue;
      for (uint32_t kk = old_start_[io]; kk < old_start_[io + 1]; ++kk) {  // its live contacts
        const uint32_t b = same ? old_jdx_[kk] : new_index(old_ids_[old_jdx_[kk]]);
        if (b == UINT32_MAX) continue;
        const bool swapped = b < a;  // now in the row of the old partner: seen from it
        const uint32_t row = swapped ? b : a, other = swapped ? a : b;
        for (uint32_t k = start[row]; k < start[row + 1]; ++k)
          if (jdx[k] == other && !hist.live[k]) {
            std::byte* const rec = hist.data.data() + size_t(k) * hs;
            std::memcpy(rec, old_hist_.data() + size_t(kk) * hs, hs);
            if (swapped) {
              if (hist.flip) hist.flip(rec);
              ++flipped;
            }
            hist.live[k] = 1;
            ++found;
            break;
          }
      }
      if (old_wlive > 0)
        for (uint32_t ee = old_wstart_[io]; ee < old_wstart_[io + 1]; ++ee) {
          if (!old_wlive_[ee]) continue;
          for (uint32_t e = wstart[a]; e < wstart[a + 1]; ++e)
            if (wall[e] == old_wall_[ee] && !whist.live[e]) {
              std::memcpy(whist.data.data() + size_t(e) * ws, old_whist_.data() + size_t(ee) * ws, ws);
              whist.live[e] = 1;
              ++wfound;
              break;
            }
        }
    }
    stats.lost_contacts += (old_live - std::min(old_live, found)) + (old_wlive - std::min(old_wlive, wfound));
    stats.flipped += flipped;
    if (dense)
      for (size_t i = 0; i < n; ++i) new_of_id_[id[i]] = UINT32_MAX;
  }
  ids_.assign(p.id.begin(), p.id.end());

  // 7. Reference state for the rebuild trigger.
  // (ref_.x and ref_.r were copied with the rows, above: positions and radii have not
  // changed since the wrap.)
  ref_.wall.resize(walls.size());
  for (size_t w = 0; w < walls.size(); ++w) ref_.wall[w] = walls[w].point;
  // The drift from the build's positions; the origin's storage kept for the checks, with its
  // length (recheck fills it on all threads, where a resize would first zero it on one).
  if (!ref_.from.empty()) from_spare_.swap(ref_.from);
  ref_.from.clear();
  ref_.carried_pair = 0;
  ref_.carried_wall.clear();
  origin_ = ref_.x.data();
  periodic_ = dom.periodic;
  skin_ = skin;
  range_ = 2 * rmax + reach;
  reach_ = reach;
  ++stats.builds;
  ++epoch;
}

void NeighborList::keep_live_pairs(size_t old_n) {
  // CSR by old row over the live entries only: old_start_[io] .. old_start_[io + 1] index
  // old_jdx_ (partner) and old_hist_ (record). Two passes over the rows on all threads: each
  // counts the live entries of an equal range of rows, then, offset by the ranges before it,
  // writes its rows' starts and copies their live entries.
  old_start_.resize(old_n + 1);
  old_start_[0] = 0;
  const size_t hs = hist.stride;
  const int threads = long(old_n) > parallel_min ? omp_get_max_threads() : 1;
  part_.assign(size_t(threads) + 1, 0);
#pragma omp parallel num_threads(threads) if (threads > 1)
  {
    const size_t nt = size_t(omp_get_num_threads()), t = size_t(omp_get_thread_num());
    const size_t lo = old_n * t / nt, hi = old_n * (t + 1) / nt;
    const uint32_t* const st = start.data();
    const uint8_t* const live = hist.live.data();
    uint32_t* const os = old_start_.data() + 1;
    uint32_t c = 0;
    for (size_t io = lo; io < hi; ++io) {
      for (uint32_t k = st[io]; k < st[io + 1]; ++k) c += live[k];
      os[io] = c;
    }
    part_[t + 1] = c;
#pragma omp barrier
#pragma omp single
    {
      for (size_t u = 1; u <= nt; ++u) part_[u] += part_[u - 1];
      old_jdx_.resize(part_[nt]);
      old_hist_.resize(part_[nt] * hs);
    }  // implicit barrier
    const uint32_t off = uint32_t(part_[t]);
    uint32_t w = off;
    const uint32_t* const jd = jdx.data();
    const std::byte* const hd = hist.data.data();
    for (size_t io = lo; io < hi; ++io) {
      os[io] += off;
      for (uint32_t k = st[io]; k < st[io + 1]; ++k)
        if (live[k]) {
          old_jdx_[w] = jd[k];
          std::memcpy(old_hist_.data() + size_t(w) * hs, hd + size_t(k) * hs, hs);
          ++w;
        }
    }
  }
}

void NeighborList::rebuild_at(ParticleStore& p, std::vector<Wall>& walls, const Domain& dom, double skin, double reach,
                              const Reference& ref) {
  if (ref.x.size() != p.size() || (!ref.r.empty() && ref.r.size() != p.size()) || ref.wall.size() != walls.size())
    throw RunError("neighbor list reference state does not match the particles and walls");
  // Without reference radii the radii have not changed since that build (no thermal model).
  const bool with_r = !ref.r.empty();
  std::vector<Vec3> x = ref.x, wp(walls.size());
  std::vector<double> r = with_r ? ref.r : std::vector<double>{};
  p.x.swap(x);
  if (with_r) p.radius.swap(r);
  for (size_t w = 0; w < walls.size(); ++w) { wp[w] = walls[w].point; walls[w].point = ref.wall[w]; }
  build(p, walls, dom, skin, reach, false);
  p.x.swap(x);
  if (with_r) p.radius.swap(r);
  for (size_t w = 0; w < walls.size(); ++w) walls[w].point = wp[w];
  // A thermal run's reference radii read into a run without a thermal model: kept until the
  // next build (the radii grew since that build, and the trigger must still count it).
  if (with_r && ref_.r.empty()) ref_.r = ref.r;
  // The drift origin of a local check since that build, and what it carries.
  if (!ref.from.empty()) {
    if (ref.from.size() != p.size()) throw RunError("neighbor list drift origin does not match the particles");
    ref_.from = ref.from;
    origin_ = ref_.from.data();
  }
  ref_.carried_pair = ref.carried_pair;
  if (!ref.carried_wall.empty() && ref.carried_wall.size() != walls.size())
    throw RunError("neighbor list carried wall bounds do not match the walls");
  ref_.carried_wall = ref.carried_wall;
}

bool NeighborList::needs_rebuild(const ParticleStore& p, const std::vector<Wall>& walls, double skin) const {
  if (!has_reference(p.size())) return true;
  const long n = long(p.size());
  Drift d;
  drift_pass(n, n > parallel_min, d, [&](const long i, Drift& di) { add_drift(di, p, size_t(i)); });
  return rebuild_due(d, walls, skin);
}

bool NeighborList::rebuild_due(const Drift& d, const std::vector<Wall>& walls, double skin) const {
  return rebuild_measure(d, walls) > skin;
}

double NeighborList::rebuild_measure(const Drift& d, const std::vector<Wall>& walls) const {
  // A pair can be missed only once the two particles have moved relative to each other by
  // more than the skin (less their radius growth). Their relative displacement is at most
  // twice the largest displacement, and at most the diagonal of the box that bounds all
  // displacements since the build: the smaller bound decides, so a bed moving as a whole (a
  // chute flow, a belt) rebuilds for what its particles move relative to each other, not for
  // how far it travels. Frozen particles do not move: with any, the box holds the origin.
  // Walls keep the absolute bound (a wall does not move with the bed).
  // After a local check that kept the lists (recheck), the displacements are measured from
  // its positions, and the check's bounds from the build to them are added.
  const double dmax = std::sqrt(d.dmax2);
  double rel = ref_.carried_pair;  // bound on any two particles' relative displacement
  if (d.hi.x >= d.lo.x) {  // some particle moves
    Vec3 lo = d.lo, hi = d.hi;
    if (d.frozen) {
      lo = {std::min(lo.x, 0.0), std::min(lo.y, 0.0), std::min(lo.z, 0.0)};
      hi = {std::max(hi.x, 0.0), std::max(hi.y, 0.0), std::max(hi.z, 0.0)};
    }
    rel += std::min(2 * dmax, norm(hi - lo));
  }
  // A NaN bound (a particle gone NaN, which the run reports elsewhere) decides nothing, as
  // a comparison with the skin it fails: the others decide.
  double m = rel + 2 * d.grow;
  for (size_t w = 0; w < walls.size(); ++w) {
    const double c = w < ref_.carried_wall.size() ? ref_.carried_wall[w] : 0.0;  // a local check's
    const double b = c + dmax + d.grow + walls[w].geometric_displacement(walls[w].point - ref_.wall[w]);
    if (b > m || m != m) m = b;
  }
  return m;
}

void NeighborList::sort_blocks(const std::array<long, 3>& nb, const std::array<double, 3>& inv, const int nt) {
  // A counting sort of the particles by the block of their position at the build, ascending
  // within a block: each thread finds the blocks of an equal range of particles (kept in
  // cell_of_, the build's scratch, free until the next build) and counts them; the counts,
  // summed block by block over the threads in order, place each thread's particles of a
  // block after those of the threads before it.
  const size_t n = ref_.x.size();
  const long nblk = nb[0] * nb[1] * nb[2];
  const Vec3* const x0 = ref_.x.data();
  const Vec3 blo = box_lo_;
  cell_of_.resize(n);
  blk_order_.resize(n);
  blk_first_.assign(size_t(nblk) + 1, 0);
  blk_count_.assign(size_t(nt) * size_t(nblk), 0);
  uint32_t* const id = cell_of_.data();
  uint32_t* const cnt = blk_count_.data();
  uint32_t* const firstb = blk_first_.data();
  uint32_t* const ord = blk_order_.data();
#pragma omp parallel num_threads(nt) if (nt > 1)
  {
    const int t = omp_get_thread_num(), tn = omp_get_num_threads();
    const size_t lo = n * size_t(t) / size_t(tn), hi = n * size_t(t + 1) / size_t(tn);
    uint32_t* const c = cnt + size_t(t) * size_t(nblk);
    // (Truncation, not std::floor: a library call in a build without SSE4.1, 3 a particle.)
    for (size_t i = lo; i < hi; ++i) {
      long k[3];
      for (int d = 0; d < 3; ++d) {
        const double u = (x0[i][d] - blo[d]) * inv[d];
        k[d] = u > 0 ? (u < double(nb[d]) ? long(u) : nb[d] - 1) : 0;  // NaN, below: 0
      }
      const uint32_t q = uint32_t((k[2] * nb[1] + k[1]) * nb[0] + k[0]);
      id[i] = q;
      ++c[q];
    }
#pragma omp barrier
#pragma omp single
    {
      // Block q's particles start after all blocks before it; within it, thread u's after
      // those of threads before u: c[u][q] becomes thread u's first place in block q.
      uint32_t at = 0;
      for (long q = 0; q < nblk; ++q) {
        firstb[q] = at;
        for (int u = 0; u < tn; ++u) {
          uint32_t& e = cnt[size_t(u) * size_t(nblk) + size_t(q)];
          const uint32_t m = e;
          e = at;
          at += m;
        }
      }
      firstb[nblk] = at;
    }  // implicit barrier
    for (size_t i = lo; i < hi; ++i) ord[c[id[i]]++] = uint32_t(i);
  }
  // The joins' neighbour tables: slab c of direction d (-1 to nb[d]) wrapped where d is
  // periodic, -1 outside a bounded direction.
  for (int d = 0; d < 3; ++d) {
    blk_wrap_[size_t(d)].resize(size_t(nb[size_t(d)]) + 2);
    for (long c = -1; c <= nb[size_t(d)]; ++c)
      blk_wrap_[size_t(d)][size_t(c + 1)] =
          c >= 0 && c < nb[size_t(d)] ? c : periodic_[size_t(d)] ? (c + nb[size_t(d)]) % nb[size_t(d)] : -1;
  }
  blk_builds_ = stats.builds;
  blk_nb_ = nb;
}

bool NeighborList::recheck(const ParticleStore& p, const std::vector<Wall>& walls, double skin) {
  const size_t n = p.size();
  if (!(local_cutoffs > 0) || tracks_radii() || !has_reference(n) || n == 0 || skin != skin_) return false;
  ++stats.checks;
  // The blocks: the build's box (periodic directions: the domain) cut into nb[d] slabs of
  // at least local_cutoffs cutoffs each, fewer where they would pass a few per particle.
  const double cut = range_ + skin;
  double edge = local_cutoffs * cut;
  std::array<long, 3> nb{};
  std::array<double, 3> inv{};
  const Vec3 ext = box_hi_ - box_lo_;
  const long cap = std::max<long>(64, long(n / 4));
  for (;;) {
    long total = 1;
    for (int d = 0; d < 3; ++d) {
      const double k = std::floor(ext[d] / edge);
      nb[d] = k >= 1 && k < 1e6 ? long(k) : 1;
      inv[d] = nb[d] > 1 ? double(nb[d]) / ext[d] : 0.0;
      total *= nb[d];
    }
    if (total <= cap) break;
    edge *= 1.25;
  }
  const long nblk = nb[0] * nb[1] * nb[2];
  constexpr size_t W = 7;  // a block's record: displacement box lo xyz, hi xyz, largest displacement
  const int nt = long(n) > parallel_min ? std::max(1, omp_get_max_threads()) : 1;
  const Vec3* const x = p.x.data();
  const Vec3* const x0 = ref_.x.data();
  // The particles by block of their positions at the build (blk_order_, blk_first_), sorted
  // once per build: a build's positions and blocks hold until the next build, and a build is
  // followed by several checks (on the LAMMPS chute about four: kept, kept, kept, failed).
  // Each check then sweeps the blocks, each on one thread, with no per-thread copies of the
  // records to set up and merge, and no block to find per particle.
  if (blk_builds_ != stats.builds || blk_order_.size() != n || blk_nb_ != nb || blk_first_.size() != size_t(nblk) + 1)
    sort_blocks(nb, inv, nt);
  const uint32_t* const order = blk_order_.data();
  const uint32_t* const first = blk_first_.data();
  blk_rec_.resize(size_t(nblk) * W);
  double* const B = blk_rec_.data();
  // Each block's displacements since the build (frozen particles add zero: the origin is in
  // their block's box), its largest one, and the global bounds (as rebuild_measure's), on
  // the threads by equal counts of particles. Min and max: exact, the same bits in any order.
  Vec3 glo{INFINITY, INFINITY, INFINITY}, ghi{-INFINITY, -INFINITY, -INFINITY};
  double gd2 = 0;
  std::vector<double>& part = blk_part_;
  part.assign(size_t(nt) * W, 0.0);
#pragma omp parallel num_threads(nt) if (nt > 1)
  {
    const int t = omp_get_thread_num(), tn = omp_get_num_threads();
    // This thread's blocks: those whose first particle is in its equal share of them.
    auto block_at = [&](const size_t cut) {
      return long(std::lower_bound(first, first + nblk, uint32_t(cut)) - first);
    };
    const long q0 = t == 0 ? 0 : block_at(n * size_t(t) / size_t(tn));
    const long q1 = t + 1 == tn ? nblk : block_at(n * size_t(t + 1) / size_t(tn));
    double l0 = INFINITY, l1 = INFINITY, l2 = INFINITY, h0 = -INFINITY, h1 = -INFINITY, h2 = -INFINITY, m2 = 0;
    constexpr uint32_t kPassAhead = 16;
    const uint32_t last = uint32_t(n - 1);
    for (long q = q0; q < q1; ++q) {
      double a0 = INFINITY, a1 = INFINITY, a2 = INFINITY, a3 = -INFINITY, a4 = -INFINITY, a5 = -INFINITY, a6 = 0;
      for (uint32_t k = first[q]; k < first[q + 1]; ++k) {
        // The particles of a block lie in a few short runs of the particle order, mostly
        // not in cache at a check (the build's positions are not read between checks): the
        // lines kPassAhead particles ahead asked for, so that their misses overlap.
        const uint32_t ia = order[std::min(k + kPassAhead, last)];
        __builtin_prefetch(x + ia);
        __builtin_prefetch(x0 + ia);
        const uint32_t i = order[k];
        const Vec3 dx = x[i] - x0[i];
        a0 = std::min(a0, dx.x); a1 = std::min(a1, dx.y); a2 = std::min(a2, dx.z);
        a3 = std::max(a3, dx.x); a4 = std::max(a4, dx.y); a5 = std::max(a5, dx.z);
        a6 = std::max(a6, norm2(dx));
      }
      double* const r = B + size_t(q) * W;
      r[0] = a0; r[1] = a1; r[2] = a2; r[3] = a3; r[4] = a4; r[5] = a5;
      r[6] = std::sqrt(a6);  // the block's largest displacement
      l0 = std::min(l0, a0); l1 = std::min(l1, a1); l2 = std::min(l2, a2);
      h0 = std::max(h0, a3); h1 = std::max(h1, a4); h2 = std::max(h2, a5);
      m2 = std::max(m2, a6);
    }
    double* const o = part.data() + size_t(t) * W;
    o[0] = l0; o[1] = l1; o[2] = l2; o[3] = h0; o[4] = h1; o[5] = h2; o[6] = m2;
    if (t == 0)
      for (int u = tn; u < nt; ++u) {  // a team smaller than asked: the other parts empty
        double* const e = part.data() + size_t(u) * W;
        e[0] = e[1] = e[2] = INFINITY;
        e[3] = e[4] = e[5] = -INFINITY;
      }
  }
  for (int t = 0; t < nt; ++t) {
    const double* const o = part.data() + size_t(t) * W;
    glo = {std::min(glo.x, o[0]), std::min(glo.y, o[1]), std::min(glo.z, o[2])};
    ghi = {std::max(ghi.x, o[3]), std::max(ghi.y, o[4]), std::max(ghi.z, o[5])};
    gd2 = std::max(gd2, o[6]);
  }
  const double move = std::sqrt(gd2), global = std::min(2 * move, norm(ghi - glo));
  // Each pair of neighbours once: a block with itself and the 13 ahead of it (in periodic
  // directions of one or two blocks, some of them the same block or the same pair again),
  // by rows of blocks along x, the neighbours' rows and columns looked up in tables that
  // wrap the periodic directions (-1: outside a bounded one). Squares compared, one square
  // root at the end. Once a bound passes what a kept check allows, the check fails whatever
  // the rest (the global bound is at least the local one, so the carried bound would pass
  // it too): every thread skips its remaining rows (a gas's failed check at 10^6 particles:
  // the joins were a quarter of it; on two threads, the one that found it tells the other).
  const double lim2 = (kRecheckRoom * skin) * (kRecheckRoom * skin);
  const long* const w0 = blk_wrap_[0].data() + 1;  // (sort_blocks: the build's blocks)
  const long* const w1 = blk_wrap_[1].data() + 1;
  const long* const w2 = blk_wrap_[2].data() + 1;
  const long nrow = nb[1] * nb[2];
  std::atomic<bool> failed{false};
  double local2 = 0;
#pragma omp parallel for schedule(static) num_threads(nt) if (nt > 1) reduction(max : local2)
  for (long row = 0; row < nrow; ++row) {
    if (failed.load(std::memory_order_relaxed)) continue;  // the check failed already
    const long k1 = row % nb[1], k2 = row / nb[1];
    for (long k0 = 0; k0 < nb[0]; ++k0) {
      const double* const a = B + size_t(row * nb[0] + k0) * W;
      if (!(a[3] >= a[0])) continue;  // empty
      const double da = a[6];
      for (int o2 = 0; o2 <= 1; ++o2) {
        const long c2 = w2[k2 + o2];
        if (c2 < 0) continue;
        for (int o1 = o2 ? -1 : 0; o1 <= 1; ++o1) {
          const long c1 = w1[k1 + o1];
          if (c1 < 0) continue;
          const double* const er = B + size_t((c2 * nb[1] + c1) * nb[0]) * W;
          for (int o0 = (o2 || o1) ? -1 : 0; o0 <= 1; ++o0) {
            const long c0 = w0[k0 + o0];
            if (c0 < 0) continue;
            const double* const e = er + size_t(c0) * W;
            if (!(e[3] >= e[0])) continue;
            const Vec3 jl{std::min(a[0], e[0]), std::min(a[1], e[1]), std::min(a[2], e[2])};
            const Vec3 jh{std::max(a[3], e[3]), std::max(a[4], e[4]), std::max(a[5], e[5])};
            const double sum = da + e[6];
            local2 = std::max(local2, std::min(norm2(jh - jl), sum * sum));
          }
        }
      }
    }
    if (local2 > lim2) failed.store(true, std::memory_order_relaxed);
  }
  const double local = std::sqrt(local2);
  // Particles in blocks that are not neighbours (two or more slabs apart in some direction
  // that has three or more) were more than a block's edge apart at the build (less a
  // rounding allowance): they stay out of range while their relative displacement stays
  // below `far`. Carried forward: the smaller of the global bound and the bound that keeps
  // both the neighbours within the skin and the others within `far`.
  const double span = std::max({std::fabs(box_lo_.x), std::fabs(box_lo_.y), std::fabs(box_lo_.z),
                                std::fabs(box_hi_.x), std::fabs(box_hi_.y), std::fabs(box_hi_.z)});
  const double far = edge * (1 - 1e-9) - 1e-12 * span - range_;
  const double pair = std::min(global, std::max(local, global - (far - skin)));
  if (!(pair <= kRecheckRoom * skin)) return false;  // (the walls' pass not needed)
  // Walls: over the free particles not listed with a wall (others have no wall entries),
  // the largest displacement less the particle's room, its gap to the wall at the build
  // (the build's widened wall) beyond the skin and reach; outside a bounded wall's widened
  // bounds the room is 0 (the global rule: it cannot reach the wall within a skin).
  const size_t nw = walls.size();
  if (nw != ref_.wall.size() || nw != wide_.size()) return false;
  wall_room_.assign(nw, -INFINITY);
  if (nw > 0) {
    double* const wr = wall_room_.data();
    const double* const rad = p.radius.data();
    const uint8_t* const flag = p.flag.data();
#pragma omp parallel for schedule(static) num_threads(nt) if (nt > 1) reduction(max : wr[:nw])
    for (size_t i = 0; i < n; ++i) {
      if (flag[i] != kFree) continue;
      const double dm = norm(x[i] - x0[i]);
      for (size_t w = 0; w < nw; ++w) {
        bool listed = false;
        for (uint32_t k = wstart[i]; k < wstart[i + 1]; ++k) listed = listed || wall[k] == w;
        if (listed) continue;
        Vec3 nn;
        double delta;
        const double room = wide_[w].contact(x0[i], rad[i], nn, delta) ? std::max(0.0, -delta - skin - reach_) : 0.0;
        wr[w] = std::max(wr[w], dm - room);
      }
    }
  }
  double m = pair;
  for (size_t w = 0; w < nw; ++w)
    m = std::max(m, wall_room_[w] + walls[w].geometric_displacement(walls[w].point - ref_.wall[w]));
  if (!(m <= kRecheckRoom * skin)) return false;
  // The lists hold: the drift from here on, the check's bounds carried.
  // (After a build `from` is empty and the storage of the origin before it is in
  // from_spare_, of the same length where the particles are the same: taken back and filled
  // on all threads. Otherwise one copy, where a resize would first write zeros over it on
  // one thread.)
  if (ref_.from.size() != n && from_spare_.size() == n) ref_.from.swap(from_spare_);
  if (ref_.from.size() != n) {
    ref_.from.assign(p.x.begin(), p.x.end());
  } else {
    Vec3* const from = ref_.from.data();
#pragma omp parallel for schedule(static) num_threads(nt) if (nt > 1)
    for (size_t i = 0; i < n; ++i) from[i] = x[i];
  }
  origin_ = ref_.from.data();
  ref_.carried_pair = pair;
  ref_.carried_wall = wall_room_;
  ++stats.deferred;
  ++epoch;
  return true;
}

size_t NeighborList::live_contacts() const {
  // Every series row and progress line counts them (at 10^6 particles about 7 million
  // entries): on the threads where the lists are long, an exact integer sum either way.
  auto count = [this](const std::vector<uint8_t>& live) {
    const long n = long(live.size());
    const uint8_t* const l = live.data();
    size_t c = 0;
    if (n > 8 * parallel_min) {  // entries: about 8 a particle where it matters
#pragma omp parallel for schedule(static) reduction(+ : c)
      for (long k = 0; k < n; ++k) c += l[k];
    } else {
      for (long k = 0; k < n; ++k) c += l[k];
    }
    return c;
  };
  return count(hist.live) + count(whist.live);
}

}  // namespace cohdem
