// Contacts evaluated four at a time, one per lane of an AVX2 register ("lanes of contacts"),
// or eight at a time in AVX-512 registers where the CPU has them (lanes_avx512.cpp),
// for the linear law (LAMMPS's chute, the poured packing), Hertz-Mindlin (the chute's
// `granular hmr` variant, the packed beds) and MEPA (the ring shear tester's law; where every
// material pair has fixed stiffnesses, n = 1 or 3/2 and no dp_shift: lane_usable, other MEPA
// settings run the scalar law), each with rolling resistance `none`, `epsd` or `sds` and no
// twisting. The force loop (sim/force_kernel.hpp) screens a batch of list entries as before;
// the touching ones are then evaluated here in groups of four (eight), and the loop adds their
// results to the particles' sums one contact at a time, in list order.
//
// The lanes do the operations of the law's ContactLaw::evaluate and of the kernel's geometry,
// in the same order, without fused multiply-adds, with every branch of the scalar code turned
// into a select of the value the scalar code would have taken: the results are the scalar
// path's bit for bit (tests/physics/test_lanes.cpp; `COHDEM_SIMD=0` in the environment
// selects the scalar path at run time). Other laws run the scalar path.
#pragma once
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <bit>
#include <type_traits>

#include "core/vec3.hpp"
#include "models/contact_law.hpp"
#include "models/damping/restitution.hpp"
#include "models/normal/hertz.hpp"
#include "models/normal/linear.hpp"
#include "models/normal/mepa.hpp"
#include "models/rolling/rolling.hpp"
#include "models/tangential/spring.hpp"
#include "models/twisting/twisting.hpp"
#include "sim/screen.hpp"

namespace cohdem {

template <class R>
using LinearLawR = ContactLaw<LinearNormal, LinearRestitutionDamping, LinearTangential, R, NoTwisting>;
template <class R>
using HertzLawR = ContactLaw<HertzNormal, TsujiDamping, MindlinTangential, R, NoTwisting>;
template <class R>
using MepaLawR = ContactLaw<MepaNormal, ViscousDamping, HystTangential<MepaNormal>, R, NoTwisting>;
using LinearLaw = LinearLawR<NoRolling>;
using LinearEpsdLaw = LinearLawR<EpsdRolling>;
using LinearSdsLaw = LinearLawR<SdsRolling>;
using HertzLaw = HertzLawR<NoRolling>;
using HertzEpsdLaw = HertzLawR<EpsdRolling>;
using HertzSdsLaw = HertzLawR<SdsRolling>;
using MepaLaw = MepaLawR<NoRolling>;
using MepaEpsdLaw = MepaLawR<EpsdRolling>;
using MepaSdsLaw = MepaLawR<SdsRolling>;

/// A material pair's parameters of the linear law, as the lanes read them: each a value the
/// scalar law computes from its Params in the same way (2 beta, the resolved kt), so that the
/// lanes' results match bit for bit. Switches are lane masks (all bits set: on; 0: off), used
/// as they are by the lanes' selects. The rolling fields are EPSD's (mu_r, two_eta_r, damped)
/// and SDS's (mu_r, k_r, gamma_r), 0 where the law has none.
struct LinearLaneParams {
  double kn;
  double two_beta;  ///< 2.0 * beta (the scalar law's first product)
  uint64_t limit;   ///< mask: limit_damping (damping never makes the force attractive)
  double mu;
  double kt;        ///< kt > 0 ? kt : kt_ratio * kn
  double damp_t;
  double mu_r;
  double two_eta_r;  ///< eta_r * 2.0 (exact)
  uint64_t damped;   ///< mask: eta_r > 0 (EPSD's viscous part)
  double k_r, gamma_r;  ///< SDS's spring and dashpot
};
LinearLaneParams lane_params(const LinearLaw::Params& p);
LinearLaneParams lane_params(const LinearEpsdLaw::Params& p);
LinearLaneParams lane_params(const LinearSdsLaw::Params& p);

/// The same for Hertz-Mindlin.
struct HertzLaneParams {
  double two_Estar;  ///< 2.0 * E* (kn = 2 E* a)
  double two_beta;
  uint64_t limit;    ///< mask
  double mu;
  double eight_Gstar;  ///< 8.0 * G* (kt = 8 G* a)
  double damp_kt;      ///< damp_t sqrt(4 G*/E*)
  double mu_r;
  double two_eta_r;    ///< eta_r * 2.0 (exact)
  uint64_t damped;     ///< mask: eta_r > 0
  double k_r, gamma_r;  ///< SDS's spring and dashpot
};
HertzLaneParams lane_params(const HertzLaw::Params& p);
HertzLaneParams lane_params(const HertzEpsdLaw::Params& p);
HertzLaneParams lane_params(const HertzSdsLaw::Params& p);

/// The same for MEPA.
struct MepaLaneParams {
  double k1, k2, plastic, kadh, f0;
  double n_k2;        ///< n * k2 (kn = n k2 delta^(n-1), the scalar law's first product)
  uint64_t n_is_1;    ///< mask: n = 1 (else 3/2)
  uint64_t offset;    ///< mask: coulomb_offset
  double gamma_n;
  uint64_t limit;     ///< mask
  double mu;
  uint64_t kt_const;  ///< mask: a fixed kt
  double kt_c, kt_ratio, kt_mult;
  double gamma_t;     ///< damp_t * gamma_n (the scalar law's product; gamma_n is a constant)
  double mu_r;
  double two_eta_r;   ///< eta_r * 2.0 (exact)
  uint64_t damped;    ///< mask: eta_r > 0
  double k_r, gamma_r;  ///< SDS's spring and dashpot
};
MepaLaneParams lane_params(const MepaLaw::Params& p);
MepaLaneParams lane_params(const MepaEpsdLaw::Params& p);
MepaLaneParams lane_params(const MepaSdsLaw::Params& p);
/// Whether a material pair's MEPA settings are those the lanes do (fixed k1, k2; n = 1 or
/// 3/2; adhesion with the same exponent; no dp_shift).
bool lane_usable(const MepaLaw::Params& p);
bool lane_usable(const MepaEpsdLaw::Params& p);
bool lane_usable(const MepaSdsLaw::Params& p);

/// A material pair's lane parameters as the lanes read them: the fields (gathered lane by
/// lane in a group of mixed pairs) and each field again in four copies, so that a group of
/// one pair reads it with one aligned 32-byte load, or as an operand of the arithmetic,
/// instead of a broadcast. Every field of P is 8 bytes (a double or a lane mask).
template <class P>
struct alignas(32) LaneParamsOf {
  static constexpr size_t kFields = sizeof(P) / 8;
  static_assert(sizeof(P) % 8 == 0 && alignof(P) == 8, "lane parameters are 8-byte fields");
  uint64_t wide[kFields][4];
  P p;
  LaneParamsOf(const P& q) : p(q) {  // NOLINT: converts from lane_params()
    for (size_t f = 0; f < kFields; ++f)
      for (size_t l = 0; l < 4; ++l) std::memcpy(&wide[f][l], reinterpret_cast<const char*>(&q) + 8 * f, 8);
  }
};

/// The laws' histories as the lanes read them (same_layout below checks them against
/// ContactLaw::State): the tangential spring, its last stiffness where it can fall, the
/// rolling spring (mk: EPSD's moment, or SDS's force, State's rolling.fk, in the same place);
/// MEPA's largest and plastic overlaps and branch first.
struct LinearLaneHistory { Vec3 fs; };
struct LinearRollingLaneHistory { Vec3 fs; Vec3 mk; };
struct HertzLaneHistory { Vec3 fs; double kt_prev; };
struct HertzRollingLaneHistory { Vec3 fs; double kt_prev; Vec3 mk; };
struct MepaLaneHistory { double Dmax, Dp; int32_t branch; Vec3 fs; double kt_prev; };
struct MepaRollingLaneHistory { double Dmax, Dp; int32_t branch; Vec3 fs; double kt_prev; Vec3 mk; };

/// What the lanes read: the particles' arrays, the list's partner index, the material pairs'
/// parameters (nmat x nmat, row = species of i, LaneParamsOf the law's lane-parameter type) and the
/// contacts' histories (by list entry, of the law's lane-history type).
struct LaneInput {
  const uint32_t* jdx;
  const Vec3* v;
  const Vec3* omega;
  const double* radius;
  const double* mass;  ///< (the inertias are not read: sphere_inertia of mass and radius)
  const uint8_t* flag;
  const int32_t* species;
  const void* params;
  size_t nmat;
  void* hist;
  double dt;
  bool want_a;
};

/// Results of up to kLaneChunk contacts: force on i, torques on i and j, contact radius, and
/// whether the contact is alive (nothing else valid when not, and its history record is then
/// for the caller to reset: the force loop does, in the branch it takes for every contact).
inline constexpr uint32_t kLaneChunk = 16;
struct LaneOut {
  double fx[kLaneChunk], fy[kLaneChunk], fz[kLaneChunk];
  double tix[kLaneChunk], tiy[kLaneChunk], tiz[kLaneChunk];
  double tjx[kLaneChunk], tjy[kLaneChunk], tjz[kLaneChunk];
  double a[kLaneChunk];
  uint8_t alive[kLaneChunk];
};

/// Evaluate the picked entries [h0, h0 + cnt) of a screened batch (cnt <= kLaneChunk) and
/// update their histories (records of contacts that ended are the caller's to reset: see
/// LaneOut). AVX2 only: call when screen_avx2_enabled().
using LaneEval = void (*)(const LaneInput& in, const ScreenHits& hits, uint32_t h0, uint32_t cnt, LaneOut& out);
/// The entry points, one list for both widths: X(law, suffix, rolling, width) for each law
/// with lanes, naming law##suffix##_lanes_##width (linear_lanes_avx2, mepa_epsd_lanes_avx512,
/// ...); lanes_body.hpp defines them from the law's group (law##_group) with the rolling
/// resistance `rolling` (kLaneNoRolling, kLaneEpsd, kLaneSds). The eight-lane ones
/// (lanes_avx512.cpp, AVX-512 registers, the same results bit for bit): call them only when
/// screen_avx512_enabled().
inline constexpr int kLaneNoRolling = 0, kLaneEpsd = 1, kLaneSds = 2;
#define COHDEM_LANE_ENTRIES(X, width)                                                                     \
  X(linear, , kLaneNoRolling, width) X(linear, _epsd, kLaneEpsd, width) X(linear, _sds, kLaneSds, width)   \
  X(hertz, , kLaneNoRolling, width) X(hertz, _epsd, kLaneEpsd, width) X(hertz, _sds, kLaneSds, width)      \
  X(mepa, , kLaneNoRolling, width) X(mepa, _epsd, kLaneEpsd, width) X(mepa, _sds, kLaneSds, width)
#define COHDEM_LANE_DECLARE(law, suffix, rolling, width) \
  void law##suffix##_lanes_##width(const LaneInput& in, const ScreenHits& hits, uint32_t h0, uint32_t cnt, LaneOut& out);
/// Where the build is not for x86-64: entries that are never called (screen_avx2_enabled()
/// is false there).
#define COHDEM_LANE_STUB(law, suffix, rolling, width) \
  void law##suffix##_lanes_##width(const LaneInput&, const ScreenHits&, uint32_t, uint32_t, LaneOut&) {}
COHDEM_LANE_ENTRIES(COHDEM_LANE_DECLARE, avx2)
COHDEM_LANE_ENTRIES(COHDEM_LANE_DECLARE, avx512)

/// Which laws have lanes, with their lane parameters and evaluation, and whether a material
/// pair's settings can take them (usable: all pairs must; ContactModelImpl::set_params).
template <class Law>
struct LaneLaw {
  static constexpr bool kHave = false;
  using Params = char;
};
template <class Law, class P, LaneEval kEval, LaneEval kEval8>
struct LaneLawOf {
  static constexpr bool kHave = true;
  using Params = LaneParamsOf<P>;
  static constexpr LaneEval eval = kEval;    ///< four lanes, AVX2
  static constexpr LaneEval eval8 = kEval8;  ///< eight lanes, AVX-512
  static bool usable(const typename Law::Params&) { return true; }
};
template <>
struct LaneLaw<LinearLaw> : LaneLawOf<LinearLaw, LinearLaneParams, linear_lanes_avx2, linear_lanes_avx512> {};
template <>
struct LaneLaw<LinearEpsdLaw> : LaneLawOf<LinearEpsdLaw, LinearLaneParams, linear_epsd_lanes_avx2, linear_epsd_lanes_avx512> {};
template <>
struct LaneLaw<LinearSdsLaw> : LaneLawOf<LinearSdsLaw, LinearLaneParams, linear_sds_lanes_avx2, linear_sds_lanes_avx512> {};
template <>
struct LaneLaw<HertzLaw> : LaneLawOf<HertzLaw, HertzLaneParams, hertz_lanes_avx2, hertz_lanes_avx512> {};
template <>
struct LaneLaw<HertzEpsdLaw> : LaneLawOf<HertzEpsdLaw, HertzLaneParams, hertz_epsd_lanes_avx2, hertz_epsd_lanes_avx512> {};
template <>
struct LaneLaw<HertzSdsLaw> : LaneLawOf<HertzSdsLaw, HertzLaneParams, hertz_sds_lanes_avx2, hertz_sds_lanes_avx512> {};
template <>
struct LaneLaw<MepaLaw> : LaneLawOf<MepaLaw, MepaLaneParams, mepa_lanes_avx2, mepa_lanes_avx512> {
  static bool usable(const MepaLaw::Params& p) { return lane_usable(p); }
};
template <>
struct LaneLaw<MepaEpsdLaw> : LaneLawOf<MepaEpsdLaw, MepaLaneParams, mepa_epsd_lanes_avx2, mepa_epsd_lanes_avx512> {
  static bool usable(const MepaEpsdLaw::Params& p) { return lane_usable(p); }
};
template <>
struct LaneLaw<MepaSdsLaw> : LaneLawOf<MepaSdsLaw, MepaLaneParams, mepa_sds_lanes_avx2, mepa_sds_lanes_avx512> {
  static bool usable(const MepaSdsLaw::Params& p) { return lane_usable(p); }
};

/// The lane histories are the laws' State, byte for byte: the same size (std::bit_cast), the
/// same fields (a last stiffness, EPSD's spring, MEPA's overlaps where the State has them)
/// at the same places.
template <class LH, class Law>
constexpr bool same_layout() {
  using S = typename Law::State;
  constexpr bool kt = requires(S x) { x.tangential.kt_prev; }, mk = requires(S x) { x.rolling.mk; },
                 fk = requires(S x) { x.rolling.fk; }, mepa = requires(S x) { x.normal.Dmax; };
  if (kt != requires(LH h) { h.kt_prev; } || (mk || fk) != requires(LH h) { h.mk; } ||
      mepa != requires(LH h) { h.Dmax; })
    return false;
  S s{};
  s.tangential.fs = {1, 2, 3};
  if constexpr (kt) s.tangential.kt_prev = 4;
  if constexpr (mk) s.rolling.mk = {5, 6, 7};
  if constexpr (fk) s.rolling.fk = {5, 6, 7};
  if constexpr (mepa) {
    s.normal.Dmax = 8;
    s.normal.Dp = 9;
    s.normal.branch = 2;
  }
  const LH h = std::bit_cast<LH>(s);
  bool ok = h.fs == Vec3{1, 2, 3};
  if constexpr (kt) ok = ok && h.kt_prev == 4;
  if constexpr (mk) ok = ok && h.mk == Vec3{5, 6, 7};
  if constexpr (fk) ok = ok && h.mk == Vec3{5, 6, 7};
  if constexpr (mepa) ok = ok && h.Dmax == 8 && h.Dp == 9 && h.branch == 2;
  return ok;
}
static_assert(same_layout<LinearLaneHistory, LinearLaw>() && same_layout<LinearRollingLaneHistory, LinearEpsdLaw>() &&
                  same_layout<LinearRollingLaneHistory, LinearSdsLaw>() && same_layout<MepaRollingLaneHistory, MepaSdsLaw>() &&
                  same_layout<HertzLaneHistory, HertzLaw>() && same_layout<HertzRollingLaneHistory, HertzEpsdLaw>() &&
                  same_layout<HertzRollingLaneHistory, HertzSdsLaw>() &&
                  same_layout<MepaLaneHistory, MepaLaw>() && same_layout<MepaRollingLaneHistory, MepaEpsdLaw>(),
              "the lanes' histories must be the laws' State, byte for byte");

}  // namespace cohdem
