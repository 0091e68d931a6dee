// The bulk force loop, compiled once per contact law (included by registry.cpp; tests read
// kBatch).
//
// Pass 1 (row i): the entries of i's row that touch or are live are picked first (branch-
//   free screening, a batch of kBatch entries of consecutive rows at a time; scalar, or four
//   entries at a time in AVX2 registers where the CPU has them: sim/screen.hpp), then evaluated
//   (one loop over the batch's contacts; for the laws that have them, four contacts at a time
//   in AVX2 lanes, sim/lanes.hpp, with the same results). Each particle has one accumulator
//   (ForceContext::rev): what j receives (the opposite of the force on i, and the torque on
//   j) is added to j's, and then, when row i comes, the forces and torques on i to i's, both
//   in list order, so i's sums are those of its pairs in the rows before, then its own row's
//   (sixty-first round). Pairs whose particle is near a block boundary are stored instead and
//   gathered in the same order (below).
// Pass 2 (particle i): takes i's sums (gathered, for a particle near a block boundary: the
//   pairs where i is j in ascending list order, then its own row's results, OwnAt), then i's
//   wall contacts, then the body force; when
//   asked (ForceContext::kick_h), it then gives i's velocities velocity Verlet's closing
//   half-kick, no row read after pass 2 of i using them, and, when asked too
//   (ForceContext::open_dt), the next step's opening half-kick and drift. With that fused
//   opening and the AVX2 paths, free particles without wall entries are finished four at a
//   time in AVX2 registers (sim/finish.hpp: the same operations, the same results).
// Every sum has an order fixed by the lists, so results are bit-identical for any thread
// count. Each thread (one parallel region) runs pass 1 over a contiguous block of particles
// (of about equal work: PairSlots::plan, corrected by the threads' measured sweep times,
// PairSlots::rebalance) and pass 2 of each particle as soon as the rows it
// depends on are done. Particles that depend on the block before (its last rows hold some
// of their pairs) are finished by that block's thread after its sweep, handed over once
// their own rows are done (PairSlots::HandOff: no barrier); where the blocks are too short
// for that (PairSlots::chained), all threads meet at a barrier and share them out. The row
// sweep adds into a particle's accumulator when all of its pairs lie in the sweeping
// thread's block (always, on one thread); a particle near a block boundary has j's share of
// its pairs stored per pair (gathered through the transposed index in the same order) and
// its own row's results kept in order apart (PairSlots::own_rows), added after them. Only
// WHEN and on which thread pass 2 runs, and how the sums are collected, depend on the thread
// count, never what is summed or in which order. With ForceContext::drift2, the next step runs in the
// same sweep, a second cursor following the first in each thread's block (System::step_sweep;
// on several threads each block is swept as two pieces, its tail first: two_steps below), and
// on one thread with ForceContext::drift_more a third and a fourth (steps_one_thread below).
#pragma once
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>

#include <omp.h>

#include "models/model_impl.hpp"
#include "sim/force_context.hpp"
#include "sim/finish.hpp"
#include "sim/lanes.hpp"
#include "sim/screen.hpp"

namespace cohdem {

/// Prefetches the cache lines of the record *p (for writing when kWrite): its first and its
/// last byte, which lie on different lines whenever the record straddles a boundary.
template <int kWrite, class T>
COHDEM_INLINE void prefetch_record(const T* p) {
  __builtin_prefetch(p, kWrite, 3);
  if constexpr (sizeof(T) > 8) __builtin_prefetch(reinterpret_cast<const char*>(p) + sizeof(T) - 1, kWrite, 3);
}

/// Asks for the reverse sums, velocity and spin of the rows of a batch's picked entries,
/// hrow[0..nh) (for writing, reading, reading). Called for a batch with fewer contacts than
/// a quarter of its rows (a dilute gas: about one in eight rows holds one), where the
/// contact's put is the first touch of its row's lines in the step, a row or more ahead of
/// the finish's own prefetches (kFinishAhead): at 10^6 particles they come from memory.
/// In a dense batch the rows' lines follow each other and the hardware brings them. Out of
/// line: inline, the test on every batch's count changed the dense batches' code (the 10^6
/// bed 0.975x). The 10^6 gas 1.00-1.04x on one and two threads, the same bits
/// (docs/performance-history.md, sixty-eighth round).
__attribute__((noinline)) inline void prefetch_rows(const uint32_t* hrow, const uint32_t nh, const PairResult* rev,
                                                    const Vec3* v, const Vec3* omega) {
  for (uint32_t h = 0; h < nh; ++h) {
    const uint32_t i = hrow[h];
    prefetch_record<1>(rev + i);
    prefetch_record<0>(v + i);
    prefetch_record<0>(omega + i);
  }
}

template <class Law>
void ContactModelImpl<Law>::compute(ForceContext& c) const {
  ParticleStore& P = c.p;
  NeighborList& nl = c.nl;
  const long n = long(P.size());
  State* const __restrict hs = reinterpret_cast<State*>(nl.hist.data.data());
  uint8_t* const __restrict live = nl.hist.live.data();
  const uint32_t* const __restrict start = nl.start.data();
  const uint32_t* const __restrict jdx = nl.jdx.data();
  const uint8_t* const __restrict image = nl.image.data();
  const uint32_t* const __restrict rstart = nl.rstart.data();
  const uint32_t* const __restrict rpair = nl.rpair.data();
  const uint32_t* const __restrict wstart = nl.wstart.data();
  const Vec3* const __restrict shift = nl.shift.data();
  // The screening reads whole groups of four entries up to the list's end (screen.hpp).
  const uint32_t entries = uint32_t(std::min({nl.jdx.size(), nl.image.size(), nl.hist.live.size()}));
  const bool simd = screen_avx2_enabled();
  const bool wide = simd && screen_avx512_enabled();  // the screening eight entries at a time
  // The touching entries' records asked for ahead only where they are too many to stay in
  // the core's caches (screen.hpp, force_loop_prefetches).
  const bool pref = force_loop_prefetches(entries, size_t(n), sizeof(State));
  // Velocities written only by the closing half-kick (ForceContext::kick_h), positions only
  // by the fused opening of the next step (ForceContext::open_dt), after every pair of the
  // particle has been evaluated.
  Vec3* const __restrict x = P.x.data();
  Vec3* const __restrict v = P.v.data();
  Vec3* const __restrict omega = P.omega.data();
  const double* const __restrict radius = P.radius.data();
  const double* const __restrict mass = P.mass.data();
  const double* const __restrict inertia = P.inertia.data();
  const uint8_t* const __restrict flag = P.flag.data();
  const int32_t* const __restrict species = P.species.data();
  Vec3* const __restrict force = P.force.data();
  Vec3* const __restrict torque = P.torque.data();
  // Per-pair results: indexed by list entry, or (several threads without recording, when
  // the context brings PairSlots) by the entry's slot, set up at the start of the region.
  PairResult* res = c.pair.data();
  const uint32_t* slot_of = nullptr;
  PairResult* const __restrict rev = c.rev.data();  // reverse sums of local particles
  constexpr double inf = std::numeric_limits<double>::infinity();
  const double dt = c.dt;
  const Vec3 grav = c.gravity;
  // The material pairs' parameters, read through locals: through `this` they were reloaded
  // after every contact's stores.
  // One particle species at the build (NeighborList::one_species): every pair has the
  // parameters of (s, s), read without the species of i and j (a gas or bed of one material
  // beside wall materials: two random loads per contact fewer, which stood out among the
  // lanes' samples at 10^6 particles).
  const size_t nmat_all = size_t(n_);
  const long s1 = nl.one_species >= 0 && size_t(nl.one_species) < nmat_all && nl.has_reference(size_t(n))
                      ? long(nl.one_species)
                      : -1;
  const size_t pair_1 = s1 >= 0 ? size_t(s1) * nmat_all + size_t(s1) : 0;
  const Params* const __restrict params = params_.data() + pair_1;
  const size_t nmat = s1 >= 0 ? 1 : nmat_all;  // one: index 0 of `params` for every pair
  // The lanes' reading of the material pairs' parameters (set_params), null where the scalar
  // law runs.
  using Lanes = LaneLaw<Law>;
  const void* const lane_p = lanes_.empty() ? nullptr : lanes_.data() + pair_1;
  double* const a_pair = c.a_pair;  // read once, not reloaded after every contact's stores
  const bool want_a = a_pair != nullptr;
  const bool keep_pair = c.keep_pair;
  const double kick_h = c.kick_h;
  const double open_dt = c.open_dt;
  if (open_dt > 0 && (kick_h <= 0 || c.drift == nullptr || !nl.has_reference(size_t(n)) || nl.tracks_radii()))
    throw std::logic_error(
        "force loop: the fused opening needs the closing half-kick, a drift and a built list without radius growth");
  if (c.drift2 != nullptr && (open_dt <= 0 || keep_pair || (n > c.parallel_min && omp_get_max_threads() > 1 && c.slots == nullptr)))
    throw std::logic_error(
        "force loop: two steps in one sweep need the fused opening, no recording and, on several threads, a PairSlots");
  if (c.drift_more[0] != nullptr && (c.drift2 == nullptr || (n > c.parallel_min && omp_get_max_threads() > 1)))
    throw std::logic_error("force loop: three or four steps in one sweep need two steps' set-up and one thread");
  if (c.needs_pair_buffer(n) && c.pair.size() < nl.pair_count())
    throw std::logic_error("force loop: the per-pair result buffer is shorter than the neighbor list");

  // Rows that hold a pair of particle p: dep_lo[p]..p (each pair lies in the row of its lower
  // index, so p's own row is the last). A
  // particle whose rows all lie in the block [a, b) of one thread is "local" to it: that
  // thread alone scatters into its reverse sums (in ascending list order, rows being swept
  // in order), with no per-pair store and no gather. The others (near a block boundary)
  // have their pairs' results stored and gathered through the transposed index. One thread:
  // every particle is local (kAllLocal skips the test).
  const uint32_t* const __restrict dep_lo = nl.dep_lo.data();

  // Each thread takes a contiguous block [a, b) of particles and runs pass 1 over it; pass 2
  // of particle p follows as soon as its own row is done (the last that holds a pair of p)
  // when all of p's rows lie in the block, so pair results are read back while they are
  // still in cache. Particles that depend on rows of an earlier block wait for the barrier.
  // Only the time at which pass 2 runs depends on the thread count, never the order of sums.
  // Several threads with a PairSlots (a System always brings one): the post-barrier work is
  // shared out (below), and without recording the gathered pairs are stored compactly. The
  // slots are set up before the parallel region, for the team it will have (no barrier for
  // that inside); a team of another size sets them up again, inside.
  const bool two = c.drift2 != nullptr;
  auto setup_slots = [&](const long nt) __attribute__((always_inline)) {
    if (keep_pair) {
      c.slots->plan(nl, n, nt);  // the blocks only: every result is stored by list entry
      c.slots->refill = true;    // (over what the slots held)
    } else {
      c.slots->update(nl, n, nt, two);
      c.slots->fit(c.pair);
      res = c.pair.data();
      slot_of = c.slots->of.data();
      if (c.slots->refill) {  // pairs not in contact: kNoPair (PairSlots::refill)
        std::fill(res, res + c.slots->count, kNoPair);
        c.slots->refill = false;
      }
    }
    if (c.slots->deferred.size() < size_t(nt)) c.slots->deferred.resize(size_t(nt));
    if (two && !c.slots->chained)
      throw std::logic_error("force loop: two steps in one sweep on several threads need blocks of 2 spans (chained)");
  };
  // Several threads above parallel_min (and with more than one to have); else `region`
  // below runs without an OpenMP region.
  const bool parallel = n > c.parallel_min && omp_get_max_threads() > 1;
  const long nt_plan = parallel ? long(omp_get_max_threads()) : 1;
  // The call's number for the chained finishing's hand-offs (PairSlots::HandOff).
  uint32_t epoch = 0;
  uint64_t pcall = 0;  // and for the stages of a two-step call (PairSlots::Stage)
  // Where the own-row results of particles not local to their piece are (OwnAt): the
  // PairSlots' (sized by next_epoch), or the call's own without one.
  OwnAt* own_at = nullptr;
  std::vector<OwnAt> own_at_plain;
  if (parallel && c.slots == nullptr) {
    own_at_plain.resize(size_t(n));
    own_at = own_at_plain.data();
  }
  if (nt_plan > 1 && c.slots != nullptr) {
    setup_slots(nt_plan);
    epoch = c.slots->next_epoch(nt_plan);
    own_at = c.slots->own_at.data();
    if (two) pcall = c.slots->next_pair_call(nt_plan);
  }
  // The region's body is a function of its own (`region`), run by every thread of the
  // parallel region, or called directly on one thread: a parallel region of one thread still
  // sets up a team, and its barriers end with a futex wake-up, a system call (about a tenth of
  // a 643-particle ring shear step on the development VM). The arrays' pointers and the loop's
  // constants are its parameters, per thread, like the firstprivate copies they replace (as
  // shared variables, each use went through the region's record of the variable's address:
  // two dependent loads, repeated after every store that might alias it; private copies stay
  // in registers or one stack slot: the linear chute 599 -> 557 instructions per
  // particle-step, bit-identical; 306.1 on the chute before and after this change). res,
  // slot_of, epoch, pcall and timed stay shared: a team of another size sets them inside the
  // region. Out of line: one copy for both callers (tests/cli/kernel_inlined.sh checks it has
  // no calls left but the allowed ones).
  bool timed = false;  // the region's threads timed their sweeps
  // ForceContext::serial_blocks: the team's size and this block's number, given to `region`
  // called once per block on this thread (0: a real team).
  long serial_nt = 0, serial_tid = 0;
  auto region = [&](State* const __restrict hs, uint8_t* const __restrict live, const uint32_t* const __restrict start,
                    const uint32_t* const __restrict jdx, const uint8_t* const __restrict image,
                    const uint32_t* const __restrict rstart, const uint32_t* const __restrict rpair,
                    const uint32_t* const __restrict wstart, const Vec3* const __restrict shift, Vec3* const __restrict x,
                    Vec3* const __restrict v, Vec3* const __restrict omega, const double* const __restrict radius,
                    const double* const __restrict mass, const double* const __restrict inertia,
                    const uint8_t* const __restrict flag, const int32_t* const __restrict species,
                    Vec3* const __restrict force, Vec3* const __restrict torque, PairResult* const __restrict rev,
                    const double dt, const Vec3 grav, double* const a_pair, const bool want_a, const bool keep_pair,
                    const double kick_h, const double open_dt, const uint32_t* const __restrict dep_lo,
                    const Params* const __restrict params, const size_t nmat, const uint32_t entries, const bool simd,
                    const void* const lane_p) __attribute__((noinline)) {
    const long nt = serial_nt > 0 ? serial_nt : omp_get_num_threads(),
               tid = serial_nt > 0 ? serial_tid : omp_get_thread_num();
    const bool share = nt > 1 && c.slots != nullptr;
    if (share && nt != nt_plan) {
#pragma omp single
      {
        setup_slots(nt);
        epoch = c.slots->next_epoch(nt);
        own_at = c.slots->own_at.data();
        if (two) pcall = c.slots->next_pair_call(nt);
      }  // implicit barrier: every thread sees the blocks, res, slot_of, the lists and epoch
    }
    // With a PairSlots its span lets the test skip dep_lo[q] away from the piece's start
    // (local_to_block); without one the span is not known and dep_lo is always read.
    const long span_known = share ? c.slots->span : std::numeric_limits<long>::max();
    auto local = [&](const uint32_t q, const long a, const long b) __attribute__((always_inline)) {
      return local_to_block(dep_lo, q, a, b, span_known);
    };
    // This thread's own-row buffer and the results in it (OwnAt; set up below).
    OwnResult* own_buf = nullptr;
    uint32_t own_used = 0;

    // Pass 1 of the list entries [kb, ke) (at most kBatch), which belong to the rows [i0, i1]
    // in block [a, b): the entries that touch or are live are picked first, without branches
    // (most entries are not in contact: the skin), so the loads of all entries overlap and no
    // branch mispredicts; then they are evaluated in one loop that runs across rows, so the
    // work of one contact overlaps with the next (several rows hold one or no contact). A row
    // longer than a batch is split over several; its results go to the sums in list order,
    // whichever batch they come in.
    auto batch = [&]<bool kAllLocal>(const long i0, const long i1, const uint32_t kb, const uint32_t ke,
                                     const long a, const long b) __attribute__((always_inline)) {
      ScreenHits hits;  // no zero fill
      const ScreenInput scr{start, jdx, image, live, shift, x, radius, entries};
      const uint32_t nh =
          wide   ? screen_avx512(scr, i0, i1, b, kb, ke, hits)
          : simd ? screen_avx2(scr, i0, i1, b, kb, ke, hits)
                 : screen_scalar(scr, i0, i1, b, kb, ke, hits);
      const uint32_t* const hk = hits.k;
      const uint32_t* const hrow = hits.row;
      // The touching entries' history and partners' reverse sums, velocities and spins are
      // far apart in memory (j runs over the neighbouring cells; touching entries are one in
      // five or seven, too sparse for the hardware prefetcher): they are asked for D contacts
      // ahead, so their misses overlap with the evaluation (asking for the whole batch at once
      // was 2-6 % slower: more requests in flight than the core keeps).
      // Each record is asked for by its first and its last byte: records of 24 to 80 bytes
      // packed end to end straddle two cache lines at a quarter to over half of their
      // positions, and the second line would still miss (the same line twice costs nothing).
      auto pf = [&](const uint32_t h) __attribute__((always_inline)) {
        const uint32_t k = hk[h], j = jdx[k];
        prefetch_record<1>(hs + k);
        if (keep_pair) prefetch_record<1>(res + k);
        prefetch_record<1>(rev + j);
        prefetch_record<0>(v + j);
        prefetch_record<0>(omega + j);
      };
      constexpr uint32_t D = 8;
      if (pref && nh * 4 < uint32_t(i1 - i0 + 1)) prefetch_rows(hrow, nh, rev, v, omega);
      if (pref)
        for (uint32_t h = 0; h < std::min(nh, D); ++h) pf(h);
      // One contact's result into the sums, in list order: the force and torque on i into
      // i's reverse sums (one accumulator a particle: its pairs of the rows before are in it
      // already), or, where i is not local to the piece, appended to the thread's own-row
      // results (OwnAt: a row's results come one after another; the finish adds them after
      // the gather that completes i's sums); j's share into its reverse sums or the per-pair
      // buffer.
      // reset: the contact's history is reset here where it ended (the lanes leave that to
      // this branch, which every contact takes anyway; the scalar law resets it itself).
      auto put = [&](const uint32_t k, const uint32_t i, const uint32_t j, const bool alive, const Vec3& f,
                     const Vec3& ti, const Vec3& tj, const double ca, const bool reset)
                     __attribute__((always_inline)) {
        live[k] = alive;
        if (!alive) {
          if (reset) hs[k] = State{};  // as ContactLaw::evaluate does
          // A slot (j not local) of a pair not in contact holds kNoPair (PairSlots::of).
          if (!kAllLocal && slot_of != nullptr && !local(j, a, b)) res[slot_of[k]] = kNoPair;
        } else {
          if (kAllLocal || local(i, a, b)) {
            rev[i].f += f;
            rev[i].tj += ti;
          } else {
            OwnAt& o = own_at[i];
            o.first = own_used - o.count;  // the row's first result (no branch)
            ++o.count;
            own_buf[own_used++] = OwnResult{{f.x, f.y, f.z}, {ti.x, ti.y, ti.z}};
          }
          if (kAllLocal || local(j, a, b)) {  // j's share straight into its reverse sums
            rev[j].f -= f;
            rev[j].tj += tj;
            if (keep_pair) res[k] = {f, tj};
          } else {
            res[slot_of ? slot_of[k] : k] = {f, tj};  // gathered by j's thread after the barrier
          }
          if (a_pair) a_pair[k] = ca;
        }
      };
      // Laws with lanes (sim/lanes.hpp: the linear law, Hertz-Mindlin and MEPA with EPSD
      // rolling): their contacts four at a time in AVX2 lanes, or eight in AVX-512 ones where
      // the screening is (wide), the same results bit for bit,
      // kLaneChunk per call, whose results are then added one contact at a time in list
      // order. The next chunk's records are asked for while one is evaluated.
      if constexpr (Lanes::kHave) {
        if (simd && lane_p != nullptr) {
          const LaneInput lin{jdx, v, omega, radius, mass, flag, species, lane_p, nmat, hs, dt, want_a};
          if (pref)
            for (uint32_t h = D; h < std::min(nh, kLaneChunk); ++h) pf(h);
          LaneOut lo;
          for (uint32_t h0 = 0; h0 < nh; h0 += kLaneChunk) {
            const uint32_t cnt = std::min(kLaneChunk, nh - h0);
            if (pref)
              for (uint32_t h = h0 + kLaneChunk; h < std::min(nh, h0 + 2 * kLaneChunk); ++h) pf(h);
            if (wide)
              Lanes::eval8(lin, hits, h0, cnt, lo);
            else
              Lanes::eval(lin, hits, h0, cnt, lo);
            for (uint32_t q = 0; q < cnt; ++q) {
              const uint32_t k = hk[h0 + q];
              put(k, hrow[h0 + q], jdx[k], lo.alive[q] != 0, Vec3{lo.fx[q], lo.fy[q], lo.fz[q]},
                  Vec3{lo.tix[q], lo.tiy[q], lo.tiz[q]}, Vec3{lo.tjx[q], lo.tjy[q], lo.tjz[q]}, lo.a[q], true);
            }
          }
          return;
        }
      }
      // Written in full by every evaluation that returns true (read only then): declared once,
      // so its 152-byte zero fill (a `rep stos`) is not repeated per contact.
      PairForce out;
      for (uint32_t h = 0; h < nh; ++h) {
        if (pref && h + D < nh) pf(h + D);
        const uint32_t k = hk[h], j = jdx[k], i = hrow[h];
        const double ri = radius[i], rj = radius[j];
        const double rsum = ri + rj;
        const double dist = std::sqrt(hits.d2[h]);
        PairGeom g;
        g.n = Vec3{hits.dx[h], hits.dy[h], hits.dz[h]} * (1.0 / dist);  // one division, not three
        g.delta = rsum - dist;
        g.ri = ri;
        g.rj = rj;
        g.rstar = ri * rj / rsum;
        const bool fi = flag[i] == kFree, fj = flag[j] == kFree;
        g.mi = fi ? mass[i] : inf;
        g.mj = fj ? mass[j] : inf;
        g.Ii = fi ? inertia[i] : inf;
        g.Ij = fj ? inertia[j] : inf;
        // m* = mi mj / (mi + mj), one division; a frozen partner counts as infinitely heavy
        // (two frozen particles: m* = inf).
        g.mstar = fi && fj ? g.mi * g.mj / (g.mi + g.mj) : (fi ? g.mi : g.mj);
        const Vec3 vij = v[i] - v[j];
        g.vn = dot(vij, g.n);
        const double li = ri - 0.5 * g.delta, lj = rj - 0.5 * g.delta;
        const Vec3 vrel = vij - cross(omega[i] * li + omega[j] * lj, g.n);
        g.vt = vrel - g.n * dot(vrel, g.n);
        g.wrel = omega[i] - omega[j];
        g.dt = dt;
        g.want_a = want_a;
        const size_t pq = nmat == 1 ? 0 : size_t(species[i]) * nmat + size_t(species[j]);
        const bool alive = Law::evaluate(params[pq], g, hs[k], out);
        put(k, i, j, alive, out.f, out.ti, out.tj, out.a, false);
      }
    };
    // Pass 2 of particle i (needs pass 1 of every row that holds a pair of i). kLocal: i is
    // known to be local to [a, b) (one thread; or finished during the sweep, which finishes
    // only particles whose rows all lie in its block), so the test is left out.
    // ob: the own-row buffer of the thread that swept i's row (read where i is not local to
    // the piece [a, b)).
    auto finish = [&]<bool kLocal>(const long i, const long a, const long b, Drift& drift, const OwnResult* ob)
                      __attribute__((always_inline)) {
      // The pairs where i is j, summed in ascending list order (the order of rpair, and the
      // order in which the row sweep scatters them), then the results of i's own row, in list
      // order: the same operations whichever way they were collected. A local particle's
      // reverse sums hold both already (put); another's are gathered here.
      Vec3 R, RT;
      if (kLocal || local(uint32_t(i), a, b)) {
        R = rev[i].f;
        RT = rev[i].tj;
        rev[i] = PairResult{};  // zero again for the next call (no fill pass over rev)
      } else {
        if (slot_of != nullptr) {
          // i's pairs in consecutive slots, in the order of its transposed list, those not in
          // contact holding kNoPair (PairSlots::of): one run read front to back, the sums of
          // the live ones bit for bit. Across the particles finished in ascending order (the
          // boundary's, handed over) the runs ascend too, so the reads form a stream that the
          // hardware prefetches, also from the other core's cache.
          const uint32_t q0 = rstart[i], m = rstart[i + 1] - q0;
          if (m > 0) {
            const PairResult* const r = res + slot_of[rpair[q0]];
            for (uint32_t q = 0; q < m; ++q) {
              R -= r[q].f;
              RT += r[q].tj;
            }
          }
        } else {
          for (uint32_t q = rstart[i]; q < rstart[i + 1]; ++q) {
            const uint32_t k = rpair[q];
            if (live[k]) {
              const PairResult& r = res[k];
              R -= r.f;
              RT += r.tj;
            }
          }
        }
        // Then i's own row: its live entries' results, in list order (OwnAt), then reset.
        OwnAt& o = own_at[i];
        const OwnResult* const r = ob + o.first;
        for (uint32_t q = 0; q < o.count; ++q) {
          R += Vec3{r[q].f[0], r[q].f[1], r[q].f[2]};
          RT += Vec3{r[q].t[0], r[q].t[1], r[q].t[2]};
        }
        o.count = 0;
      }
      Vec3 F = R, T = RT;
      // The wall contacts, out of line: rare on most rows, and inline they would keep F and T
      // in stack memory for every particle (the register allocator spills them around the
      // loop's body).
      if (wstart[i] < wstart[i + 1]) {
        Vec3 Fw = F, Tw = T;
        wall_contacts(c, i, Fw, Tw);
        F = Fw;
        T = Tw;
      }
      const bool free_i = flag[i] == kFree;
      if (free_i) F += grav * mass[i];
      // Stored, except a free particle's in a fused call (its kicks use them here, and
      // nothing reads them before the next call: ForceContext::open_dt).
      if (!(free_i && kick_h > 0 && open_dt > 0)) {
        force[i] = F;
        torque[i] = T;
      }
      // Every row that holds a pair of i is done (that is when finish runs): i's velocities
      // are not read again in this call, and its force is final.
      // The kicks and the drift work on registers and store each result once: a vector
      // stored as three scalars and read back at once (v[i] after the closing kick, x[i] for
      // the displacement) cannot be forwarded from the store buffer and stalls.
      if (kick_h > 0 && free_i) {
        const double hm = kick_h / mass[i], hI = kick_h / inertia[i];
        Vec3 vi = v[i] + F * hm, wi = omega[i] + T * hI;
        // The next step's opening half-kick and drift (System::step_once's particle pass, the
        // same operations in the same order), while i is in cache: nothing reads x[i] or v[i]
        // again in this call. Particles attached to walls are carried by that pass.
        if (open_dt > 0) {
          open_free(vi, wi, x[i], F, T, hm, hI, open_dt);
          nl.add_moved(drift, size_t(i), x[i]);  // radii unchanged since the build (!tracks_radii)
        }
        v[i] = vi;
        omega[i] = wi;
      } else if (open_dt > 0 && flag[i] == kFrozen) {
        drift.frozen = true;
      }
    };
    // The finish of free particles four at a time (finish.hpp): with the fused opening, where
    // the AVX2 paths run.
    const bool vec_finish = simd && kick_h > 0 && open_dt > 0;
    const FinishFree ff{x, v, omega, rev, mass, inertia, flag, wstart,
                        vec_finish ? nl.drift_origin() : nullptr, grav, kick_h, open_dt};
    // The blocks: of about equal work with a PairSlots (its plan), else of equal count.
    auto block = [&](const long t) __attribute__((always_inline)) {
      return share ? c.slots->bound[size_t(t)] : block_begin(n, t, nt);
    };
    const long a = block(tid), b = block(tid + 1);
    // The batch that starts at row i, entry k: its end ke (kBatch entries, the block's last
    // batch shorter) and its last row i1 (the last row with entries in [k, ke), or the first
    // row after them).
    // e: where the rows end (the block's end, or a piece's in a two-step call).
    auto batch_end = [&](const long i, const uint32_t k, long& i1, uint32_t& ke, const long e = -1)
                         __attribute__((always_inline)) {
      const long end = e < 0 ? b : e;
      ke = std::min(k + kBatch, start[end]);
      i1 = i;
      while (i1 < end && start[i1 + 1] <= ke) ++i1;
    };
    // Finishes the local particles [next, i) and returns i: four at a time in AVX2 registers
    // where they can (free, no wall entries, the fused opening: finish.hpp), else one at a
    // time (at most four, then the registers again).
    auto finish_local = [&](long next, const long i, Drift& d) __attribute__((always_inline)) {
      if (vec_finish) {
        while (next < i) {
          next = finish_free_avx2(ff, next, i, d);
          for (const long stop = std::min(i, next + 4); next < stop; ++next)
            finish.template operator()<true>(next, a, b, d, nullptr);
        }
      }
      for (; next < i; ++next) finish.template operator()<true>(next, a, b, d, nullptr);
      return next;
    };
    // The block's head: the rows whose particles can depend on an earlier block, those within
    // PairSlots::span of its start (i - dep_lo[i] <= span for every i); without a PairSlots,
    // any.
    const long head_end = share ? std::min(b, a + c.slots->span) : b;
    // This thread's own-row results (OwnAt) of the rows whose particles may not be local
    // to their piece: its block's head, and in a two-step call its tail's first `span` rows,
    // at most one result an entry of those rows a step. One thread: none (every particle is
    // local).
    OwnBuffer own_plain;  // several threads without a PairSlots
    if (nt > 1) {
      size_t cap = start[head_end] - start[a];
      if (two) {
        const long tb = c.slots->tail(tid);
        cap = 2 * (cap + (start[std::min(b, tb + c.slots->span)] - start[tb]));
      }
      OwnBuffer& store = share ? c.slots->own_rows[size_t(tid)].buf : own_plain;
      if (store.size() < cap) store.resize(cap);
      own_buf = store.data();
    }
    Drift drift;  // this thread's share of the fused opening's displacements (exact merge)
    // next: the first particle of the block not yet finished or deferred. No particle depends
    // on a later row than its own, so every particle of the block is finished or deferred by
    // the end of the sweep. One thread (a = 0, b = n) takes the same path with every particle
    // local (kAllLocal: no locality tests; nothing is left for after the barrier). Several:
    // the particles met on the way that depend on an earlier block are handed to `defer`
    // (ascending), so that no second pass over the block has to look for them.
    auto sweep = [&]<bool kAllLocal>(auto&& defer, auto&& swept_to) __attribute__((always_inline)) {
      // Batches of kBatch entries (the last of the block shorter); i: the first row not yet
      // done, k: its first entry not yet screened. Rows done, [.., i), may be finished.
      long next = a, i = a;
      const long head = kAllLocal ? a : head_end;  // a local copy: kept in a register
      for (uint32_t k = start[a]; i < b;) {
        long i1;
        uint32_t ke;
        batch_end(i, k, i1, ke);
        batch.template operator()<kAllLocal>(i, i1, k, ke, a, b);
        i = i1;
        k = ke;
        // Every row of `next` is done and below b: local when none lies before a, which only
        // the block's first `span` rows can fail (head_end; one thread: none).
        for (const long h = std::min(i, head); next < h; ++next) {
          if (long(dep_lo[next]) >= a)
            finish.template operator()<true>(next, a, b, drift, nullptr);
          else
            defer(next);
        }
        next = finish_local(next, i, drift);
        swept_to(next);  // every particle before `next` is finished or deferred
      }
    };
    // The particles left for after the barrier are not spread evenly: a block's first
    // particles depend on the rows of the block before (the plane of cells across the
    // boundary), the first block's on none. On several threads each lists its own (those the
    // sweep deferred: ascending). With a PairSlots all of them are
    // shared out in equal parts after the barrier; finish() is told the block that owns the
    // particle (its locality test is the owner's), so what is summed, and in which order, is
    // the same whichever thread finishes it. Without one, each thread finishes its own.
    // The thread's list is a vector object of its own, handed to the PairSlots (which keeps
    // its capacity from call to call) before the barrier: the PairSlots' vector headers share
    // cache lines, which every growth through them bounced between the cores. It is made as
    // long as the particles the sweep can defer (those of the block's head, head_end - a at
    // most; not zero-filled: DeferList) and cut to its length once complete: a particle is
    // appended through a pointer, with no capacity test and no call (a push_back out of line
    // took about 39 instructions a particle, 2 per particle-step of the 10^4 gas on two
    // threads).
    DeferList own;
    if (share) own.swap(c.slots->deferred[size_t(tid)]);
    if (nt > 1 && own.size() < size_t(head_end - a)) own.resize(size_t(head_end - a));
    uint32_t* const own_p = own.data();
    size_t own_n = 0;
    auto none = [](const long) __attribute__((always_inline)) {};
    const double t_sweep = share ? omp_get_wtime() : 0.0;
    // Chained finishing (PairSlots::chained: every block at least 2 span rows): no barrier.
    // The particles of block t that depend on block t - 1 lie in its first `span` rows; once
    // thread t has swept them (next >= a + span), its list of them is complete and their own
    // rows are done, and it hands the list to thread t - 1 (release), which finishes them
    // after its own sweep (acquire): they need rows of blocks t - 1 and t only, up to their
    // own. Otherwise all threads meet at the barrier and share the deferred particles out.
    const bool chain = share && c.slots->chained;  // always, in a two-step call (setup_slots)
    long hand_at = chain && tid > 0 ? head_end : std::numeric_limits<long>::max();
    auto hand_over = [&]() __attribute__((always_inline)) {
      own.resize(own_n);  // complete: no particle is deferred after this point
      c.slots->hand_over(tid, own, epoch);
      hand_at = std::numeric_limits<long>::max();
    };
    double waited = 0;  // seconds a two-step call waited for another thread (not work)
    Drift drift_b;      // a two-step call: this thread's share of the second step's displacements
    // Two steps in one sweep (ForceContext::drift2). Cursor A runs this step as `sweep`
    // does, cursor B the next one, a batch at a time, once A has finished the batch's rows
    // and every partner they hold (so B reads positions and velocities A has moved, and
    // scatters into reverse sums and pair slots that A has read). Each particle's arithmetic,
    // and its order, is that of two separate calls; B works on data A touched one plane of
    // cells before, still in cache at sizes where a whole sweep is not.
    // On several threads each block is swept as two pieces, its tail (PairSlots::tail: the
    // last `span` rows, the only ones that hold pairs of the next block's particles) and
    // the rest, each piece with its own locality (a particle is local to the piece that
    // holds all its rows). A sweeps the tail first, so that the next block's head (its
    // particles that depend on this block) can be finished for the first step by its own
    // thread early on (PairSlots::Stage), and B can follow A there. B sweeps the tail last,
    // once A is done and the next block's head is finished for the first step; then this
    // thread finishes the next block's head for the second step, handed over as in a
    // chained call (PairSlots::HandOff; below). One thread: one piece, no locality tests,
    // no stages.
    auto two_steps = [&]<bool kAllLocal>() __attribute__((always_inline)) {
      struct Cursor {
        long next, i;  // the first particle not finished (or deferred), the first row not done
        uint32_t k;    // the first entry not screened
      };
      const long tb = kAllLocal ? b : c.slots->tail(tid);  // the tail: rows [tb, b)
      const long hd = kAllLocal || tid == 0 ? a : head_end;  // the head: particles [a, hd)
      // The particles the first step left for later: the head's that depend on the block
      // before, the tail's that depend on the rest of the block; and the second step's tail.
      // (The second step's head goes to `own`, the list handed to the thread before.)
      // Both at most `span` long (PairSlots::pieces).
      uint32_t* const head_a = kAllLocal ? nullptr : c.slots->pieces[size_t(tid)].data();
      uint32_t* const tail_a = kAllLocal ? nullptr : head_a + c.slots->span;
      uint32_t* const tail_b = kAllLocal ? nullptr : tail_a + c.slots->span;
      size_t nha = 0, nta = 0, ntb = 0;
      // One batch of the piece [pa, pe) at cursor C, then the particles it completed:
      // finished, or (those before `head` that depend on rows before pa) deferred.
      auto advance = [&](Cursor& C, Drift& d, const long i1, const uint32_t ke, const long pa, const long pe,
                         const long head, uint32_t* dl, size_t& dn) __attribute__((always_inline)) {
        batch.template operator()<kAllLocal>(C.i, i1, C.k, ke, pa, pe);
        C.i = i1;
        C.k = ke;
        if constexpr (!kAllLocal) {
          for (const long h = std::min(i1, head); C.next < h; ++C.next) {
            if (long(dep_lo[C.next]) >= pa)
              finish.template operator()<true>(C.next, pa, pe, d, nullptr);
            else
              dl[dn++] = uint32_t(C.next);
          }
        }
        C.next = finish_local(C.next, i1, d);
      };
      // The piece [pa, pe) swept whole by one cursor.
      auto whole = [&](const long pa, const long pe, Drift& d, uint32_t* dl, size_t& dn)
                       __attribute__((always_inline)) {
        Cursor C{pa, pa, start[pa]};
        while (C.i < pe) {
          long i1;
          uint32_t ke;
          batch_end(C.i, C.k, i1, ke, pe);
          advance(C, d, i1, ke, pa, pe, pe, dl, dn);
        }
      };
      // First step, the tail.
      if (tb < b) whole(tb, b, drift, tail_a, nta);
      if constexpr (!kAllLocal) c.slots->reach(tid, pcall, PairSlots::kTailA);
      Cursor A{a, a, start[a]}, B{a, a, start[a]};
      bool head_done = hd == a, a_done = false;
      // First step, the head: once A has passed it and the block before has swept its
      // tail (looked at after every batch; waited for only when A has nothing else to do).
      auto head_check = [&](const bool wait) __attribute__((always_inline)) {
        if (head_done || A.next < hd) return;
        if (!wait && !c.slots->reached(tid - 1, pcall, PairSlots::kTailA)) return;
        waited += c.slots->wait_stage(tid - 1, pcall, PairSlots::kTailA);
        for (size_t g = 0; g < nha; ++g) finish.template operator()<false>(long(head_a[g]), a, tb, drift, own_buf);
        head_done = true;
        c.slots->reach(tid, pcall, PairSlots::kHeadA);
      };
      // B's next batch and the particle A must have finished past it (its highest row or
      // partner), found once per batch. Rows and partners in the tail wait for all of A.
      long b_i1 = 0;
      uint32_t b_ke = 0;
      long b_need = -1;
      auto run_b = [&]() __attribute__((always_inline)) {
        if (!head_done) return;
        while (B.i < tb) {
          if (b_need < 0) {
            batch_end(B.i, B.k, b_i1, b_ke, tb);
            const uint32_t row = uint32_t(std::min(b_i1, tb - 1));
            b_need = long(simd ? max_index_avx2(jdx + B.k, b_ke - B.k, row) : max_index_scalar(jdx + B.k, b_ke - B.k, row));
          }
          if (b_need >= tb ? !a_done : b_need >= A.next) return;
          advance(B, drift_b, b_i1, b_ke, a, tb, hd, own_p, own_n);
          b_need = -1;
          if constexpr (!kAllLocal) {
            if (B.next >= hand_at) hand_over();  // the second step's head, to the thread before
          }
        }
      };
      while (A.i < tb) {
        long i1;
        uint32_t ke;
        batch_end(A.i, A.k, i1, ke, tb);
        advance(A, drift, i1, ke, a, tb, hd, head_a, nha);
        if constexpr (!kAllLocal) head_check(false);
        run_b();
      }
      if constexpr (!kAllLocal) {
        head_check(true);
        for (size_t g = 0; g < nta; ++g) finish.template operator()<false>(long(tail_a[g]), tb, b, drift, own_buf);
      }
      a_done = true;
      run_b();
      // Second step, the tail (its partners in the next block's head finished for the first
      // step); the next block's head follows after the sweep (the chained hand-off).
      if constexpr (!kAllLocal) {
        if (tb < b) {
          waited += c.slots->wait_stage(tid + 1, pcall, PairSlots::kHeadA);
          whole(tb, b, drift_b, tail_b, ntb);
          for (size_t g = 0; g < ntb; ++g) finish.template operator()<false>(long(tail_b[g]), tb, b, drift_b, own_buf);
        }
      }
    };
    // Three or four steps in one sweep on one thread (ForceContext::drift_more): cursor q
    // runs step q, a batch at a time, once cursor q - 1 has finished the batch's rows and
    // every partner they hold (the highest index among them, max_index), as B follows A in
    // two_steps, so it reads the positions and velocities that cursor moved and its pairs'
    // history as that cursor left it. The reverse sums each cursor scatters into lie between
    // its own first unfinished particle and the one of the cursor before it: no two cursors
    // share one. Every particle's arithmetic, and its order, is that of separate calls. Two
    // steps on one thread stay with two_steps<true>: this loop over a cursor array ran them
    // 0.98x as fast on the 10^5 gas (sixty-ninth round).
    auto steps_one_thread = [&]() __attribute__((always_inline)) {
      struct Cursor {
        long next, i;       // the first particle not finished, the first row not done
        uint32_t k;         // the first entry not screened
        long i1 = 0;        // its next batch: last row, entries' end, and the particle the
        uint32_t ke = 0;    // cursor before must have finished first (-1: not found yet)
        long need = -1;
      };
      constexpr int kMax = 4;
      Drift later[2];  // the third and fourth steps' displacements (merged below)
      Drift* const dr[kMax] = {&drift, &drift_b, &later[0], &later[1]};
      const int ns = c.drift_more[1] != nullptr ? 4 : 3;
      Cursor C[kMax];
      for (int q = 0; q < ns; ++q) C[q] = Cursor{a, a, start[a]};
      auto advance = [&](Cursor& X, Drift& d, const long i1, const uint32_t ke) __attribute__((always_inline)) {
        batch.template operator()<true>(X.i, i1, X.k, ke, a, b);
        X.i = i1;
        X.k = ke;
        X.next = finish_local(X.next, i1, d);
      };
      // Cursor q as far as cursor q - 1 allows (to the end once that one is done).
      auto follow = [&](const int q) __attribute__((always_inline)) {
        Cursor& X = C[q];
        const Cursor& P = C[q - 1];
        const bool before_done = P.i >= b;
        while (X.i < b) {
          if (X.need < 0) {
            batch_end(X.i, X.k, X.i1, X.ke, b);
            const uint32_t row = uint32_t(std::min(X.i1, b - 1));
            X.need = long(simd ? max_index_avx2(jdx + X.k, X.ke - X.k, row) : max_index_scalar(jdx + X.k, X.ke - X.k, row));
          }
          if (!before_done && X.need >= P.next) return;
          advance(X, *dr[q], X.i1, X.ke);
          X.need = -1;
        }
      };
      while (C[0].i < b) {
        long i1;
        uint32_t ke;
        batch_end(C[0].i, C[0].k, i1, ke, b);
        advance(C[0], *dr[0], i1, ke);
        for (int q = 1; q < ns; ++q) follow(q);
      }
      for (int q = 1; q < ns; ++q) follow(q);
      for (int q = 2; q < ns; ++q) c.drift_more[q - 2]->merge(later[q - 2]);  // (drift_b: below)
    };
    if (two) {
      if (nt == 1 && c.drift_more[0] != nullptr)
        steps_one_thread();
      else if (nt == 1)
        two_steps.template operator()<true>();
      else
        two_steps.template operator()<false>();
    } else if (nt == 1)
      sweep.template operator()<true>(none, none);
    else
      sweep.template operator()<false>(
          [&](const long q) __attribute__((always_inline)) { own_p[own_n++] = uint32_t(q); },
          [&](const long swept) __attribute__((always_inline)) {
            if (swept >= hand_at) hand_over();
          });
    own.resize(own_n);
    if (share) {
      if (hand_at != std::numeric_limits<long>::max()) hand_over();  // an empty block
      own.swap(c.slots->deferred[size_t(tid)]);  // a buffer handed over stays where it is
      double busy = omp_get_wtime() - t_sweep - waited, head = 0.0;
      if (chain && tid + 1 < nt) {
        const PairSlots::HandOff& H = c.slots->wait_for(tid + 1, epoch);
        const double t0 = omp_get_wtime();
        const long ta = block(tid + 1), tb = block(tid + 2);
        Drift& d = two ? drift_b : drift;  // a two-step call hands over the second step's head
        const OwnResult* const ob = c.slots->own_rows[size_t(tid + 1)].buf.data();  // sized before the hand-off
        for (size_t g = 0; g < H.count; ++g) finish.template operator()<false>(long(H.list[g]), ta, tb, d, ob);
        head = omp_get_wtime() - t0;  // the waiting is not this block's work
        busy += head;
      }
      c.slots->measured(tid, busy, head);
      if (tid == 0) {
        timed = true;
        c.slots->chained_calls += chain;
      }
    }
    // Chained: done, the region's join is the only meeting. Otherwise the barrier, then the
    // particles left for after it.
    if (share && !chain) {
#pragma omp barrier
      size_t total = 0;
      for (long t = 0; t < nt; ++t) total += c.slots->deferred[size_t(t)].size();
      const size_t g0 = total * size_t(tid) / size_t(nt), g1 = total * size_t(tid + 1) / size_t(nt);
      size_t base = 0;
      for (long t = 0; t < nt && base < g1; ++t) {
        const DeferList& list = c.slots->deferred[size_t(t)];
        const size_t lo = std::max(g0, base), hi = std::min(g1, base + list.size());
        const long ta = block(t), tb = block(t + 1);
        const OwnResult* const ob = c.slots->own_rows[size_t(t)].buf.data();  // sized before the barrier
        for (size_t g = lo; g < hi; ++g) finish.template operator()<false>(list[g - base], ta, tb, drift, ob);
        base += list.size();
      }
    } else if (!share) {
#pragma omp barrier
      for (const uint32_t q : own) finish.template operator()<false>(long(q), a, b, drift, own_buf);
    }
    if (open_dt > 0) {
      // Both merges inside the critical section: `omp critical` covers one statement or
      // block, and until the sixty-fifth round the second merge stood outside it, so two
      // threads could update *drift2 at once and one thread's displacements be lost (a
      // rebuild taken late in a two-step call on several threads).
#pragma omp critical(cohdem_fused_drift)
      {
        c.drift->merge(drift);  // max / min / or: the same in any order
        if (two) c.drift2->merge(drift_b);
      }
    }
  };
  if (parallel && c.serial_blocks && c.slots != nullptr && c.slots->chained && !two) {
    // The blocks one after another, the last first: a chained block waits only for the
    // hand-off of the block after it (PairSlots::wait_for), which is then already made.
    serial_nt = nt_plan;
    for (serial_tid = nt_plan - 1; serial_tid >= 0; --serial_tid)
      region(hs, live, start, jdx, image, rstart, rpair, wstart, shift, x, v, omega, radius, mass, inertia, flag, species,
             force, torque, rev, dt, grav, a_pair, want_a, keep_pair, kick_h, open_dt, dep_lo, params, nmat, entries, simd,
             lane_p);
    serial_nt = 0;
    ++c.slots->serial_calls;
  } else if (parallel) {
#pragma omp parallel
    region(hs, live, start, jdx, image, rstart, rpair, wstart, shift, x, v, omega, radius, mass, inertia, flag, species,
           force, torque, rev, dt, grav, a_pair, want_a, keep_pair, kick_h, open_dt, dep_lo, params, nmat, entries, simd,
           lane_p);
  } else {
    region(hs, live, start, jdx, image, rstart, rpair, wstart, shift, x, v, omega, radius, mass, inertia, flag, species,
           force, torque, rev, dt, grav, a_pair, want_a, keep_pair, kick_h, open_dt, dep_lo, params, nmat, entries, simd,
           lane_p);
  }
  if (timed) c.slots->rebalance();
}

template <class Law>
void ContactModelImpl<Law>::wall_contacts(ForceContext& c, const long i, Vec3& F, Vec3& T) const {
  // One particle: its values are read once; the wall entries' arrays by index.
  const ParticleStore& P = c.p;
  NeighborList& nl = c.nl;
  State* const ws = reinterpret_cast<State*>(nl.whist.data.data());
  const Vec3 xi = P.x[i], vi = P.v[i], wi = P.omega[i];
  const double ri = P.radius[i], mi = P.mass[i], Ii = P.inertia[i];
  const int si = P.species[i];
  constexpr double inf = std::numeric_limits<double>::infinity();
  for (uint32_t e = nl.wstart[i]; e < nl.wstart[i + 1]; ++e) {
    const Wall& w = c.walls[nl.wall[e]];
    uint8_t& live = nl.whist.live[e];
    PairGeom g;
    double delta;
    if (!w.contact(xi, ri, g.n, delta) || (!live && delta <= 0)) {
      if (live) { ws[e] = State{}; live = 0; }
      continue;
    }
    g.delta = delta;
    g.ri = ri;
    g.rj = 0;
    g.rstar = g.ri;
    g.mi = g.mstar = mi;
    g.mj = g.Ij = inf;
    g.Ii = Ii;
    const double li = g.ri - delta;
    const Vec3 cp = xi - g.n * li;
    const Vec3 vw = w.velocity_at(cp, c.t);
    g.vn = dot(vi - vw, g.n);
    const Vec3 vrel = vi - vw - cross(wi * li, g.n);
    g.vt = vrel - g.n * dot(vrel, g.n);
    g.wrel = wi - w.omega;
    g.dt = c.dt;
    g.want_a = c.a_wall != nullptr;
    PairForce out;
    const bool alive = Law::evaluate(p(si, w.material), g, ws[e], out);
    live = alive;
    if (alive) {
      F += out.f;
      T += out.ti;
      c.f_wall[e] = out.f;
      c.tw_wall[e] = out.tj;
      c.c_wall[e] = cp;
      if (c.a_wall) c.a_wall[e] = out.a;
    }
  }
}

}  // namespace cohdem
