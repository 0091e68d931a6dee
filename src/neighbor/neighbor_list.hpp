// Half neighbor list with a Verlet skin, built by cell binning, plus the wall-contact
// candidates, and the contact history that rides on both.
//
// - Cells are at least (2 r_max + skin + reach) wide, so any size ratio is handled (each
//   pair is tested against its own cutoff r_i + r_j + skin + reach). The search is a half
//   stencil: a particle tests the rest of its own cell and the 13 cells ahead of it, so each
//   pair (under each periodic image) is found once, whatever the particles' order.
// - Each pair is stored once, in the row of the particle with the LOWER index (i < j): every
//   pair of particle q lies in rows up to q's own, so the force loop can finish q (sum its
//   forces, kick, drift) as soon as its own row is done, whatever the particles' ids. The
//   history (tangential spring, plastic overlap, ...) is kept as seen from i.
// - Rows are CSR by i; a transposed index lets the force gather run per particle in a fixed
//   order, so results do not depend on the number of threads.
// - History is kept for live contacts only and carried over at each rebuild by matching
//   (id_i, id_j): the old row of whichever of the two had the lower index is scanned for the
//   other (ids map to old rows through a table), so it survives rebuilds, re-sorting and
//   (later) MPI migration. When a re-sort has swapped the two's order, the history is
//   rewritten as seen from the other side (HistoryArray::flip, the contact law's). Wall
//   contacts are keyed by (particle id, wall index).
// - Periodic images: positions are wrapped at rebuilds only; each pair stores the image
//   code of j so distances need no minimum-image test in the force loop.
#pragma once
#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "core/vec3.hpp"
#include "particles/particle_store.hpp"
#include "walls/wall.hpp"

namespace cohdem {

struct Domain {
  Vec3 lo, hi;  ///< box bounds, m (required in periodic directions)
  std::array<bool, 3> periodic{false, false, false};
  Vec3 length() const { return hi - lo; }
};

/// Image shifts: code = (sx+1)*9 + (sy+1)*3 + (sz+1), shift = (sx Lx, sy Ly, sz Lz).
constexpr uint8_t kNoImage = 13;

struct HistoryArray {
  size_t stride = 0;              ///< bytes per contact (ContactModel::state_size)
  std::vector<std::byte> data;    ///< one slot per list entry
  std::vector<uint8_t> live;      ///< 1 while the contact exists
  /// Rewrites one record as seen from the other particle (ContactModel::flipper; null: the
  /// records read the same from either side, as the tests' plain bytes do).
  void (*flip)(void*) = nullptr;
  void resize(size_t n) { data.assign(n * stride, std::byte{0}); live.assign(n, 0); }
  void* at(size_t k) { return data.data() + k * stride; }
};

/// Displacements and radius growth of the particles since the last build, reduced over the
/// particles (min and max only: exact, so the rebuild decision is the same on any number of
/// threads). Filled by NeighborList::needs_rebuild, or by the integrator in the pass that
/// moves the particles (System::step_once), and judged by NeighborList::rebuild_due.
struct Drift {
  static constexpr double kInf = std::numeric_limits<double>::infinity();
  double dmax2 = 0;  ///< largest squared displacement, m^2
  double grow = 0;   ///< largest radius growth, m
  Vec3 lo{kInf, kInf, kInf}, hi{-kInf, -kInf, -kInf};  ///< bounding box of the displacements
  bool frozen = false;  ///< some particle is frozen (does not move: the origin is in the box)
  /// A particle that can move, displaced by d, its radius grown by dr.
  COHDEM_INLINE void add(const Vec3& d, double dr) {
    add(d);
    grow = std::max(grow, dr);
  }
  /// The same for a particle whose radius is as at the list build.
  COHDEM_INLINE void add(const Vec3& d) {
    dmax2 = std::max(dmax2, norm2(d));
    lo.x = std::min(lo.x, d.x); lo.y = std::min(lo.y, d.y); lo.z = std::min(lo.z, d.z);
    hi.x = std::max(hi.x, d.x); hi.y = std::max(hi.y, d.y); hi.z = std::max(hi.z, d.z);
  }
  void merge(const Drift& o) {
    dmax2 = std::max(dmax2, o.dmax2);
    grow = std::max(grow, o.grow);
    lo = {std::min(lo.x, o.lo.x), std::min(lo.y, o.lo.y), std::min(lo.z, o.lo.z)};
    hi = {std::max(hi.x, o.hi.x), std::max(hi.y, o.hi.y), std::max(hi.z, o.hi.z)};
    frozen = frozen || o.frozen;
  }
};
#pragma omp declare reduction(drift : cohdem::Drift : omp_out.merge(omp_in)) initializer(omp_priv = cohdem::Drift{})

/// f(i, d) for i in [0, n), each adding its displacement to the Drift d, all merged into
/// `drift`: on all threads when `parallel`, else without entering an OpenMP construct (a
/// region of one thread still sets up a team and ends with a futex wake-up, a system call:
/// about a tenth of a small system's step on the development VM). The merge is exact (max,
/// min, or), so both forms give the same bits.
template <class F>
void drift_pass(long n, bool parallel, Drift& drift, F&& f) {
  if (parallel) {
#pragma omp parallel for reduction(drift : drift) schedule(static)
    for (long i = 0; i < n; ++i) f(i, drift);
  } else {
    for (long i = 0; i < n; ++i) f(i, drift);
  }
}

struct NeighborStats {
  uint64_t builds = 0;
  uint64_t lost_contacts = 0;  ///< live contacts whose pair left the list (should stay 0)
  uint64_t flipped = 0;        ///< histories carried over from the other particle's row (re-sorts)
  uint64_t checks = 0;         ///< local checks run where the global trigger fired (NeighborList::recheck)
  uint64_t deferred = 0;       ///< of them, those that found the lists still good (no build then)
};

/// Image code of a partner seen in place: shift[kNoShift] is (+0, +0, +0).
inline constexpr uint8_t kNoShift = 13;

class NeighborList {
 public:
  // Pair rows (CSR by i, i has the lower index).
  std::vector<uint32_t> start;   ///< n+1 offsets
  std::vector<uint32_t> jdx;     ///< partner j
  std::vector<uint8_t> image;    ///< image code of j
  std::vector<uint32_t> rstart;  ///< transposed: n+1 offsets
  std::vector<uint32_t> rpair;   ///< pair indices where the particle is j
  /// Lowest row (i) holding a pair of the particle, itself included. With each pair in the
  /// row of its lower index, the particle's own row is the highest: the force kernel
  /// finishes a particle once rows dep_lo..itself are done.
  std::vector<uint32_t> dep_lo;
  HistoryArray hist;

  // Wall candidates (CSR by particle).
  std::vector<uint32_t> wstart;
  std::vector<uint16_t> wall;
  HistoryArray whist;

  /// Particles attached to walls (kAttached) at the build, ascending: after a fused step
  /// (System::step_once(true)) only they are left for the particle pass, which then skips
  /// the others without reading their flags (and without a parallel region when none is).
  std::vector<uint32_t> attached;
  /// The species every particle had at the build, or -1 when they differ (or there are
  /// none): with one, every pair's material parameters are the same, and the force loop
  /// reads no species (species change only with a rebuild: adding or removing particles).
  int32_t one_species = -1;

  std::array<Vec3, 27> shift{};  ///< image translations, code (sx+1)*9 + (sy+1)*3 + (sz+1)
  NeighborStats stats;
  long parallel_min = 0;  ///< loops run on one thread below this many particles (SimConfig)

  /// Rebuilds the lists: wraps periodic positions, optionally re-sorts particles by cell
  /// (applied to `p`), bins, finds pairs within r_i + r_j + skin + reach, finds wall
  /// candidates, carries history over, and records the reference positions.
  void build(ParticleStore& p, const std::vector<Wall>& walls, const Domain& dom, double skin,
             double reach, bool resort);

  /// True when some particle or wall moved (or grew) far enough that a pair may be missed:
  /// two particles relative to each other (bounded by twice the largest displacement and by
  /// the diagonal of the displacements' bounding box, so a bed moving as a whole does not
  /// rebuild for that), or a particle relative to a wall.
  bool needs_rebuild(const ParticleStore& p, const std::vector<Wall>& walls, double skin) const;
  /// The same decision from displacements reduced elsewhere (Drift, over every particle, from
  /// the reference below); walls are judged here. Needs has_reference(n).
  bool rebuild_due(const Drift& d, const std::vector<Wall>& walls, double skin) const;
  /// What rebuild_due compares with the skin: the largest of the bound on two particles'
  /// relative displacement (plus their radius growth) and each wall's bound, m; a rebuild is
  /// due exactly when it exceeds the skin (System::step_sweep forecasts it the sweep's steps ahead).
  double rebuild_measure(const Drift& d, const std::vector<Wall>& walls) const;
  /// Whether the lists were built for n particles (otherwise they must be rebuilt).
  bool has_reference(size_t n) const { return ref_.x.size() == n; }
  /// Where the trigger fires, a finer test (a local check) before a build: the particles
  /// binned into blocks of at least `local_cutoffs` interaction cutoffs (2 r_max + skin +
  /// reach) by their positions at the build; for each two neighbouring blocks, the bound on
  /// the relative displacement of their particles (the diagonal of their displacements'
  /// joint box, or the sum of their largest displacements); particles in blocks that are not
  /// neighbours were more than a block's edge apart at the build, and need only the global
  /// bound to stay below that edge less the contact range. A sheared bed many blocks deep
  /// (a chute) moves its neighbours nearly alike while its top and base part by the whole
  /// flow: the lists hold far longer than the global bound says (a bed a few particles high
  /// across its shear, a ring shear cell's, spans too few blocks). Where the check finds the
  /// lists good (with kRecheckRoom of the skin to spare), the drift is measured from the
  /// present positions on (the drift origin) and the check's bounds are carried (added to
  /// the trigger's), so the per-step cost stays one reduction; the trigger fires again when
  /// carried plus new displacement reach the skin, and the check runs again from the build's
  /// positions. Walls the same way: a particle not listed with a wall at the build was
  /// further from it than the skin and reach, by a room of its own; only the particles that
  /// moved more than their room count against the skin (the bed far from a base, a lid).
  /// Not where radii change between builds (tracks_radii) or local_cutoffs <= 0.
  /// Returns whether the lists may be kept (no build needed); exact reductions: the same
  /// decision on any number of threads.
  bool recheck(const ParticleStore& p, const std::vector<Wall>& walls, double skin);
  /// Block edge of the local check, in interaction cutoffs (SimConfig::local_rebuild; 0: off).
  double local_cutoffs = 2;
  /// A check keeps the lists only where its bounds leave this fraction of the skin at most
  /// used: at the edge, checks would follow each other every few steps.
  static constexpr double kRecheckRoom = 0.75;
  /// Changes at each build and each local check that keeps the lists (the drift origin
  /// moved): displacements reduced before it are not comparable with those after.
  uint64_t epoch = 0;
  /// The positions the displacements of the trigger are measured from: the build's, or the
  /// last local check's that kept the lists (recheck).
  const Vec3* drift_origin() const { return origin_; }
  /// Adds particle i's displacement and radius growth since the build to d (a frozen
  /// particle only marks d.frozen). Needs has_reference(p.size()).
  COHDEM_INLINE void add_drift(Drift& d, const ParticleStore& p, size_t i) const {
    if (p.flag[i] == kFrozen)
      d.frozen = true;
    else
      add_moved(d, i, p.x[i], p.radius[i]);
  }
  /// The same for particle i, which can move, now at x with radius r (the force loop's fused
  /// drift passes its fresh values).
  COHDEM_INLINE void add_moved(Drift& d, size_t i, const Vec3& x, double r) const {
    if (ref_.r.empty())
      d.add(x - origin_[i]);  // radii unchanged since the build (tracks_radii)
    else
      d.add(x - origin_[i], r - ref_.r[i]);  // radius growth since the build
  }
  /// Whether the lists keep the radii they were built with: only when radii can have changed
  /// since (a thermal model's expansion, or a thermal run's checkpoint read into a run
  /// without one, until its next build). Without them a particle's radius growth is 0.
  bool tracks_radii() const { return !ref_.r.empty(); }
  /// The same for a particle whose radius has not changed since the build (the force loop's
  /// fused drift: it runs only where !tracks_radii()), so its radius growth, 0, is not read.
  COHDEM_INLINE void add_moved(Drift& d, size_t i, const Vec3& x) const { d.add(x - origin_[i]); }

  /// The state the lists were last built from (positions, radii where tracks_radii(), wall
  /// points): a checkpoint saves it, and rebuild_at() rebuilds exactly the same lists from
  /// it, so a restart at any step (not only at a rebuild step) continues bit for bit.
  struct Reference {
    std::vector<Vec3> x;
    std::vector<double> r;  ///< empty where radii cannot have changed (no thermal model)
    std::vector<Vec3> wall;
    /// The drift origin where a local check moved it since the build (recheck; empty: x),
    /// and the bounds it carries, m: on two particles' relative displacement from x to
    /// `from`; and for each wall, the largest displacement from x to `from` of a particle
    /// not listed with it, less that particle's gap to it at the build beyond the skin and
    /// reach (negative where every such particle is further than it moved; empty: 0).
    std::vector<Vec3> from;
    double carried_pair = 0;
    std::vector<double> carried_wall;
  };
  const Reference& reference() const { return ref_; }
  /// Builds the lists as they were built from `ref` (particles in their current order, no
  /// re-sort), leaving positions, radii and walls as they are now, with ref's drift origin
  /// and carried bounds. Throws RunError when `ref` does not match the particle or wall count.
  void rebuild_at(ParticleStore& p, std::vector<Wall>& walls, const Domain& dom, double skin, double reach,
                  const Reference& ref);

  size_t pair_count() const { return jdx.size(); }
  size_t wall_entry_count() const { return wall.size(); }
  size_t live_contacts() const;

 private:
  Reference ref_;
  const Vec3* origin_ = nullptr;  // ref_.from where a local check set it, else ref_.x
  // The last build's settings, for the local check: the domain's periodic directions, the
  // skin, and the contact range 2 r_max + reach.
  std::array<bool, 3> periodic_{};
  double skin_ = 0, range_ = 0, reach_ = 0;
  Vec3 box_lo_, box_hi_;  // the build's bounds (periodic directions: the domain's)
  // The local check's blocks (the build's positions binned), made by sort_blocks for the
  // build blk_builds_ and the blocks blk_nb_: the particles sorted by block (blk_order_, each
  // block's first place in blk_first_; the sort's counts in blk_count_) and the joins'
  // neighbour tables (blk_wrap_); per check, each block's displacement box and largest
  // displacement (lo xyz, hi xyz, d) and per thread its blocks' global bounds.
  std::vector<uint32_t> blk_order_, blk_first_, blk_count_;
  uint64_t blk_builds_ = ~uint64_t(0);
  std::array<long, 3> blk_nb_{};
  std::vector<double> blk_rec_, blk_part_;
  std::array<std::vector<long>, 3> blk_wrap_;
  /// Sorts the particles by the local check's block of their position at the build (nb
  /// blocks a direction, inv their count per unit length; nt threads), and makes the joins'
  /// neighbour tables for those blocks.
  void sort_blocks(const std::array<long, 3>& nb, const std::array<double, 3>& inv, int nt);
  std::vector<double> wall_room_;  // the local check's per-wall bounds (carried_wall)
  std::vector<Vec3> from_spare_;  // the drift origin's storage while ref_.from is empty (build, recheck)
  // scratch reused across builds
  std::vector<uint32_t> cell_of_, cell_start_, cell_list_, fill_;
  // Several threads: the cell order cut into one part a thread (its first cells, and ncell),
  // binned, copied for the search and searched by that thread; the search's chunks (their
  // first cells, and ncell) and each part's first chunk (and the chunk count).
  std::vector<uint32_t> split_, chunk_cell_, run_first_;
  std::vector<Wall> wide_;
  std::vector<std::vector<uint64_t>> tl_key_;  // per-chunk pairs found, (lower << 32) | higher
  std::vector<std::vector<uint8_t>> tl_img_;   // their images, seen from the lower
  std::vector<size_t> tl_cnt_;                 // their counts (the buffers keep their length)
  std::vector<std::array<uint32_t, 4>> tl_rng_;  // their lowest and highest rows and partners
  std::vector<uint64_t> part_;                 // per thread range: its rows' and transposed rows' entries
  std::vector<std::vector<uint16_t>> wl_buf_;  // per thread: its range's wall entries (build step 5)
  // The previous lists during a build (pairs: their live contacts, copied; walls: swapped)
  // and the ids of their rows.
  std::vector<uint64_t> ids_, old_ids_;
  std::vector<uint32_t> old_start_, old_jdx_, old_wstart_, new_of_id_;
  std::vector<uint16_t> old_wall_;
  std::vector<std::byte> old_hist_, old_whist_;  // old_hist_: live pair contacts only
  std::vector<uint8_t> old_wlive_;
  /// Copies the live pair contacts of the current lists (old_n rows) into old_start_,
  /// old_jdx_ and old_hist_, compactly, before the lists' storage is reused by a build.
  void keep_live_pairs(size_t old_n);
};

}  // namespace cohdem
