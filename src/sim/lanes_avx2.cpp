// The lanes of contacts in AVX2 registers, four at a time (see lanes.hpp): the lane
// parameters of the laws (lane_params, shared with the AVX-512 lanes), then the primitives of
// four lanes, from which lanes_body.hpp makes the laws. Compiled for AVX2 alone: no fused
// multiply-adds, which would round differently from the scalar law.
#include "sim/lanes.hpp"

#include <algorithm>
#include <type_traits>
#include <cstddef>
#include <cstring>
#include <limits>

#include "particles/particle_store.hpp"

#if defined(__x86_64__)
#include <immintrin.h>

#include "sim/lanes_ops4.hpp"
#endif

namespace cohdem {

namespace {

constexpr uint64_t mask_of(const bool on) { return on ? ~uint64_t(0) : 0; }

/// The rolling fields of the lane parameters: EPSD's or SDS's, 0 where the law has none.
template <class Q, class R>
void rolling_params(Q& q, const R& r) {
  q.k_r = q.gamma_r = 0;
  if constexpr (requires { r.k_r; }) {
    q.mu_r = r.mu_r;
    q.k_r = r.k_r;
    q.gamma_r = r.gamma_r;
    q.two_eta_r = 0;
    q.damped = 0;
  } else if constexpr (requires { r.mu_r; }) {
    q.mu_r = r.mu_r;
    q.two_eta_r = r.eta_r * 2.0;
    q.damped = mask_of(r.eta_r > 0);
  } else {
    q.mu_r = q.two_eta_r = 0;
    q.damped = 0;
  }
}

template <class P>
LinearLaneParams linear_params(const P& p) {
  LinearLaneParams q;
  q.kn = p.normal.kn;
  q.two_beta = 2.0 * p.damping.beta;
  q.limit = mask_of(p.damping.limit);
  q.mu = p.tangential.mu;
  // LinearTangential::apply: kt > 0 ? kt : kt_ratio * kn, with kn = LinearNormal's kn.
  q.kt = p.tangential.kt > 0 ? p.tangential.kt : p.tangential.kt_ratio * p.normal.kn;
  q.damp_t = p.tangential.damp_t;
  rolling_params(q, p.rolling);
  return q;
}

template <class P>
HertzLaneParams hertz_params(const P& p) {
  HertzLaneParams q;
  q.two_Estar = 2.0 * p.normal.Estar;
  q.two_beta = 2.0 * p.damping.beta;
  q.limit = mask_of(p.damping.limit);
  q.mu = p.tangential.mu;
  q.eight_Gstar = 8.0 * p.tangential.Gstar;
  q.damp_kt = p.tangential.damp_kt;
  rolling_params(q, p.rolling);
  return q;
}

template <class P>
MepaLaneParams mepa_params(const P& p) {
  const auto& np = p.normal;
  const auto& tp = p.tangential;
  MepaLaneParams q;
  q.k1 = np.k1;
  q.k2 = np.k2;
  q.plastic = np.plastic;
  q.kadh = np.kadh;
  q.f0 = np.f0;
  q.n_k2 = np.n * np.k2;
  q.n_is_1 = mask_of(np.n == 1.0);
  q.offset = mask_of(np.offset);
  q.gamma_n = p.damping.gamma_n;
  q.limit = mask_of(p.damping.limit);
  q.mu = tp.mu;
  q.kt_const = mask_of(tp.kt_const);
  q.kt_c = tp.kt_c;
  q.kt_ratio = tp.kt_ratio;
  q.kt_mult = tp.kt_mult;
  q.gamma_t = tp.damp_t * p.damping.gamma_n;
  rolling_params(q, p.rolling);
  return q;
}

template <class P>
bool mepa_usable(const P& p) {
  const auto& np = p.normal;
  // HystereticNormal::apply with p.fixed, x_is_n and no shift; pow_nm1 as 1 or a square root;
  // HystTangential without kt_hertz (never with fixed stiffnesses; checked all the same).
  return np.fixed && np.x_is_n && !np.shift && (np.n == 1.0 || np.n == 1.5) && !p.tangential.kt_hertz;
}

}  // namespace

LinearLaneParams lane_params(const LinearLaw::Params& p) { return linear_params(p); }
LinearLaneParams lane_params(const LinearEpsdLaw::Params& p) { return linear_params(p); }
LinearLaneParams lane_params(const LinearSdsLaw::Params& p) { return linear_params(p); }
HertzLaneParams lane_params(const HertzLaw::Params& p) { return hertz_params(p); }
HertzLaneParams lane_params(const HertzEpsdLaw::Params& p) { return hertz_params(p); }
HertzLaneParams lane_params(const HertzSdsLaw::Params& p) { return hertz_params(p); }
MepaLaneParams lane_params(const MepaLaw::Params& p) { return mepa_params(p); }
MepaLaneParams lane_params(const MepaEpsdLaw::Params& p) { return mepa_params(p); }
MepaLaneParams lane_params(const MepaSdsLaw::Params& p) { return mepa_params(p); }
bool lane_usable(const MepaLaw::Params& p) { return mepa_usable(p); }
bool lane_usable(const MepaEpsdLaw::Params& p) { return mepa_usable(p); }
bool lane_usable(const MepaSdsLaw::Params& p) { return mepa_usable(p); }

#if defined(__x86_64__)

namespace {

// The primitives of four lanes (lanes_body.hpp says what each is), in AVX2.
#define LANES_TARGET "avx2"
#define LANES_FN __attribute__((target(LANES_TARGET), always_inline)) inline

constexpr uint32_t kW = 4;
using V = lanes4::V4;
using M = lanes4::M4;
using lanes4::Quads;
using lanes4::Pairs;

LANES_FN V sqrtv(const V a) { return V(_mm256_sqrt_pd(__m256d(a))); }
/// std::max(a, 0.0) lane by lane: a < 0 ? 0 : a (a -0 or a NaN passes through, as there).
LANES_FN V max0(const V a) { return V(_mm256_max_pd(_mm256_setzero_pd(), __m256d(a))); }
/// m ? a : b lane by lane, m a lane mask (all bits set or none): one blend on m's sign bits
/// (`m ? a : b` also compares a mask loaded from the parameters with zero first).
LANES_FN V sel(const M m, const V a, const V b) {
  return V(_mm256_blendv_pd(__m256d(b), __m256d(a), _mm256_castsi256_pd(__m256i(m))));
}
/// Whether any lane of m is set.
LANES_FN bool any(const M m) { return _mm256_movemask_pd(_mm256_castsi256_pd(__m256i(m))) != 0; }
LANES_FN V splat(const double s) { return V{s, s, s, s}; }
LANES_FN M msplat(const long long s) { return M{s, s, s, s}; }
LANES_FN V loadv(const double* src) { return V(_mm256_loadu_pd(src)); }
LANES_FN void store(double* dst, const V a) { _mm256_storeu_pd(dst, __m256d(a)); }
/// {f(0), f(1), f(2), f(3)}.
template <class F>
LANES_FN V make(F&& f) { return V{f(0), f(1), f(2), f(3)}; }
template <class F>
LANES_FN M makem(F&& f) { return M{f(0), f(1), f(2), f(3)}; }
/// Doubles a[idx[0..3]].
LANES_FN V gather(const double* __restrict a, const uint32_t* idx) { return V{a[idx[0]], a[idx[1]], a[idx[2]], a[idx[3]]}; }
LANES_FN void load3(const Vec3* const* a, V& x, V& y, V& z) { lanes4::load3(a, x, y, z); }
LANES_FN Quads quads(const V a, const V b, const V c, const V d) { return lanes4::quads(a, b, c, d); }
LANES_FN Pairs pairs(const V a, const V b) { return lanes4::pairs(a, b); }
/// Four doubles of each lane's record in four lanes.
struct Cols { V v[4]; };
template <class H>
LANES_FN Cols load_quads(H* h, const uint32_t* k, const uint32_t o) {
  const Quads q = lanes4::load_quads(h, k, o);
  return {{V(q.q[0]), V(q.q[1]), V(q.q[2]), V(q.q[3])}};
}
template <class H>
LANES_FN void load_pairs(H* h, const uint32_t* k, const uint32_t o, V& a, V& b) { lanes4::load_pairs(h, k, o, a, b); }

/// out.alive[g .. g + 4) from the alive lanes' sign bits in one 4-byte store (lanes past the
/// chunk's end write bytes that no one reads: g + 4 <= kLaneChunk).
constexpr uint32_t alive_bytes(const int m) {
  return uint32_t(m & 1) | uint32_t((m >> 1) & 1) << 8 | uint32_t((m >> 2) & 1) << 16 | uint32_t((m >> 3) & 1) << 24;
}
constexpr uint32_t kAliveBytes[16] = {alive_bytes(0),  alive_bytes(1),  alive_bytes(2),  alive_bytes(3),
                                      alive_bytes(4),  alive_bytes(5),  alive_bytes(6),  alive_bytes(7),
                                      alive_bytes(8),  alive_bytes(9),  alive_bytes(10), alive_bytes(11),
                                      alive_bytes(12), alive_bytes(13), alive_bytes(14), alive_bytes(15)};
LANES_FN void put_alive(const M alive, const uint32_t g, LaneOut& out) {
  const uint32_t b = kAliveBytes[_mm256_movemask_pd(_mm256_castsi256_pd(__m256i(alive)))];
  std::memcpy(out.alive + g, &b, sizeof b);
}

/// A uniform group's parameter: the pair's four copies of it (LaneParamsOf::wide), one
/// aligned load, often an operand of the arithmetic.
template <class T, class F>
LANES_FN const uint64_t* wide_of(const LaneParamsOf<T>* u, F T::*m) {
  const size_t f = size_t(reinterpret_cast<const char*>(&(u->p.*m)) - reinterpret_cast<const char*>(&u->p)) / 8;
  return u->wide[f];
}
template <class T>
LANES_FN V par_load(const LaneParamsOf<T>* u, double T::*m) {
  return V(_mm256_load_pd(reinterpret_cast<const double*>(wide_of(u, m))));
}
template <class T>
LANES_FN M par_load(const LaneParamsOf<T>* u, uint64_t T::*m) {
  return M(_mm256_load_si256(reinterpret_cast<const __m256i*>(wide_of(u, m))));
}

#include "sim/lanes_body.hpp"

}  // namespace

COHDEM_LANE_ENTRIES(COHDEM_LANE_DEFINE, avx2)

#else

COHDEM_LANE_ENTRIES(COHDEM_LANE_STUB, avx2)

#endif

}  // namespace cohdem
