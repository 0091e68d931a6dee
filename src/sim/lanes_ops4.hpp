// Four doubles in an AVX2 register: the primitives of the lanes of contacts four at a time
// (lanes_avx2.cpp), which the eight-lane AVX-512 lanes (lanes_avx512.cpp) also use for each
// half of a group (loads and stores of the particles' vectors and of the history records,
// transposed). Included by those two files only, inside their anonymous namespace: the
// functions are compiled for AVX2, and inline into callers compiled for AVX2 or AVX-512.
#pragma once
#if !defined(__x86_64__)
#error "sim/lanes_ops4.hpp is for x86-64 builds only"
#endif
#include <immintrin.h>

#include <cstdint>

#include "core/vec3.hpp"

namespace cohdem::lanes4 {

typedef double V4 __attribute__((vector_size(32)));
typedef long long M4 __attribute__((vector_size(32)));  // lane masks: all ones or zero

#define LANES4_FN __attribute__((target("avx2"), always_inline)) inline

/// x, y, z of the Vec3s *a[0..3], one lane each (two 16-byte loads, two inserts and two
/// unpacks for x and y).
LANES4_FN void load3(const Vec3* const* a, V4& x, V4& y, V4& z) {
  const __m256d t0 = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(&a[0]->x)), _mm_loadu_pd(&a[2]->x), 1);
  const __m256d t1 = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(&a[1]->x)), _mm_loadu_pd(&a[3]->x), 1);
  x = V4(_mm256_unpacklo_pd(t0, t1));
  y = V4(_mm256_unpackhi_pd(t0, t1));
  z = V4(_mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadh_pd(_mm_load_sd(&a[0]->z), &a[1]->z)),
                              _mm_loadh_pd(_mm_load_sd(&a[2]->z), &a[3]->z), 1));
}

/// The histories are written back one whole record per lane, from the lanes transposed
/// (unpacks and 128-bit permutes), instead of one double at a time: quads(a, b, c, d).q[l] =
/// {a[l], b[l], c[l], d[l]}, a 32-byte store; pairs(a, b).p[l] = {a[l], b[l]}, a 16-byte store.
struct Quads { __m256d q[4]; };
struct Pairs { __m128d p[4]; };
LANES4_FN Quads quads(const V4 a, const V4 b, const V4 c, const V4 d) {
  const __m256d t0 = _mm256_unpacklo_pd(__m256d(a), __m256d(b));  // a0 b0 a2 b2
  const __m256d t1 = _mm256_unpackhi_pd(__m256d(a), __m256d(b));  // a1 b1 a3 b3
  const __m256d t2 = _mm256_unpacklo_pd(__m256d(c), __m256d(d));  // c0 d0 c2 d2
  const __m256d t3 = _mm256_unpackhi_pd(__m256d(c), __m256d(d));  // c1 d1 c3 d3
  return {{_mm256_permute2f128_pd(t0, t2, 0x20), _mm256_permute2f128_pd(t1, t3, 0x20),
           _mm256_permute2f128_pd(t0, t2, 0x31), _mm256_permute2f128_pd(t1, t3, 0x31)}};
}
LANES4_FN Pairs pairs(const V4 a, const V4 b) {
  const __m256d t0 = _mm256_unpacklo_pd(__m256d(a), __m256d(b));  // a0 b0 a2 b2
  const __m256d t1 = _mm256_unpackhi_pd(__m256d(a), __m256d(b));  // a1 b1 a3 b3
  return {{_mm256_castpd256_pd128(t0), _mm256_castpd256_pd128(t1), _mm256_extractf128_pd(t0, 1),
           _mm256_extractf128_pd(t1, 1)}};
}

/// The record of list entry k as doubles (the loads and stores go to fixed offsets in it).
template <class H>
LANES4_FN double* rec(H* h, const uint32_t k) { return reinterpret_cast<double*>(h + k); }
/// The lanes of the four doubles at offset o of each lane's record (entries k[0..3]), read as
/// the stores write them: a 4x4 transpose is its own inverse.
template <class H>
LANES4_FN Quads load_quads(H* h, const uint32_t* k, const uint32_t o) {
  return quads(V4(_mm256_loadu_pd(rec(h, k[0]) + o)), V4(_mm256_loadu_pd(rec(h, k[1]) + o)),
               V4(_mm256_loadu_pd(rec(h, k[2]) + o)), V4(_mm256_loadu_pd(rec(h, k[3]) + o)));
}
/// The same for two doubles at offset o: their lanes in a, b.
template <class H>
LANES4_FN void load_pairs(H* h, const uint32_t* k, const uint32_t o, V4& a, V4& b) {
  const __m256d t02 =
      _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(rec(h, k[0]) + o)), _mm_loadu_pd(rec(h, k[2]) + o), 1);
  const __m256d t13 =
      _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(rec(h, k[1]) + o)), _mm_loadu_pd(rec(h, k[3]) + o), 1);
  a = V4(_mm256_unpacklo_pd(t02, t13));
  b = V4(_mm256_unpackhi_pd(t02, t13));
}

#undef LANES4_FN

}  // namespace cohdem::lanes4
