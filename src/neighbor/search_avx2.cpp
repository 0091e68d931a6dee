// The list build's pair search in AVX2 registers (see search.hpp).
#include "neighbor/search.hpp"

#include <algorithm>
#include <cstring>

#include "core/pack_table.hpp"
#include "particles/particle_store.hpp"

#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace cohdem {

#if defined(__x86_64__)

namespace {

/// The lanes of a group with c candidates left in its range (c >= 4: all four).
constexpr uint32_t kLanesIn[5] = {0x0, 0x1, 0x3, 0x7, 0xF};

}  // namespace

__attribute__((target("avx2,popcnt"))) size_t search_avx2(const SearchInput& s, const uint32_t a, const Vec3& xa,
                                                          const double ra, const bool fixed_a, const int nr,
                                                          const uint32_t* q0, const uint32_t* q1, const uint8_t* img,
                                                          uint64_t* const key, uint8_t* const image, size_t k) {
  const double* const __restrict cx = s.x;
  const double* const __restrict cy = s.y;
  const double* const __restrict cz = s.z;
  const double* const __restrict cr = s.r;
  const __m256d rav = _mm256_set1_pd(ra);
  const __m256i av = _mm256_set1_epi64x(int64_t(a));
  const __m256i ahi = _mm256_slli_epi64(av, 32);
  for (int r = 0; r < nr; ++r) {
    const uint8_t im = img[r], back = uint8_t(26 - im);  // back: a seen from b
    const Vec3 xs = xa - s.shift[im];
    const __m256d xsx = _mm256_set1_pd(xs.x), xsy = _mm256_set1_pd(xs.y), xsz = _mm256_set1_pd(xs.z);
    const uint32_t im4 = uint32_t(im) * 0x01010101u, back4 = uint32_t(back) * 0x01010101u;
    const uint32_t e = q1[r];
    for (uint32_t t = q0[r]; t < e; t += 4) {
      const __m256d dx = _mm256_sub_pd(xsx, _mm256_loadu_pd(cx + t));
      const __m256d dy = _mm256_sub_pd(xsy, _mm256_loadu_pd(cy + t));
      const __m256d dz = _mm256_sub_pd(xsz, _mm256_loadu_pd(cz + t));
      const __m256d d2 = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(dx, dx), _mm256_mul_pd(dy, dy)), _mm256_mul_pd(dz, dz));
      const __m256d rc = _mm256_add_pd(rav, _mm256_loadu_pd(cr + t));
      uint32_t m = uint32_t(_mm256_movemask_pd(_mm256_cmp_pd(d2, _mm256_mul_pd(rc, rc), _CMP_LT_OQ)));
      m &= kLanesIn[std::min(e - t, 4u)];  // not the lanes past the range (no branch: ranges are short)
      if (fixed_a)  // pairs of two fixed bodies are not listed
        for (uint32_t l = 0; l < 4; ++l) m &= ~(uint32_t(s.flag[s.index[t + l]] != kFree) << l);
      // Keys (lower << 32 | higher) and images (of the higher, seen from the lower).
      const __m256i bv = _mm256_cvtepu32_epi64(_mm_loadu_si128(reinterpret_cast<const __m128i*>(s.index + t)));
      const __m256i lower = _mm256_cmpgt_epi64(bv, av);  // a < b (indices below 2^32)
      const __m256i kv = _mm256_blendv_epi8(_mm256_or_si256(_mm256_slli_epi64(bv, 32), av), _mm256_or_si256(ahi, bv), lower);
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(key + k),
                          _mm256_permutevar8x32_epi32(kv, _mm256_load_si256(reinterpret_cast<const __m256i*>(kPack.dbl[m]))));
      const uint32_t lm = uint32_t(_mm256_movemask_pd(_mm256_castsi256_pd(lower)));
      const uint32_t sel = ((lm * 0x204081u) & 0x01010101u) * 0xFFu;  // byte l all ones where lane l is lower
      const uint32_t w = (im4 & sel) | (back4 & ~sel);
      const uint32_t packed = uint32_t(_mm_cvtsi128_si32(
          _mm_shuffle_epi8(_mm_cvtsi32_si128(int32_t(w)), _mm_load_si128(reinterpret_cast<const __m128i*>(kPack.u8[m])))));
      std::memcpy(image + k, &packed, sizeof packed);
      k += size_t(__builtin_popcount(m));
    }
  }
  return k;
}

#else

size_t search_avx2(const SearchInput&, uint32_t, const Vec3&, double, bool, int, const uint32_t*, const uint32_t*,
                   const uint8_t*, uint64_t*, uint8_t*, const size_t k) {
  return k;  // never called: the build searches with the portable loop
}

#endif

}  // namespace cohdem
