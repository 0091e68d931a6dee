// The force loop's screening in AVX-512 registers (see screen.hpp): the AVX2 screening's
// algorithm eight entries at a time, with the picked lanes left-packed by the CPU's own
// compress instructions instead of a permutation table. The same operations in the same
// order as the scalar screening, so the same hits bit for bit: no fused multiply-add (this
// file is compiled with -ffp-contract=off, CMakeLists.txt: AVX-512 has them, and a fused
// product and sum rounds once where the scalar screening rounds twice). Compiled for AVX-512
// F, VL, DQ and BW alone, and chosen at run time where the CPU and the operating system have
// them (screen_avx512_enabled).
// GCC 12's AVX-512 intrinsics read a deliberately undefined register (the unused lanes of a
// cast or of a mask's merge source) and warn that it may be uninitialised (GCC bug 105593);
// silenced for the headers, which must come after this line.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"

#include "sim/screen.hpp"

#include <algorithm>
#include <cstring>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace cohdem {

#if defined(__x86_64__)

#define COHDEM_AVX512 __attribute__((target("avx512f,avx512vl,avx512dq,avx512bw,popcnt")))

namespace {

/// x, y, z and r of eight particles (of indices j[0..7]), one lane each.
struct Lanes8 { __m512d x, y, z, r; };

/// Two doubles at p and q as one 16-byte lane.
COHDEM_AVX512 inline __m128d pair(const double* p, const double* q) { return _mm_loadh_pd(_mm_load_sd(p), q); }

COHDEM_AVX512 inline __m512d four128(const __m128d a, const __m128d b, const __m128d c, const __m128d d) {
  const __m256d lo = _mm256_insertf128_pd(_mm256_castpd128_pd256(a), b, 1);
  const __m256d hi = _mm256_insertf128_pd(_mm256_castpd128_pd256(c), d, 1);
  return _mm512_insertf64x4(_mm512_castpd256_pd512(lo), hi, 1);
}

COHDEM_AVX512 inline Lanes8 load_lanes(const Vec3* __restrict x, const double* __restrict radius, const uint32_t* j) {
  // x and y of the even lanes and of the odd lanes, 16 bytes each; unpacking them gives the
  // lanes in order.
  const __m512d t0 = four128(_mm_loadu_pd(&x[j[0]].x), _mm_loadu_pd(&x[j[2]].x), _mm_loadu_pd(&x[j[4]].x),
                             _mm_loadu_pd(&x[j[6]].x));
  const __m512d t1 = four128(_mm_loadu_pd(&x[j[1]].x), _mm_loadu_pd(&x[j[3]].x), _mm_loadu_pd(&x[j[5]].x),
                             _mm_loadu_pd(&x[j[7]].x));
  Lanes8 L;
  L.x = _mm512_unpacklo_pd(t0, t1);
  L.y = _mm512_unpackhi_pd(t0, t1);
  L.z = four128(pair(&x[j[0]].z, &x[j[1]].z), pair(&x[j[2]].z, &x[j[3]].z), pair(&x[j[4]].z, &x[j[5]].z),
                pair(&x[j[6]].z, &x[j[7]].z));
  L.r = four128(pair(&radius[j[0]], &radius[j[1]]), pair(&radius[j[2]], &radius[j[3]]),
                pair(&radius[j[4]], &radius[j[5]]), pair(&radius[j[6]], &radius[j[7]]));
  return L;
}

}  // namespace

COHDEM_AVX512 uint32_t screen_avx512(const ScreenInput& s, const long i0, const long i1, const long b,
                                     const uint32_t kb, const uint32_t ke, ScreenHits& h) {
  const uint32_t* const __restrict start = s.start;
  const uint32_t* const __restrict jdx = s.jdx;
  const uint8_t* const __restrict image = s.image;
  const uint8_t* const __restrict live = s.live;
  const Vec3* const __restrict x = s.x;
  const double* const __restrict radius = s.radius;
  const Vec3* const __restrict shift = s.shift;
  constexpr uint64_t kAllInPlace = 0x0101010101010101ull * kNoShift;
  // Each entry's row, and its row particle's x, y, z and radius, for entries kb.. (eight at
  // a time; a row's last store runs into the next row's slots, which that row then writes):
  // a group then reads its rows' particles as four plain loads instead of assembling them
  // lane by lane (24 loads and the shuffles to place them: the screening's bottleneck).
  // A row of at most four entries (most rows of the gas, the chute and the bed) is written
  // four lanes wide: eight-lane stores at a row's offset, not a multiple of eight, each
  // straddle two cache lines, and these stores held a quarter of the screening's samples
  // in the 10^6 gas (perf). The 10^4 gas 1.037x, the chute 1.004x, the same bits
  // (docs/performance-history.md, sixty-eighth round); four lanes for every row lost 1.2-1.7 %
  // on the chute, whose longer rows then take two rounds of stores.
  uint32_t erow[kBatch + 8];
  alignas(64) double ex[kBatch + 8], ey[kBatch + 8], ez[kBatch + 8], erad[kBatch + 8];
  auto mark = [&](const long i, const uint32_t k0, const uint32_t k1)
                  __attribute__((target("avx512f,avx512vl"), always_inline)) {
    const __m512d bx = _mm512_set1_pd(x[i].x), by = _mm512_set1_pd(x[i].y), bz = _mm512_set1_pd(x[i].z),
                  br = _mm512_set1_pd(radius[i]);
    if (k1 - k0 <= 4) {
      const uint32_t o = k0 - kb;
      _mm_storeu_si128(reinterpret_cast<__m128i*>(erow + o), _mm_set1_epi32(int32_t(i)));
      _mm256_storeu_pd(ex + o, _mm512_castpd512_pd256(bx));
      _mm256_storeu_pd(ey + o, _mm512_castpd512_pd256(by));
      _mm256_storeu_pd(ez + o, _mm512_castpd512_pd256(bz));
      _mm256_storeu_pd(erad + o, _mm512_castpd512_pd256(br));
      return;
    }
    const __m256i rv = _mm256_set1_epi32(int32_t(i));
    for (uint32_t k = k0; k < k1; k += 8) {
      const uint32_t o = k - kb;
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(erow + o), rv);
      _mm512_storeu_pd(ex + o, bx);
      _mm512_storeu_pd(ey + o, by);
      _mm512_storeu_pd(ez + o, bz);
      _mm512_storeu_pd(erad + o, br);
    }
  };
  for (long i = i0; i <= i1 && i < b; ++i)
    mark(i, std::max(start[i], kb), std::min(start[i + 1], ke));
  // The lanes past the batch's end read a valid row (and are not picked).
  mark(i0, ke, ke + 8);
  // Groups of eight read whole groups inside the list only; the list's last entries singly.
  const uint32_t full = s.entries >= 8 ? s.entries - 7 : 0;
  const uint32_t kg = std::min(ke, full);
  const __m256i step = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  uint32_t nh = 0;
  uint32_t k = kb;
  for (; k < kg; k += 8) {
    const uint32_t o = k - kb;
    const uint32_t* const er = erow + o;
    Lanes8 I;
    I.x = _mm512_loadu_pd(ex + o);
    I.y = _mm512_loadu_pd(ey + o);
    I.z = _mm512_loadu_pd(ez + o);
    I.r = _mm512_loadu_pd(erad + o);
    Lanes8 J = load_lanes(x, radius, jdx + k);
    uint64_t im8;
    std::memcpy(&im8, image + k, sizeof im8);
    if (im8 != kAllInPlace) {
      // The periodic shifts of the lanes that have one, gathered from the (small, cached)
      // table and added to those lanes only, as screen_entry does.
      const __m256i imv = _mm256_cvtepu8_epi32(_mm_cvtsi64_si128(int64_t(im8)));
      const __mmask8 sh = _mm256_cmpneq_epi32_mask(imv, _mm256_set1_epi32(kNoShift));
      const __m256i i3 = _mm256_add_epi32(imv, _mm256_add_epi32(imv, imv));
      const __m512d zero = _mm512_setzero_pd();
      J.x = _mm512_mask_add_pd(J.x, sh, J.x, _mm512_mask_i32gather_pd(zero, sh, i3, &shift[0].x, 8));
      J.y = _mm512_mask_add_pd(J.y, sh, J.y, _mm512_mask_i32gather_pd(zero, sh, i3, &shift[0].y, 8));
      J.z = _mm512_mask_add_pd(J.z, sh, J.z, _mm512_mask_i32gather_pd(zero, sh, i3, &shift[0].z, 8));
    }
    const __m512d dx = _mm512_sub_pd(I.x, J.x), dy = _mm512_sub_pd(I.y, J.y), dz = _mm512_sub_pd(I.z, J.z);
    const __m512d d2 = _mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(dx, dx), _mm512_mul_pd(dy, dy)), _mm512_mul_pd(dz, dz));
    const __m512d rs = _mm512_add_pd(I.r, J.r);
    uint64_t lv8;
    std::memcpy(&lv8, live + k, sizeof lv8);
    const __m128i lv = _mm_cvtsi64_si128(int64_t(lv8));
    __mmask8 m = _mm512_cmp_pd_mask(d2, _mm512_mul_pd(rs, rs), _CMP_LT_OQ) | __mmask8(_mm_test_epi8_mask(lv, lv));
    // Lanes inside the batch only.
    if (ke - k < 8) m &= __mmask8((1u << (ke - k)) - 1u);
    ScreenHits* hp = &h;
    asm("" : "+r"(hp));
    _mm512_storeu_pd(hp->dx + nh, _mm512_maskz_compress_pd(m, dx));
    _mm512_storeu_pd(hp->dy + nh, _mm512_maskz_compress_pd(m, dy));
    _mm512_storeu_pd(hp->dz + nh, _mm512_maskz_compress_pd(m, dz));
    _mm512_storeu_pd(hp->d2 + nh, _mm512_maskz_compress_pd(m, d2));
    const __m256i kv = _mm256_add_epi32(_mm256_set1_epi32(int32_t(k)), step);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(hp->k + nh), _mm256_maskz_compress_epi32(m, kv));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(hp->row + nh),
                        _mm256_maskz_compress_epi32(m, _mm256_loadu_si256(reinterpret_cast<const __m256i*>(er))));
    nh += uint32_t(__builtin_popcount(unsigned(m)));
  }
  for (; k < ke; ++k) {  // the list's last entries
    const uint32_t i = erow[k - kb];
    nh += screen_entry(s, load_xy(x[i]), x[i].z, radius[i], i, k, nh, h);
  }
  return nh;
}

bool avx512_available() {
  return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") &&
         __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512bw");
}

#else

uint32_t screen_avx512(const ScreenInput& s, const long i0, const long i1, const long b, const uint32_t kb,
                       const uint32_t ke, ScreenHits& h) {
  return screen_scalar(s, i0, i1, b, kb, ke, h);
}
bool avx512_available() { return false; }

#endif

}  // namespace cohdem
