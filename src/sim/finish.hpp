// The force loop's finish of free particles four at a time in AVX2 registers (see
// src/sim/force_kernel.hpp, pass 2): the same operations, in the same order, as the scalar
// finish of one particle, so the results are the same bit for bit.
#pragma once
#include <cstddef>
#include <cstdint>

#include "core/vec3.hpp"
#include "neighbor/neighbor_list.hpp"
#include "sim/force_context.hpp"

namespace cohdem {

/// What the finish of a free particle reads and writes, with the fused opening of the next
/// step (ForceContext::kick_h > 0 and open_dt > 0).
struct FinishFree {
  Vec3* x;
  Vec3* v;
  Vec3* omega;
  PairResult* rev;  ///< the particles' sums of all their pairs (one accumulator a particle), read and zeroed
  const double* mass;
  const double* inertia;
  const uint8_t* flag;
  const uint32_t* wstart;  ///< the lists' wall-entry starts (n + 1)
  const Vec3* ref;         ///< the lists' reference positions (the drift since the build)
  Vec3 grav;
  double kick_h;
  double open_dt;
};

/// How many particles ahead of those it finishes finish_free_avx2 asks for their lines
/// (velocities, spins, sums, reference positions, mass, inertia, flags, wall-entry starts).
/// Where the particles outgrow the caches, these are the lines the finish reads first in
/// the step: in a dilute gas a particle without contacts has only its position and radius
/// read before (by the screening), and the reference positions, inertia, flags and
/// wall-entry starts only the finish reads. The hardware prefetcher, with the dozen or so
/// streams of a sweep to follow, does not bring them in time: asked for this far
/// ahead, the 10^6-particle gas ran 1.11x as fast on one thread of the development VM and
/// 1.12x on two, the 10^4 gas and the chute as fast as before (docs/performance-history.md,
/// sixty-second round, with the distances tried). The results are the same bits.
inline constexpr size_t kFinishAhead = 64;

/// Finishes the particles [i, e) four at a time, from i on, as long as all four of a group
/// are free and have no wall entries, as the scalar finish does for a local particle: its
/// pair sums (then zeroed) plus gravity, the closing half-kick, the next step's opening
/// half-kick and drift, and the drift since the build into d. The force and torque are not
/// stored (a fused call's free particles': ForceContext::open_dt). Returns the
/// first particle it did not finish (a group it may not take, or fewer than four left).
/// x86-64 with AVX2 only: call it only when screen_avx2_enabled().
long finish_free_avx2(const FinishFree& f, long i, long e, Drift& d);

}  // namespace cohdem
