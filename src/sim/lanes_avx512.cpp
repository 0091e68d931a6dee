// The lanes of contacts in AVX-512 registers, eight at a time (see lanes.hpp): the primitives
// of eight lanes, from which lanes_body.hpp makes the same laws as the four AVX2 lanes do.
// Their loads and stores of the particles' vectors and of the history records go through the
// AVX2 transposes of lanes_ops4.hpp, one half of the group each. Compiled for AVX-512 F, VL,
// DQ and BW and with -ffp-contract=off (CMakeLists.txt): AVX-512 has fused multiply-adds,
// which round once where the scalar law rounds twice. Chosen at run time where the CPU and
// the operating system have AVX-512 (screen_avx512_enabled; COHDEM_SIMD=avx2 selects the four
// AVX2 lanes): the results are the scalar law's bit for bit, as the four lanes' are.
// GCC 12's AVX-512 intrinsics read a deliberately undefined register (GCC bug 105593, see
// screen_avx512.cpp); silenced for the headers, which must come after this line.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <limits>
#include <type_traits>

#include "particles/particle_store.hpp"
#include "sim/lanes.hpp"

#if defined(__x86_64__)
#include <immintrin.h>

#include "sim/lanes_ops4.hpp"
#endif

namespace cohdem {

#if defined(__x86_64__)

namespace {

// The primitives of eight lanes (lanes_body.hpp says what each is).
#define LANES_TARGET "avx512f,avx512vl,avx512dq,avx512bw"
#define LANES_FN __attribute__((target(LANES_TARGET), always_inline)) inline

constexpr uint32_t kW = 8;
typedef double V __attribute__((vector_size(64)));
typedef long long M __attribute__((vector_size(64)));  // lane masks: all ones or zero
using lanes4::V4;

/// The lanes' sign bits as an AVX-512 mask register.
LANES_FN __mmask8 kmask(const M m) { return _mm512_movepi64_mask(__m512i(m)); }
LANES_FN V4 lo(const V a) { return V4(_mm512_castpd512_pd256(__m512d(a))); }
LANES_FN V4 hi(const V a) { return V4(_mm512_extractf64x4_pd(__m512d(a), 1)); }
LANES_FN V join(const V4 a, const V4 b) {
  return V(_mm512_insertf64x4(_mm512_castpd256_pd512(__m256d(a)), __m256d(b), 1));
}

LANES_FN V sqrtv(const V a) { return V(_mm512_sqrt_pd(__m512d(a))); }
/// std::max(a, 0.0) lane by lane: a < 0 ? 0 : a (a -0 or a NaN passes through, as there).
LANES_FN V max0(const V a) { return V(_mm512_max_pd(_mm512_setzero_pd(), __m512d(a))); }
/// m ? a : b lane by lane, on m's sign bits.
LANES_FN V sel(const M m, const V a, const V b) { return V(_mm512_mask_blend_pd(kmask(m), __m512d(b), __m512d(a))); }
LANES_FN bool any(const M m) { return kmask(m) != 0; }
LANES_FN V splat(const double s) { return V(_mm512_set1_pd(s)); }
LANES_FN M msplat(const long long s) { return M(_mm512_set1_epi64(s)); }
LANES_FN V loadv(const double* src) { return V(_mm512_loadu_pd(src)); }
LANES_FN void store(double* dst, const V a) { _mm512_storeu_pd(dst, __m512d(a)); }
/// {f(0), ..., f(7)}.
template <class F>
LANES_FN V make(F&& f) { return V{f(0), f(1), f(2), f(3), f(4), f(5), f(6), f(7)}; }
template <class F>
LANES_FN M makem(F&& f) { return M{f(0), f(1), f(2), f(3), f(4), f(5), f(6), f(7)}; }
/// Doubles a[idx[0..7]], loaded one by one (the gather instruction measured 3-7 % slower on
/// the Zen 5: BM_LaneWidths, fifty-second round).
LANES_FN V gather(const double* __restrict a, const uint32_t* idx) {
  return V{a[idx[0]], a[idx[1]], a[idx[2]], a[idx[3]], a[idx[4]], a[idx[5]], a[idx[6]], a[idx[7]]};
}
LANES_FN void load3(const Vec3* const* a, V& x, V& y, V& z) {
  V4 x0, y0, z0, x1, y1, z1;
  lanes4::load3(a, x0, y0, z0);
  lanes4::load3(a + 4, x1, y1, z1);
  x = join(x0, x1);
  y = join(y0, y1);
  z = join(z0, z1);
}
/// Each lane's record parts (the four lanes' transposes of each half).
struct Quads { __m256d q[8]; };
struct Pairs { __m128d p[8]; };
LANES_FN Quads quads(const V a, const V b, const V c, const V d) {
  const lanes4::Quads l = lanes4::quads(lo(a), lo(b), lo(c), lo(d)), h = lanes4::quads(hi(a), hi(b), hi(c), hi(d));
  return {{l.q[0], l.q[1], l.q[2], l.q[3], h.q[0], h.q[1], h.q[2], h.q[3]}};
}
LANES_FN Pairs pairs(const V a, const V b) {
  const lanes4::Pairs l = lanes4::pairs(lo(a), lo(b)), h = lanes4::pairs(hi(a), hi(b));
  return {{l.p[0], l.p[1], l.p[2], l.p[3], h.p[0], h.p[1], h.p[2], h.p[3]}};
}
/// Four doubles of each lane's record in eight lanes.
struct Cols { V v[4]; };
template <class H>
LANES_FN Cols load_quads(H* h, const uint32_t* k, const uint32_t o) {
  const lanes4::Quads l = lanes4::load_quads(h, k, o), u = lanes4::load_quads(h, k + 4, o);
  return {{join(V4(l.q[0]), V4(u.q[0])), join(V4(l.q[1]), V4(u.q[1])), join(V4(l.q[2]), V4(u.q[2])),
           join(V4(l.q[3]), V4(u.q[3]))}};
}
template <class H>
LANES_FN void load_pairs(H* h, const uint32_t* k, const uint32_t o, V& a, V& b) {
  V4 a0, b0, a1, b1;
  lanes4::load_pairs(h, k, o, a0, b0);
  lanes4::load_pairs(h, k + 4, o, a1, b1);
  a = join(a0, a1);
  b = join(b0, b1);
}
/// out.alive[g .. g + 8) from the alive lanes (all bits set: 1) in one 8-byte store (lanes
/// past the chunk's end write bytes that no one reads: g + 8 <= kLaneChunk).
LANES_FN void put_alive(const M alive, const uint32_t g, LaneOut& out) {
  const __m128i b = _mm512_cvtepi64_epi8(_mm512_srli_epi64(__m512i(alive), 63));
  _mm_storel_epi64(reinterpret_cast<__m128i*>(out.alive + g), b);
}
/// A uniform group's parameter, broadcast (an operand of the arithmetic where it can be).
template <class T>
LANES_FN V par_load(const LaneParamsOf<T>* u, double T::*m) {
  return splat(u->p.*m);
}
template <class T>
LANES_FN M par_load(const LaneParamsOf<T>* u, uint64_t T::*m) {
  return msplat((long long)(u->p.*m));
}

#include "sim/lanes_body.hpp"

}  // namespace

COHDEM_LANE_ENTRIES(COHDEM_LANE_DEFINE, avx512)

#else

COHDEM_LANE_ENTRIES(COHDEM_LANE_STUB, avx512)

#endif

}  // namespace cohdem
