// Everything one force evaluation reads and writes.
#pragma once
#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <utility>
#include <vector>

#include <omp.h>

#include "core/grow.hpp"
#include "neighbor/neighbor_list.hpp"
#include "particles/particle_store.hpp"
#include "walls/wall.hpp"

namespace cohdem {

/// Velocity Verlet's opening for a free particle: the half-kick v += F hm, w += T hI (hm =
/// h/m, hI = h/I) and the drift x += v dt. Written once for System::step_once's particle
/// pass and the force loop's fused opening (ForceContext::open_dt), which must stay
/// bit-identical. v and w are the caller's registers; x is written component by component:
/// a Vec3 temporary would be built on the stack and read back through a 16-byte load that
/// the store buffer cannot forward (a stall).
COHDEM_INLINE void open_free(Vec3& v, Vec3& w, Vec3& x, const Vec3& F, const Vec3& T, double hm, double hI, double dt) {
  v += F * hm;
  w += T * hI;
  x.x += v.x * dt;
  x.y += v.y * dt;
  x.z += v.z * dt;
}

/// Result of one pair entry that j receives: the force on i (j takes its opposite) and the
/// torque on j. One record, so the gather of pass 2 touches one cache line, not two.
struct PairResult {
  Vec3 f, tj;
};
/// What a slot of a pair not in contact holds (PairSlots): adding it to a gather's sums
/// changes no bit of them, whatever they hold, signed zeros included (s - (+0) = s and
/// s + (-0) = s for every s; s + (+0) would turn -0 into +0). The gather of a particle
/// whose pairs lie in consecutive slots can then sum all of them, without asking which are
/// live: the same sums as skipping the dead ones.
inline constexpr PairResult kNoPair{Vec3{0.0, 0.0, 0.0}, Vec3{-0.0, -0.0, -0.0}};

/// Where the own-row results of a particle not local to its piece are kept (it depends on
/// rows before the piece, so its sums are completed by a gather, after which its own row's
/// results are added, in list order): `count` records from `first` in the own-row buffer of
/// the thread that swept its row (PairSlots::OwnStore), each the force and torque on i of a
/// live entry (OwnResult). Local particles take their own results straight
/// into their reverse sums instead, after the pairs of the rows before (one accumulator a
/// particle: the same operations in the same order). count is 0 between force calls (the
/// finish that reads it resets it).
struct OwnAt {
  uint32_t first = 0, count = 0;
};

/// The force loop's split of n particles over nt threads without a PairSlots (whose plan()
/// splits by work): thread t sweeps [n t/nt, n (t+1)/nt).
COHDEM_INLINE long block_begin(long n, long t, long nt) { return n * t / nt; }
/// Particle q is "local" to the block [a, b) when every row that holds a pair of q lies in
/// it: rows dep_lo[q] (from the list build) to q's own, the last (each pair lies in the row
/// of its lower index). That block's thread alone scatters into q's reverse sums; the pairs
/// of the other particles are stored and gathered.
/// Where the widest reach of a row is known (`span`: q - dep_lo[q] <= span for every q,
/// PairSlots::span), a particle `span` or more rows past a is local without reading
/// dep_lo[q]: the force loop tests every contact's partner, a plane of cells ahead of the
/// row, where that load came from beyond the caches (docs/performance-history.md,
/// sixty-eighth round).
COHDEM_INLINE bool local_to_block(const uint32_t* dep_lo, uint32_t q, long a, long b,
                                  long span = std::numeric_limits<long>::max()) {
  return long(q) < b && (long(q) - a >= span || long(dep_lo[q]) >= a);
}

/// An allocator that leaves the elements a resize adds uninitialised (trivial types only
/// here): a list made as long as it can get, filled through a pointer, then cut to its
/// length, is not zero-filled first.
template <class T>
struct NoFillAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = NoFillAllocator<U>;
  };
  NoFillAllocator() = default;
  template <class U>
  NoFillAllocator(const NoFillAllocator<U>&) noexcept {}
  template <class U>
  void construct(U* p) noexcept {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... A>
  void construct(U* p, A&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<A>(args)...);
  }
};
/// A thread's particles left for another thread or for after the barrier (force loop).
using DeferList = std::vector<uint32_t, NoFillAllocator<uint32_t>>;
/// One own-row result (OwnAt): the force and the torque on i. Six plain doubles, so that
/// a buffer of them grows without a zero fill: it is sized for every entry of the rows that
/// may need it, and only their live contacts' are written (the pages never written are never
/// committed).
struct OwnResult {
  double f[3], t[3];
};
using OwnBuffer = std::vector<OwnResult, NoFillAllocator<OwnResult>>;

/// How the force loop on several threads splits the particles, and where it keeps the results
/// it stores for the gather. The blocks are contiguous ranges of particles of about equal
/// work (plan()), not of equal count: the rows differ in length and contacts (a chute's base
/// and dense bottom layers against its dilute top). Only pairs whose j is not local to the
/// sweeping thread's block (near a block boundary) are stored, each in its own slot of a
/// compact buffer, so the buffer holds those pairs rather than the whole list (48 bytes per
/// stored pair instead of per list entry). Split and map are redone when the list, the
/// thread count or the shares (below) change. Also holds, per thread, the particles left for after the kernel's
/// barrier (with or without recording).
///
/// The work model is rough (its weights are costs on one machine and one problem; wall
/// contacts are not in it, and a core shared with other work is slower), so the split is
/// corrected by measurement: the kernel times each thread's sweep of its block (measured()),
/// and every kRebalanceCalls calls (sooner after a new thread count) the blocks' shares of
/// the modelled work are set so that every thread is predicted to take the same time
/// (rebalance()). Which thread sweeps which
/// particle never changes a result (force_kernel.hpp), so the timing-driven split leaves
/// results bit-identical; it only moves where the threads meet.
struct PairSlots {
  static constexpr uint32_t kNone = ~uint32_t(0);
  /// Work of a particle, in units of one screened list entry: the particle's own share
  /// (finish, half-kicks, drift) and each contact evaluated. Rough costs on the chute (ns,
  /// one thread): about 15 per particle, 4 per entry, 60 per contact.
  static constexpr uint64_t kWorkParticle = 4, kWorkContact = 15;
  /// Force calls between rebalances: enough sweeps that the sums of their times are not
  /// ruled by one interrupted step, few enough to follow a flow whose dense region moves.
  static constexpr uint32_t kRebalanceCalls = 32;
  /// The first rebalances after a new thread count come sooner, after kFirstRebalanceCalls
  /// calls, then twice as many, up to kRebalanceCalls, and move the shares all the way to
  /// their aim: the work model's equal first split can be far off (on the development VM
  /// one block took 1.3-1.6x as long as the other in the first calls of the 10^4 and 10^6
  /// gases and the chute; where the shares settle moves with the two cores' speeds), and
  /// moving halfway every 32 calls took 160-190 calls to settle.
  static constexpr uint32_t kFirstRebalanceCalls = 8;
  /// The smallest share a block is given, as a fraction of an equal share.
  static constexpr double kMinShare = 0.25;
  std::vector<long> bound;   ///< thread t sweeps particles [bound[t], bound[t + 1])
  /// Slot of each list entry, kNone where nothing is stored. Numbered by partner, not by
  /// row (update()): the pairs of a particle whose pairs are stored (one that depends on
  /// rows outside its block) take consecutive slots, in the order of its transposed list
  /// (NeighborList::rpair), and such particles, ascending, take ascending runs; its gather
  /// then reads one run of slots, and the boundary's particles, finished in ascending
  /// order, one stream.
  std::vector<uint32_t> of;
  uint32_t count = 0;        ///< slots in use
  /// The slots hold nothing valid: a new map (which is also when fit() can move the
  /// buffer), a call that stored its results by list entry (recording), or contacts ended
  /// behind the force loop's back (System::step_sweep's undo restores an older history; a
  /// caller that hands over a fresh buffer or restores a history sets it too). The force
  /// loop then fills them with kNoPair before its sweep. From then on every pair that is
  /// picked (in contact, or live before the call) writes its slot, its result when in
  /// contact and kNoPair when not, so a slot whose pair is not in contact holds kNoPair.
  bool refill = true;
  /// Per thread, during a force evaluation: the particles of its block left for after the
  /// barrier (the kernel shares them out evenly among the threads there).
  std::vector<DeferList> deferred;
  /// What the split and the map were made for: the list build, thread and particle counts.
  uint64_t builds = ~uint64_t(0);
  long threads = 0, n = 0;
  size_t np = 0;
  bool mapped = false;  ///< `of` and `count` belong to the current split
  /// Share of the total modelled work that thread t's block gets (sums to 1; equal until
  /// the first rebalance, and again whenever the thread count changes).
  std::vector<double> share;
  /// Since the last rebalance, per thread: seconds spent sweeping its block (written by that
  /// thread only, in the kernel) and the modelled work of the blocks it swept.
  std::vector<double> busy;
  std::vector<double> swept;
  uint32_t calls = 0;      ///< force calls timed since the last rebalance
  uint32_t period = kFirstRebalanceCalls;  ///< calls from the last rebalance to the next
  bool stale = false;      ///< the shares changed: plan() splits again at its next call
  uint64_t rebalances = 0; ///< splits moved by measurement (for tests and diagnostics)
  /// Per list build: the modelled work of particles [0, i) (n + 1 entries), and the widest
  /// dependency range, max(i - dep_lo[i]), which bounds how far from a block boundary a
  /// row can hold a pair that is not local (update()).
  std::vector<uint64_t> prefix;
  long span = 0;
  /// Whether the split lets the force loop end without its barrier ("chained" finishing):
  /// every block holds at least 2 `span` rows. A particle of block t that depends on an
  /// earlier block (dep_lo below the block) then lies in block t's first `span` rows and
  /// depends on block t - 1 and on no block before it, so thread t - 1 can finish it once its
  /// own sweep is done and thread t has handed over its first `span` rows (HandOff). Set by
  /// plan().
  bool chained = false;
  /// Per thread t > 0, in a chained force call: the particles of block t that depend on
  /// block t - 1, published (release) once thread t has swept its first `span` rows, for
  /// thread t - 1 to finish (acquire). `epoch` is the call's number, so no reset is needed
  /// between calls (only equality with the current call's number is asked; never 0, which
  /// a fresh record holds). One cache line each: the flag is spun on.
  struct alignas(64) HandOff {
    std::atomic<uint32_t> epoch{0};
    const uint32_t* list = nullptr;
    size_t count = 0;
  };
  std::unique_ptr<HandOff[]> hand;
  size_t hand_n = 0;
  /// Two steps in one sweep on several threads (ForceContext::drift2): thread t first
  /// sweeps its block's tail, the last `span` rows [tail(t), bound[t + 1]), which alone hold
  /// pairs of block t + 1's particles, then the rest; each thread finishes the particles of
  /// its own block that depend on the block before (its head). The threads tell each other
  /// how far they are through a stage record each (one cache line: spun on), which holds
  /// the call's number times 4 plus the last stage reached: kTailA (the tail swept for the
  /// first step), kHeadA (the head finished for the first step). The numbers only grow, so
  /// no reset between calls. The second step's head is handed to the thread before as in a
  /// chained call (HandOff).
  static constexpr uint64_t kTailA = 1, kHeadA = 2;
  struct alignas(64) Stage {
    std::atomic<uint64_t> v{0};
  };
  std::unique_ptr<Stage[]> stage;
  size_t stage_n = 0;
  uint64_t pair_calls = 0;  ///< force calls made with two steps on several threads
  /// Per thread, in a two-step call: room for the particles its pieces leave for later,
  /// three lists of at most `span` each (the first step's head and tail, the second
  /// step's tail; force_kernel.hpp), kept from call to call.
  std::vector<DeferList> pieces;
  /// Per thread, during a force evaluation: the own-row results of the particles its sweep
  /// met that are not local to their piece (those of its block's head, and in a two-step
  /// call of its tail's first `span` rows; OwnAt), in the order they came, kept from call to
  /// call. Each thread sizes and writes its own (a cache line or more each: alignas) before
  /// the hand-off or barrier after which another thread may read it.
  struct alignas(64) OwnStore {
    OwnBuffer buf;
  };
  std::vector<OwnStore> own_rows;
  /// Per particle: where its own-row results are (OwnAt; all counts 0 between calls).
  std::vector<OwnAt> own_at;
  /// Numbers a two-step call on nt threads and makes room for it (set-up, before the
  /// parallel region; out of line).
  [[gnu::noinline]] uint64_t next_pair_call(long nt) {
    if (stage_n < size_t(nt)) {
      stage = std::make_unique<Stage[]>(size_t(nt));
      stage_n = size_t(nt);
    }
    if (pieces.size() < size_t(nt)) pieces.resize(size_t(nt));
    for (long t = 0; t < nt; ++t)
      if (pieces[size_t(t)].size() < size_t(3 * span)) pieces[size_t(t)].resize(size_t(3 * span));
    return ++pair_calls;
  }
  /// Thread t has reached stage s of call `call` (release).
  [[gnu::noinline]] void reach(long t, uint64_t call, uint64_t s) {
    std::atomic<uint64_t>& v = stage[size_t(t)].v;
    v.store(call * 4 + s, std::memory_order_release);
    v.notify_all();
  }
  /// Whether thread t has reached stage s of call `call` (acquire).
  bool reached(long t, uint64_t call, uint64_t s) const {
    return stage[size_t(t)].v.load(std::memory_order_acquire) >= call * 4 + s;
  }
  /// Waits until thread t has reached stage s of call `call` (acquire): spun on, then slept
  /// on (as wait_for). Returns the seconds waited (not the block's work: measured()).
  [[gnu::noinline]] double wait_stage(long t, uint64_t call, uint64_t s) const {
    const std::atomic<uint64_t>& v = stage[size_t(t)].v;
    const uint64_t want = call * 4 + s;
    if (v.load(std::memory_order_acquire) >= want) return 0.0;
    const double t0 = omp_get_wtime();
    for (uint32_t spins = 0;; ++spins) {
      const uint64_t seen = v.load(std::memory_order_acquire);
      if (seen >= want) break;
      if (spins < kSpinsBeforeSleep) {
#if defined(__x86_64__) || defined(__i386__)
        __builtin_ia32_pause();
#endif
      } else {
        v.wait(seen, std::memory_order_acquire);
      }
    }
    return omp_get_wtime() - t0;
  }
  /// The first row of block t's tail in a two-step call: `span` rows before its end; the
  /// last block has none (nothing after it depends on it).
  long tail(long t) const {
    const long e = bound[size_t(t + 1)];
    return t + 1 == threads ? e : std::max(bound[size_t(t)], e - span);
  }
  uint32_t epoch = 0;  ///< force calls made through this PairSlots, the last one's number (wraps)
  uint64_t chained_calls = 0;  ///< of those, calls that ended without the barrier (tests)
  uint64_t serial_calls = 0;   ///< of those, calls whose blocks ran one after another (ForceContext::serial_blocks)
  /// Since the slots were made, for the run's summary (summary.json's thread_sweep): force
  /// calls timed on several threads (thread 0's measured()), and per thread the seconds of its sweeps
  /// (measured(): its block and the head it finished for the thread after it, waits left
  /// out) and the particles of its block it handed to the thread before (hand_over()).
  uint64_t timed_calls = 0;
  std::vector<double> busy_total;
  std::vector<uint64_t> handed_total;
  /// Per thread, of busy_total: the seconds it spent finishing the head handed over by the
  /// thread after it (the particles that depend on both blocks).
  std::vector<double> head_total;
  /// Per thread: the seconds of its sweep in the last force call (measured()).
  std::vector<double> last;
  /// Since the slots were made, per timed call on several threads, summed: the longest of the
  /// threads' sweeps (the call's sweeps end at the join, waits left out), and the sweep every
  /// thread would have taken had the call's work been split so that all ended together, each
  /// at the rate it swept at in that call (the blocks' modelled work over the sum of the
  /// threads' rates, block_work(t) / last[t]). longest_total - balanced_total is what the
  /// split's imbalance cost, call by call; a split made before the call, from the times of
  /// earlier calls, can only recover part of it (the cores' speeds move from call to call).
  double longest_total = 0, balanced_total = 0;
  /// Numbers a new force call and makes sure there is a hand-off record per thread (set-up,
  /// before the parallel region).
  /// At the wrap the records are cleared, so that no record keeps a number that a later
  /// call gets (a record not written for 2^32 calls, the barrier taken meanwhile).
  uint32_t next_epoch(long nt) {
    if (own_rows.size() < size_t(nt)) own_rows.resize(size_t(nt));
    if (own_at.size() < size_t(n)) own_at.resize(size_t(n));
    if (hand_n < size_t(nt)) {
      hand = std::make_unique<HandOff[]>(size_t(nt));
      hand_n = size_t(nt);
    }
    if (++epoch == 0) {
      for (size_t t = 0; t < hand_n; ++t) hand[t].epoch.store(0, std::memory_order_relaxed);
      epoch = 1;
    }
    return epoch;
  }
  /// Thread t's hand-off of its block's particles that depend on block t - 1 (the list is
  /// complete: none is added to it after this call, so its buffer stays where it is). Out of
  /// line: once per call and thread.
  [[gnu::noinline]] void hand_over(long t, const DeferList& list, uint32_t call) {
    HandOff& H = hand[size_t(t)];
    H.list = list.data();
    H.count = list.size();
    handed_total[size_t(t)] += list.size();
    H.epoch.store(call, std::memory_order_release);
    H.epoch.notify_all();  // a load, unless the thread that takes the list sleeps on it
  }
  /// Pauses spun on a hand-off before the waiting thread sleeps (some tens of microseconds).
  static constexpr uint32_t kSpinsBeforeSleep = 2000;
  /// Waits until thread t has handed over its list in call `call` (acquire). Spun on for a
  /// short while (the hand-off normally came long before), then slept on (a futex, woken by
  /// hand_over): with more threads than free cores the thread waited for may be the one that
  /// needs this core (libgomp's barrier does the same when its spin count runs out).
  [[gnu::noinline]] const HandOff& wait_for(long t, uint32_t call) const {
    const HandOff& H = hand[size_t(t)];
    for (uint32_t spins = 0;; ++spins) {
      const uint32_t seen = H.epoch.load(std::memory_order_acquire);
      if (seen == call) return H;
      if (spins < kSpinsBeforeSleep) {
#if defined(__x86_64__) || defined(__i386__)
        __builtin_ia32_pause();
#endif
      } else {
        H.epoch.wait(seen, std::memory_order_acquire);
      }
    }
  }

  /// Work of particle i: kWorkParticle, one per list entry of its row, kWorkContact per live
  /// contact (the contacts carried over at the last build).
  static uint64_t work_of(const NeighborList& nl, long i) {
    uint64_t w = kWorkParticle;
    for (uint32_t k = nl.start[i]; k < nl.start[i + 1]; ++k) w += 1 + kWorkContact * nl.hist.live[k];
    return w;
  }
  /// prefix[i] = the work of particles [0, i), work_of summed, and span. Without a loop over
  /// each row's entries: the work before row i is kWorkParticle i, one per entry before its
  /// first (start[i]) and kWorkContact per live contact before it, and the live flags
  /// before an entry are counted eight at a time (the sums of whole words, then the word
  /// that holds the entry, masked). A loop per row (0 to 8 entries, 3.5 on the chute)
  /// mispredicted its end on most rows: 0.37 ms per list build on the chute, set-up that
  /// runs on one thread while the others wait.
  void work_prefix(const NeighborList& nl, long n_) {
    prefix.assign(size_t(n_ + 1), 0);
    span = 0;
    for (long i = 0; i < n_; ++i) span = std::max(span, i - long(nl.dep_lo[size_t(i)]));
    const uint32_t* const start = nl.start.data();
    if constexpr (std::endian::native != std::endian::little) {
      for (long i = 0; i < n_; ++i) prefix[size_t(i + 1)] = prefix[size_t(i)] + work_of(nl, i);
      return;
    }
    const uint8_t* const live = nl.hist.live.data();
    const size_t nlive = nl.hist.live.size(), words = (size_t(start[n_]) + 7) / 8 + 1;
    // The flags of entries 8w .. 8w + 7 as one word (little-endian: entry 8w + b in byte b),
    // zero past the end. A flag is 0 or 1, so a word's bytes sum to at most 8 and the
    // multiply adds them without a carry between bytes.
    auto word = [&](const size_t w) {
      uint64_t x = 0;
      const size_t at = 8 * w;
      if (at + 8 <= nlive)
        std::memcpy(&x, live + at, 8);
      else if (at < nlive)
        std::memcpy(&x, live + at, nlive - at);
      return x;
    };
    auto bytes = [](const uint64_t x) { return (x * 0x0101010101010101ull) >> 56; };
    std::vector<uint32_t> before(words);  // live flags of entries [0, 8w)
    for (size_t w = 0; w + 1 < words; ++w) before[w + 1] = before[w] + uint32_t(bytes(word(w)));
    auto live_before = [&](const uint32_t k) {
      const size_t w = k / 8;
      const uint64_t mask = (uint64_t(1) << (8 * (k % 8))) - 1;  // the word's first k % 8 bytes
      return uint64_t(before[w]) + bytes(word(w) & mask);
    };
    const uint64_t live0 = live_before(start[0]);
    for (long i = 1; i <= n_; ++i)
      prefix[size_t(i)] = kWorkParticle * uint64_t(i) + (start[i] - start[0]) + kWorkContact * (live_before(start[i]) - live0);
  }
  /// Splits n particles into nt contiguous blocks, block t holding about share[t] of the
  /// total work (work_of; equal shares until measured). Which thread sweeps which particle
  /// never changes what is summed or in which order (force_kernel.hpp), so results do not
  /// depend on the split. The work is summed once per list build; a new split from new
  /// shares is a search in those sums.
  void plan(const NeighborList& nl, long n_, long nt) {
    const bool new_list = builds != nl.stats.builds || n != n_ || np != nl.pair_count();
    if (!stale && !new_list && threads == nt) return;
    if (threads != nt || share.size() != size_t(nt)) {
      share.assign(size_t(nt), 1.0 / double(nt));
      busy.assign(size_t(nt), 0.0);
      swept.assign(size_t(nt), 0.0);
      calls = 0;
      period = kFirstRebalanceCalls;
      if (busy_total.size() < size_t(nt)) {
        busy_total.resize(size_t(nt), 0.0);
        handed_total.resize(size_t(nt), 0);
        head_total.resize(size_t(nt), 0.0);
        last.resize(size_t(nt), 0.0);
      }
    }
    stale = false;
    mapped = false;
    builds = nl.stats.builds;
    threads = nt;
    n = n_;
    np = nl.pair_count();
    if (new_list || prefix.size() != size_t(n + 1)) {
      work_prefix(nl, n);
      map_all = true;
    }
    // Block t ends at the first particle where the work before it reaches the shares of
    // blocks 0..t (a running sum of the shares; the last block takes the rest).
    const double total = double(prefix[size_t(n)]);
    bound.assign(size_t(nt + 1), n);
    bound[0] = 0;
    double cum = 0;
    for (long t = 1; t < nt; ++t) {
      cum += share[size_t(t - 1)];
      const double cut = cum * total;
      // first i in [bound[t-1], n] with prefix[i] >= cut
      const auto it = std::lower_bound(prefix.begin() + bound[size_t(t - 1)], prefix.end(), cut,
                                       [](const uint64_t w, const double c) { return double(w) < c; });
      bound[size_t(t)] = std::min(n, long(it - prefix.begin()));
    }
    chained = true;
    for (long t = 0; t < nt; ++t) chained = chained && bound[size_t(t + 1)] - bound[size_t(t)] >= 2 * span;
  }
  /// Grows the result buffer to the slots in use (with headroom: set-up, out of line).
  [[gnu::noinline]] void fit(std::vector<PairResult>& pair) const { grow_to(pair, count); }
  /// Modelled work of block t of the current split.
  uint64_t block_work(long t) const { return prefix[size_t(bound[size_t(t + 1)])] - prefix[size_t(bound[size_t(t)])]; }
  /// Thread t swept its block in `seconds` (called by that thread in the kernel).
  /// head: of those seconds, the ones spent finishing the head of block t + 1.
  void measured(long t, double seconds, double head = 0.0) {
    if (t == 0) ++timed_calls;  // thread 0 alone writes it
    busy[size_t(t)] += seconds;
    busy_total[size_t(t)] += seconds;
    head_total[size_t(t)] += head;
    last[size_t(t)] = seconds;
    swept[size_t(t)] += double(block_work(t));
  }
  /// After a force call whose threads each called measured(): its longest sweep and its
  /// balanced one into longest_total and balanced_total (a block without work or a sweep
  /// without time counts the call as balanced).
  void account_call() {
    double longest = 0, rate = 0, work = 0;
    bool timed = true;
    for (size_t t = 0; t < share.size(); ++t) {
      const double w = double(block_work(long(t))), sec = last[t];
      longest = std::max(longest, sec);
      timed = timed && w > 0 && sec > 0;
      if (timed) rate += w / sec;
      work += w;
    }
    longest_total += longest;
    balanced_total += timed ? work / rate : longest;
  }
  /// After a force call whose threads each called measured(): every `period` calls (8, 16,
  /// then kRebalanceCalls), each thread's time per unit of modelled work sets the new shares
  /// (share ~ 1 / time per unit), moved all the way in the first two rebalances and halfway
  /// from the old ones after them (the time per unit of a block changes as its boundary
  /// moves, and halving damps the overshoot), none below kMinShare of an equal share. The
  /// split is redone only when a share moves by more than 0.2 % of the total work.
  void rebalance() {
    account_call();
    if (++calls < period) return;
    calls = 0;
    const bool early = period < kRebalanceCalls;  // one of the first rebalances: a full move
    period = std::min(2 * period, kRebalanceCalls);
    const size_t nt = share.size();
    std::vector<double> inv(nt, 0.0);
    double inv_sum = 0;
    bool timed = true;
    for (size_t t = 0; t < nt; ++t) {
      timed = timed && busy[t] > 0 && swept[t] > 0;  // an empty block or no timing: keep the split
      inv[t] = timed ? swept[t] / busy[t] : 0.0;
      inv_sum += inv[t];
    }
    std::fill(busy.begin(), busy.end(), 0.0);
    std::fill(swept.begin(), swept.end(), 0.0);
    if (!timed) return;
    // Halfway to the aim (early: the aim), and at least a quarter of an equal share: a
    // thread that was held up for a while (its core taken by other work) keeps a block to
    // time, so its share can come back when it is fast again.
    // (The new shares sum to 1; those below the floor are raised to it and the others
    // scaled down to leave the sum at 1.)
    const double floor = kMinShare / double(nt);
    double low = 0, rest = 0;
    for (size_t t = 0; t < nt; ++t) {
      inv[t] = early ? inv[t] / inv_sum : 0.5 * (share[t] + inv[t] / inv_sum);
      if (inv[t] < floor) low += floor; else rest += inv[t];
    }
    double moved = 0;
    for (size_t t = 0; t < nt; ++t) {
      inv[t] = inv[t] < floor ? floor : inv[t] * (1.0 - low) / rest;
      moved = std::max(moved, std::abs(inv[t] - share[t]));
    }
    if (moved < 0.002) return;
    share = inv;
    stale = true;
    ++rebalances;
  }
  /// plan(), then the slot map for its blocks. A pair that is not local to its row's block
  /// lies within `span` rows of a boundary between blocks (its partner's rows reach across
  /// it), so only those rows are mapped; elsewhere `of` is never read. After a new list the
  /// whole map is cleared first.
  /// Out of line: a set-up call of the force loop (tests/cli/kernel_inlined.sh allows calls
  /// into PairSlots), not inlined into it.
  /// tails (a two-step call, ForceContext::drift2): the map is for the blocks cut again at
  /// their tails (tail()), the pieces the threads sweep as units there; a pair not local to
  /// its block is not local to its piece either, so that map serves plain calls too, but it
  /// has more slots.
  [[gnu::noinline]] void update(const NeighborList& nl, long n_, long nt, bool tails = false) {
    plan(nl, n_, nt);
    if (mapped && mapped_tails == tails) return;
    mapped = true;
    mapped_tails = tails;
    if (map_all) {
      reserve_headroom(of, np);
      of.assign(np, kNone);
      map_all = false;
    }
    // The pieces' bounds, ascending: the blocks', and with tails each block's tail.
    cut.assign(1, 0);
    for (long t = 0; t < nt; ++t) {
      if (tails && tail(t) > cut.back()) cut.push_back(tail(t));
      if (bound[size_t(t + 1)] > cut.back()) cut.push_back(bound[size_t(t + 1)]);
    }
    // A pair gets a slot when its partner j is not local to the piece of its row; j then
    // depends on a row before its own piece [a, b), so it lies in [a, a + span), and every
    // pair of j gets one (its rows before a lie in other pieces, the rest in a piece where
    // j is not local). So the slots are given particle by particle: each piece's first
    // `span` particles, ascending, and of each one that is not local to its piece all its
    // pairs, in the order of its transposed list. The rows that can hold such pairs, those
    // within `span` of a cut, are cleared first (kNone: nothing stored).
    count = 0;
    long from = 0;  // rows before it are cleared
    for (size_t u = 1; u + 1 < cut.size(); ++u) {
      const long p = cut[u];
      const long lo = std::max(from, p - span), hi = std::min(n, p + span);
      if (lo < hi) std::fill(of.begin() + nl.start[size_t(lo)], of.begin() + nl.start[size_t(hi)], kNone);
      from = std::max(from, hi);
    }
    for (size_t u = 1; u + 1 < cut.size(); ++u) {
      const long a = cut[u], b = cut[u + 1];
      for (long q = a; q < std::min(b, a + span); ++q) {
        if (local_to_block(nl.dep_lo.data(), uint32_t(q), a, b)) continue;
        for (uint32_t r = nl.rstart[size_t(q)]; r < nl.rstart[size_t(q) + 1]; ++r) of[nl.rpair[r]] = count++;
      }
    }
    refill = true;
  }

 private:
  bool map_all = true;  ///< the next update() clears the whole map (a new list)
  bool mapped_tails = false;  ///< the map is for the blocks cut at their tails (update())
  std::vector<long> cut;      ///< the pieces' bounds of the last map (update())
};

struct ForceContext {
  ParticleStore& p;
  NeighborList& nl;
  const std::vector<Wall>& walls;
  double dt = 0, t = 0;
  // Per-pair results (indexed like nl.jdx), valid where nl.hist.live[k]; i's side is summed
  // straight into i's sums (rev).
  std::vector<PairResult>& pair;
  /// Per particle: the sums of all its pairs (force, torque; one accumulator a particle),
  /// those where it is j first, in ascending list order, then those of its own row, in list
  /// order; added to during the row sweep by the one thread that holds all of its pairs
  /// (force_kernel.hpp, "local"; the others' are gathered). At least as long as the particle
  /// arrays and all zero between calls: the kernel resets each entry when it reads it (a new
  /// buffer must start zeroed).
  std::vector<PairResult>& rev;
  // Per wall entry: force on the particle, moment on the wall about the contact point,
  // contact point; valid where nl.whist.live[e].
  std::vector<Vec3>& f_wall;
  std::vector<Vec3>& tw_wall;
  std::vector<Vec3>& c_wall;
  /// Body-force acceleration added to every free particle after its contact forces, m/s^2.
  Vec3 gravity{};
  /// When > 0: velocity Verlet's closing half-kick, applied by the kernel to each free
  /// particle as soon as its force and torque are complete, v += F kick_h/m, omega +=
  /// T kick_h/I (the same operations as a separate pass after the kernel, one pass fewer).
  /// No pair read after that point uses the particle's velocities. 0: forces only.
  double kick_h = 0;
  /// When > 0 (needs kick_h > 0, `drift` and a list built for these particles): the next
  /// step's opening, fused. After its closing half-kick each free particle gets the next
  /// step's opening half-kick (the same v += F kick_h/m, omega += T kick_h/I again) and
  /// drift x += v open_dt, and its displacement since the list build goes into *drift
  /// (frozen particles mark it): the operations of System::step_once's particle pass, in the
  /// same order, so results are bit-identical to the unfused step. Particles attached to
  /// walls are left to that pass. The state after the call is then mid-step. Only for
  /// particles whose radii are as at the list build (no thermal model: System::step_once).
  /// A free particle's force and torque are then not stored in ParticleStore::force and
  /// torque (the kicks use them; the next step's opening is done, and what reads them, the
  /// outputs and checkpoints, runs only after an unfused call: System::mid_step()).
  double open_dt = 0;
  Drift* drift = nullptr;
  /// When not null (needs the fused opening and no recording; on several threads a PairSlots
  /// whose blocks are chained): the loop runs
  /// the next step too, in the same sweep (System::step_sweep), its displacements since the
  /// build into *drift2. Its forces, kicks and drift are those of the next call to the loop
  /// with the same lists: the caller must take that step only if the lists need no rebuild
  /// after this one (*drift), and undo it otherwise.
  Drift* drift2 = nullptr;
  /// With drift2, on one thread only: further steps in the same sweep (System::step_sweep),
  /// the third step's displacements into drift_more[0], the fourth's into drift_more[1]
  /// (null: none). Each step's cursor follows the one before as the second follows the first.
  Drift* drift_more[2] = {nullptr, nullptr};
  /// Below this many particles the kernel runs on one thread (fork/join costs more than it saves).
  long parallel_min = 0;
  /// Store every live pair's result in `pair` (otherwise only those gathered across thread
  /// blocks are stored).
  bool keep_pair = true;
  /// Whether `pair` must cover the neighbor list for n particles: recorded results, or a
  /// force loop on several threads (it goes parallel above parallel_min particles), whose
  /// block-boundary pairs are stored and gathered.
  bool needs_pair_buffer(long n) const {
    return keep_pair || (slots == nullptr && n > parallel_min && omp_get_max_threads() > 1);
  }
  /// Several threads: the lists of particles shared out after the barrier, and, without
  /// recording, the gathered pairs stored compactly (the kernel sizes `pair` itself). Null:
  /// `pair` covers the list (needs_pair_buffer) and each thread finishes its own particles.
  PairSlots* slots = nullptr;
  /// Diagnostics (SimConfig::serial_blocks): a call on several threads whose blocks are
  /// chained sweeps them one after another on the calling thread, the last first.
  bool serial_blocks = false;
  /// Contact radius of each live pair (indexed like nl.jdx) and wall entry, when not null
  /// (conduction, contact network).
  double* a_pair = nullptr;
  double* a_wall = nullptr;
};

}  // namespace cohdem
