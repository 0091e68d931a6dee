// The finish of free particles four at a time (finish.hpp). The particles' vectors are
// stored x, y, z one particle after the other, so four particles' are twelve consecutive
// doubles, three AVX2 registers; every operation of the finish is component by component
// (a sum, or a product with a per-particle scalar: spread over the pattern of the
// components), so it runs on those registers as they are, without transposing. Compiled
// for AVX2 alone (no FMA: a fused multiply-add rounds differently from the scalar finish).
#include "sim/finish.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace cohdem {

#if defined(__x86_64__)

namespace {

/// A per-particle scalar of four particles, s = [s0 s1 s2 s3], spread over the components of
/// their twelve doubles: [s0 s0 s0 s1], [s1 s1 s2 s2], [s2 s3 s3 s3].
struct Spread { __m256d a, b, c; };
__attribute__((target("avx2"), always_inline)) inline Spread spread(const __m256d s) {
  return {_mm256_permute4x64_pd(s, 0x40), _mm256_permute4x64_pd(s, 0xA5), _mm256_permute4x64_pd(s, 0xFE)};
}

/// Asks for the cache line that holds byte `bytes` after p (for writing when kWrite). The
/// address is formed as an integer: it may lie past the arrays' ends (a prefetch never
/// faults), where pointer arithmetic would not be allowed.
template <int kWrite>
__attribute__((always_inline)) inline void ask(const void* p, const size_t bytes) {
  __builtin_prefetch(reinterpret_cast<const void*>(reinterpret_cast<uintptr_t>(p) + bytes), kWrite, 3);
}

/// Two doubles at p and q as one 16-byte lane.
__attribute__((target("avx2"), always_inline)) inline __m128d pair(const double* p, const double* q) {
  return _mm_loadh_pd(_mm_load_sd(p), q);
}
__attribute__((target("avx2"), always_inline)) inline __m256d join(const __m128d lo, const __m128d hi) {
  return _mm256_insertf128_pd(_mm256_castpd128_pd256(lo), hi, 1);
}

}  // namespace

__attribute__((target("avx2"))) long finish_free_avx2(const FinishFree& f, long i, const long e, Drift& d) {
  static_assert(sizeof(Vec3) == 3 * sizeof(double) && sizeof(PairResult) == 6 * sizeof(double));
  double* const __restrict x = &f.x[0].x;
  double* const __restrict v = &f.v[0].x;
  double* const __restrict w = &f.omega[0].x;
  double* const __restrict rev = &f.rev[0].f.x;
  const double* const __restrict ref = &f.ref[0].x;
  const double* const __restrict mass = f.mass;
  const double* const __restrict inertia = f.inertia;
  const uint8_t* const __restrict flag = f.flag;
  const uint32_t* const __restrict wstart = f.wstart;
  const Vec3 g = f.grav;
  const __m256d g0 = _mm256_setr_pd(g.x, g.y, g.z, g.x), g1 = _mm256_setr_pd(g.y, g.z, g.x, g.y),
                g2 = _mm256_setr_pd(g.z, g.x, g.y, g.z);
  const __m256d kh = _mm256_set1_pd(f.kick_h), dt = _mm256_set1_pd(f.open_dt), zero = _mm256_setzero_pd();
  constexpr double kInf = Drift::kInf;
  __m256d lo0 = _mm256_set1_pd(kInf), lo1 = lo0, lo2 = lo0;
  __m256d hi0 = _mm256_set1_pd(-kInf), hi1 = hi0, hi2 = hi0;
  double dmax2 = d.dmax2;
  alignas(32) double q[12];
  for (; i + 4 <= e; i += 4) {
    uint32_t fl;
    std::memcpy(&fl, flag + i, sizeof fl);
    static_assert(kFree == 0);
    if (fl != 0 || wstart[i + 4] != wstart[i]) break;
    const size_t o = size_t(i) * 3;
    // The lines of the particles kFinishAhead on (finish.hpp): 96 bytes of each Vec3 array,
    // 192 of the sums, 32 of mass and inertia per group of four (a line asked for twice is
    // asked for at no cost worth counting; a span's last line is asked for by the next group).
    {
      constexpr size_t kA = kFinishAhead;
      const size_t ov = (o + 3 * kA) * sizeof(double), orv = (size_t(i) + kA) * sizeof(PairResult);
      ask<1>(v, ov);
      ask<1>(v, ov + 64);
      ask<1>(w, ov);
      ask<1>(w, ov + 64);
      ask<0>(ref, ov);
      ask<0>(ref, ov + 64);
      ask<1>(rev, orv);
      ask<1>(rev, orv + 64);
      ask<1>(rev, orv + 128);
      ask<0>(mass, (size_t(i) + kA) * sizeof(double));
      ask<0>(inertia, (size_t(i) + kA) * sizeof(double));
      ask<0>(flag, size_t(i) + kA);
      ask<0>(wstart, (size_t(i) + kA) * sizeof(uint32_t));
    }
    // The reverse sums (f, tj) of the four particles: f of particle p at rp[6p..6p+2], tj at
    // rp[6p+3..6p+5], read into the component pattern, then zeroed for the next call.
    double* const rp = rev + size_t(i) * 6;
    const __m256d rf0 = join(_mm_loadu_pd(rp + 0), pair(rp + 2, rp + 6));
    const __m256d rf1 = join(_mm_loadu_pd(rp + 7), _mm_loadu_pd(rp + 12));
    const __m256d rf2 = join(pair(rp + 14, rp + 18), _mm_loadu_pd(rp + 19));
    const __m256d rt0 = join(_mm_loadu_pd(rp + 3), pair(rp + 5, rp + 9));
    const __m256d rt1 = join(_mm_loadu_pd(rp + 10), _mm_loadu_pd(rp + 15));
    const __m256d rt2 = join(pair(rp + 17, rp + 21), _mm_loadu_pd(rp + 22));
    for (int k = 0; k < 6; ++k) _mm256_storeu_pd(rp + 4 * k, zero);
    // F = R + grav m, T = RT: the particles' final force and torque (R holds the sums of
    // all their pairs, their own rows' included). Used by the kicks and not stored: in a
    // fused call nothing reads a free particle's force afterwards (ForceContext::open_dt).
    const __m256d m = _mm256_loadu_pd(mass + i);
    const Spread ms = spread(m);
    const __m256d F0 = _mm256_add_pd(rf0, _mm256_mul_pd(g0, ms.a));
    const __m256d F1 = _mm256_add_pd(rf1, _mm256_mul_pd(g1, ms.b));
    const __m256d F2 = _mm256_add_pd(rf2, _mm256_mul_pd(g2, ms.c));
    const __m256d T0 = rt0, T1 = rt1, T2 = rt2;
    // The closing half-kick, then the opening one and the drift: v + F hm + F hm, x + v dt.
    const Spread hm = spread(_mm256_div_pd(kh, m));
    const Spread hI = spread(_mm256_div_pd(kh, _mm256_loadu_pd(inertia + i)));
    const __m256d fm0 = _mm256_mul_pd(F0, hm.a), fm1 = _mm256_mul_pd(F1, hm.b), fm2 = _mm256_mul_pd(F2, hm.c);
    const __m256d V0 = _mm256_add_pd(_mm256_add_pd(_mm256_loadu_pd(v + o), fm0), fm0);
    const __m256d V1 = _mm256_add_pd(_mm256_add_pd(_mm256_loadu_pd(v + o + 4), fm1), fm1);
    const __m256d V2 = _mm256_add_pd(_mm256_add_pd(_mm256_loadu_pd(v + o + 8), fm2), fm2);
    const __m256d tI0 = _mm256_mul_pd(T0, hI.a), tI1 = _mm256_mul_pd(T1, hI.b), tI2 = _mm256_mul_pd(T2, hI.c);
    _mm256_storeu_pd(w + o, _mm256_add_pd(_mm256_add_pd(_mm256_loadu_pd(w + o), tI0), tI0));
    _mm256_storeu_pd(w + o + 4, _mm256_add_pd(_mm256_add_pd(_mm256_loadu_pd(w + o + 4), tI1), tI1));
    _mm256_storeu_pd(w + o + 8, _mm256_add_pd(_mm256_add_pd(_mm256_loadu_pd(w + o + 8), tI2), tI2));
    _mm256_storeu_pd(v + o, V0);
    _mm256_storeu_pd(v + o + 4, V1);
    _mm256_storeu_pd(v + o + 8, V2);
    const __m256d X0 = _mm256_add_pd(_mm256_loadu_pd(x + o), _mm256_mul_pd(V0, dt));
    const __m256d X1 = _mm256_add_pd(_mm256_loadu_pd(x + o + 4), _mm256_mul_pd(V1, dt));
    const __m256d X2 = _mm256_add_pd(_mm256_loadu_pd(x + o + 8), _mm256_mul_pd(V2, dt));
    _mm256_storeu_pd(x + o, X0);
    _mm256_storeu_pd(x + o + 4, X1);
    _mm256_storeu_pd(x + o + 8, X2);
    // The displacement since the build: its box (min and max by component, exact in any
    // order) and its largest squared length, (dx dx + dy dy) + dz dz as Drift::add sums it.
    const __m256d D0 = _mm256_sub_pd(X0, _mm256_loadu_pd(ref + o));
    const __m256d D1 = _mm256_sub_pd(X1, _mm256_loadu_pd(ref + o + 4));
    const __m256d D2 = _mm256_sub_pd(X2, _mm256_loadu_pd(ref + o + 8));
    lo0 = _mm256_min_pd(D0, lo0);  // (d < lo) ? d : lo, as std::min(lo, d)
    lo1 = _mm256_min_pd(D1, lo1);
    lo2 = _mm256_min_pd(D2, lo2);
    hi0 = _mm256_max_pd(D0, hi0);  // (d > hi) ? d : hi, as std::max(hi, d)
    hi1 = _mm256_max_pd(D1, hi1);
    hi2 = _mm256_max_pd(D2, hi2);
    _mm256_store_pd(q, _mm256_mul_pd(D0, D0));
    _mm256_store_pd(q + 4, _mm256_mul_pd(D1, D1));
    _mm256_store_pd(q + 8, _mm256_mul_pd(D2, D2));
    for (int p = 0; p < 4; ++p) dmax2 = std::max(dmax2, (q[3 * p] + q[3 * p + 1]) + q[3 * p + 2]);
  }
  d.dmax2 = dmax2;
  alignas(32) double l[12], h[12];
  _mm256_store_pd(l, lo0);
  _mm256_store_pd(l + 4, lo1);
  _mm256_store_pd(l + 8, lo2);
  _mm256_store_pd(h, hi0);
  _mm256_store_pd(h + 4, hi1);
  _mm256_store_pd(h + 8, hi2);
  double* const dlo = &d.lo.x;
  double* const dhi = &d.hi.x;
  for (int k = 0; k < 12; ++k) {
    dlo[k % 3] = std::min(dlo[k % 3], l[k]);
    dhi[k % 3] = std::max(dhi[k % 3], h[k]);
  }
  return i;
}

#else

long finish_free_avx2(const FinishFree&, const long i, long, Drift&) { return i; }

#endif

}  // namespace cohdem
