// Contacts evaluated four at a time, one per lane of an AVX2 register ("lanes of contacts"),
// for the linear law without rolling or twisting resistance (the law of LAMMPS's chute
// benchmark and of the poured packing). The force loop (sim/force_kernel.hpp) screens a batch
// of list entries as before; the touching ones are then evaluated here in groups of four, and
// the loop adds their results to the particles' sums one contact at a time, in list order.
//
// The lanes do the operations of ContactLaw<LinearNormal, LinearRestitutionDamping,
// LinearTangential, NoRolling, NoTwisting>::evaluate and of the kernel's geometry, in the same
// order, without fused multiply-adds, with every branch of the scalar code turned into a
// select of the value the scalar code would have taken: the results are the scalar path's bit
// for bit (tests/unit/test_lanes.cpp; `COHDEM_SIMD=0` selects the scalar path at run time).
#pragma once
#include <cstddef>
#include <cstdint>

#include "core/vec3.hpp"
#include "models/contact_law.hpp"
#include "models/damping/restitution.hpp"
#include "models/normal/linear.hpp"
#include "models/rolling/rolling.hpp"
#include "models/tangential/spring.hpp"
#include "models/twisting/twisting.hpp"
#include "sim/screen.hpp"

namespace cohdem {

using LinearLaw = ContactLaw<LinearNormal, LinearRestitutionDamping, LinearTangential, NoRolling, NoTwisting>;

/// A material pair's parameters of the linear law, as the lanes read them: each a value the
/// scalar law computes from its Params in the same way (2 beta, the resolved kt), so that the
/// lanes' results match bit for bit.
struct LinearLaneParams {
  double kn;
  double two_beta;  ///< 2.0 * beta (the scalar law's first product)
  double limit;     ///< 1: limit_damping (damping never makes the force attractive), else 0
  double mu;
  double kt;        ///< kt > 0 ? kt : kt_ratio * kn
  double damp_t;
};
LinearLaneParams linear_lane_params(const LinearLaw::Params& p);

/// What the lanes read: the particles' arrays, the list's partner index, the material pairs'
/// parameters (nmat x nmat, row = species of i) and the contacts' histories (list entry k).
struct LaneInput {
  const uint32_t* jdx;
  const Vec3* v;
  const Vec3* omega;
  const double* radius;
  const double* mass;
  const uint8_t* flag;
  const int32_t* species;
  const LinearLaneParams* params;
  size_t nmat;
  Vec3* fs;  ///< LinearLaw's history (its State is the tangential spring's force), by list entry
  double dt;
  bool want_a;
};

/// Results of up to kLaneChunk contacts: force on i, torques on i and j, contact radius, and
/// whether the contact is alive (its history reset and nothing else valid when not).
inline constexpr uint32_t kLaneChunk = 16;
struct LaneOut {
  double fx[kLaneChunk], fy[kLaneChunk], fz[kLaneChunk];
  double tix[kLaneChunk], tiy[kLaneChunk], tiz[kLaneChunk];
  double tjx[kLaneChunk], tjy[kLaneChunk], tjz[kLaneChunk];
  double a[kLaneChunk];
  uint8_t alive[kLaneChunk];
};

/// Evaluates the picked entries [h0, h0 + cnt) of a screened batch (cnt <= kLaneChunk) and
/// updates their histories. AVX2 only: call when screen_avx2_enabled().
void linear_lanes_avx2(const LaneInput& in, const ScreenHits& hits, uint32_t h0, uint32_t cnt, LaneOut& out);

}  // namespace cohdem
