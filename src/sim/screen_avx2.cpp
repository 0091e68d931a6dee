// The force loop's screening in AVX2 registers (see screen.hpp): the batch's entries four at
// a time across rows (each lane reads its own row's particle from per-entry copies made once
// per row, so short rows leave no lane idle), periodic shifts gathered for the lanes that
// have one, the picked ones left-packed into ScreenHits with one permutation per array. The
// function is compiled for AVX2 alone (no FMA: a fused multiply-add would round d2
// differently from the scalar screening) and called only when the CPU has it.
#include "sim/screen.hpp"

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <cstring>

#include "core/pack_table.hpp"

#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace cohdem {

namespace {

std::atomic<int> g_avx2{-1};    // -1: not decided yet (read by every force call)
std::atomic<int> g_avx512{-1};  // the same for the AVX-512 screening

#if defined(__x86_64__)

/// Stores the lanes of v in the order of the permutation p (32-bit halves) at dst.
__attribute__((target("avx2"), always_inline)) inline void put_packed(double* dst, const __m256d v, const __m256i p) {
  _mm256_storeu_pd(dst, _mm256_castps_pd(_mm256_permutevar8x32_ps(_mm256_castpd_ps(v), p)));
}

/// x, y, z and r of four particles (of indices j0..j3), one lane each.
struct Lanes { __m256d x, y, z, r; };
__attribute__((target("avx2"), always_inline)) inline Lanes load_lanes(const Vec3* __restrict x,
                                                                       const double* __restrict radius, const uint32_t j0,
                                                                       const uint32_t j1, const uint32_t j2, const uint32_t j3) {
  const __m256d t0 = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(&x[j0].x)), _mm_loadu_pd(&x[j2].x), 1);
  const __m256d t1 = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(&x[j1].x)), _mm_loadu_pd(&x[j3].x), 1);
  Lanes L;
  L.x = _mm256_unpacklo_pd(t0, t1);
  L.y = _mm256_unpackhi_pd(t0, t1);
  L.z = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadh_pd(_mm_load_sd(&x[j0].z), &x[j1].z)),
                             _mm_loadh_pd(_mm_load_sd(&x[j2].z), &x[j3].z), 1);
  L.r = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadh_pd(_mm_load_sd(&radius[j0]), &radius[j1])),
                             _mm_loadh_pd(_mm_load_sd(&radius[j2]), &radius[j3]), 1);
  return L;
}
#endif

}  // namespace

#if defined(__x86_64__)

__attribute__((target("avx2,popcnt"))) uint32_t screen_avx2(const ScreenInput& s, const long i0, const long i1,
                                                            const long b, const uint32_t kb, const uint32_t ke,
                                                            ScreenHits& h) {
  const uint32_t* const __restrict start = s.start;
  const uint32_t* const __restrict jdx = s.jdx;
  const uint8_t* const __restrict image = s.image;
  const uint8_t* const __restrict live = s.live;
  const Vec3* const __restrict x = s.x;
  const double* const __restrict radius = s.radius;
  const Vec3* const __restrict shift = s.shift;
  constexpr uint32_t kAllInPlace = 0x01010101u * kNoShift;
  // Each entry's row, and its row particle's x, y, z and radius, for entries kb.. (four at a
  // time; a row's last store runs into the next row's slots, which that row then writes): a
  // group then reads its rows' particles as four plain loads, where loading them lane by lane
  // took eight loads and six shuffles.
  uint32_t erow[kBatch + 4];
  alignas(32) double ex[kBatch + 4], ey[kBatch + 4], ez[kBatch + 4], erad[kBatch + 4];
  auto mark = [&](const long i, const uint32_t k0, const uint32_t k1) __attribute__((target("avx2"), always_inline)) {
    const __m128i rv = _mm_set1_epi32(int32_t(i));
    const __m256d bx = _mm256_set1_pd(x[i].x), by = _mm256_set1_pd(x[i].y), bz = _mm256_set1_pd(x[i].z),
                  br = _mm256_set1_pd(radius[i]);
    for (uint32_t k = k0; k < k1; k += 4) {
      const uint32_t o = k - kb;
      _mm_storeu_si128(reinterpret_cast<__m128i*>(erow + o), rv);
      _mm256_storeu_pd(ex + o, bx);
      _mm256_storeu_pd(ey + o, by);
      _mm256_storeu_pd(ez + o, bz);
      _mm256_storeu_pd(erad + o, br);
    }
  };
  for (long i = i0; i <= i1 && i < b; ++i)
    mark(i, std::max(start[i], kb), std::min(start[i + 1], ke));
  // The lanes past the batch's end read a valid row (and are not picked).
  mark(i0, ke, ke + 1);
  const uint32_t full = s.entries >= 4 ? s.entries - 3 : 0;
  const uint32_t kg = std::min(ke, full);
  __m128i kv = _mm_add_epi32(_mm_set1_epi32(int32_t(kb)), _mm_setr_epi32(0, 1, 2, 3));
  const __m128i kev = _mm_set1_epi32(int32_t(ke));
  const __m128i four = _mm_set1_epi32(4);
  const __m128i zero8 = _mm_setzero_si128();
  uint32_t nh = 0;
  uint32_t k = kb;
  for (; k < kg; k += 4) {
    const uint32_t o = k - kb;
    const uint32_t* const er = erow + o;
    Lanes I;
    I.x = _mm256_loadu_pd(ex + o);
    I.y = _mm256_loadu_pd(ey + o);
    I.z = _mm256_loadu_pd(ez + o);
    I.r = _mm256_loadu_pd(erad + o);
    Lanes J = load_lanes(x, radius, jdx[k], jdx[k + 1], jdx[k + 2], jdx[k + 3]);
    uint32_t im4;
    std::memcpy(&im4, image + k, sizeof im4);
    if (im4 != kAllInPlace) {
      // The periodic shifts of the lanes that have one, gathered from the (small, cached)
      // table and added to those lanes only, as screen_entry does.
      const __m128i imv = _mm_cvtepu8_epi32(_mm_cvtsi32_si128(int32_t(im4)));
      const __m256d sh = _mm256_castsi256_pd(
          _mm256_cvtepi32_epi64(_mm_xor_si128(_mm_cmpeq_epi32(imv, _mm_set1_epi32(kNoShift)), _mm_set1_epi32(-1))));
      const __m128i i3 = _mm_add_epi32(imv, _mm_add_epi32(imv, imv));
      const __m256d zero = _mm256_setzero_pd();
      J.x = _mm256_blendv_pd(J.x, _mm256_add_pd(J.x, _mm256_mask_i32gather_pd(zero, &shift[0].x, i3, sh, 8)), sh);
      J.y = _mm256_blendv_pd(J.y, _mm256_add_pd(J.y, _mm256_mask_i32gather_pd(zero, &shift[0].y, i3, sh, 8)), sh);
      J.z = _mm256_blendv_pd(J.z, _mm256_add_pd(J.z, _mm256_mask_i32gather_pd(zero, &shift[0].z, i3, sh, 8)), sh);
    }
    const __m256d dx = _mm256_sub_pd(I.x, J.x), dy = _mm256_sub_pd(I.y, J.y), dz = _mm256_sub_pd(I.z, J.z);
    const __m256d d2 = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(dx, dx), _mm256_mul_pd(dy, dy)), _mm256_mul_pd(dz, dz));
    const __m256d rs = _mm256_add_pd(I.r, J.r);
    uint32_t m = uint32_t(_mm256_movemask_pd(_mm256_cmp_pd(d2, _mm256_mul_pd(rs, rs), _CMP_LT_OQ)));
    uint32_t lv4;
    std::memcpy(&lv4, live + k, sizeof lv4);
    m |= ~uint32_t(_mm_movemask_epi8(_mm_cmpeq_epi8(_mm_cvtsi32_si128(int32_t(lv4)), zero8)));
    // Lanes inside the batch (a signed compare: lists are shorter than 2^31 entries).
    m &= uint32_t(_mm_movemask_ps(_mm_castsi128_ps(_mm_cmpgt_epi32(kev, kv))));
    const __m256i pd = _mm256_load_si256(reinterpret_cast<const __m256i*>(kPack.dbl[m]));
    const __m128i pu = _mm_load_si128(reinterpret_cast<const __m128i*>(kPack.u32[m]));
    ScreenHits* hp = &h;
    asm("" : "+r"(hp));
    put_packed(hp->dx + nh, dx, pd);
    put_packed(hp->dy + nh, dy, pd);
    put_packed(hp->dz + nh, dz, pd);
    put_packed(hp->d2 + nh, d2, pd);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(hp->k + nh), _mm_shuffle_epi8(kv, pu));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(hp->row + nh),
                     _mm_shuffle_epi8(_mm_loadu_si128(reinterpret_cast<const __m128i*>(er)), pu));
    kv = _mm_add_epi32(kv, four);
    nh += uint32_t(__builtin_popcount(m));
  }
  for (; k < ke; ++k) {  // the list's last entries
    const uint32_t i = erow[k - kb];
    nh += screen_entry(s, load_xy(x[i]), x[i].z, radius[i], i, k, nh, h);
  }
  return nh;
}

__attribute__((target("avx2"))) uint32_t max_index_avx2(const uint32_t* p, const uint32_t n, const uint32_t floor) {
  __m256i m = _mm256_set1_epi32(int32_t(floor));
  uint32_t q = 0;
  for (; q + 8 <= n; q += 8) m = _mm256_max_epu32(m, _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p + q)));
  __m128i h = _mm_max_epu32(_mm256_castsi256_si128(m), _mm256_extracti128_si256(m, 1));
  h = _mm_max_epu32(h, _mm_shuffle_epi32(h, _MM_SHUFFLE(1, 0, 3, 2)));
  h = _mm_max_epu32(h, _mm_shuffle_epi32(h, _MM_SHUFFLE(2, 3, 0, 1)));
  return max_index_scalar(p + q, n - q, uint32_t(_mm_cvtsi128_si32(h)));
}

bool screen_avx2_enabled() {
  if (g_avx2 < 0) {
    const char* e = std::getenv("COHDEM_SIMD");
    g_avx2 = (e != nullptr && std::strcmp(e, "0") == 0) ? 0 : (__builtin_cpu_supports("avx2") ? 1 : 0);
  }
  return g_avx2 == 1;
}

bool screen_avx512_enabled() {
  if (g_avx512 < 0) {
    const char* e = std::getenv("COHDEM_SIMD");
    g_avx512 = (e != nullptr && std::strcmp(e, "avx2") == 0) ? 0 : (avx512_available() ? 1 : 0);
  }
  return g_avx512 == 1 && screen_avx2_enabled();
}

const char* screen_simd_name() {
  return screen_avx512_enabled() ? "avx512" : screen_avx2_enabled() ? "avx2" : "scalar";
}

void set_screen_avx2(const bool on) { g_avx2 = (on && __builtin_cpu_supports("avx2")) ? 1 : 0; }
void set_screen_avx512(const bool on) { g_avx512 = (on && avx512_available()) ? 1 : 0; }
bool avx2_available() { return __builtin_cpu_supports("avx2"); }

#else

uint32_t screen_avx2(const ScreenInput& s, const long i0, const long i1, const long b, const uint32_t kb,
                     const uint32_t ke, ScreenHits& h) {
  return screen_scalar(s, i0, i1, b, kb, ke, h);
}
uint32_t max_index_avx2(const uint32_t* p, const uint32_t n, const uint32_t floor) {
  return max_index_scalar(p, n, floor);
}
bool screen_avx2_enabled() { return false; }
bool screen_avx512_enabled() { return false; }
const char* screen_simd_name() { return "scalar"; }
void set_screen_avx2(bool) { g_avx2 = 0; }
void set_screen_avx512(bool) { g_avx512 = 0; }
bool avx2_available() { return false; }

#endif

namespace {
int g_prefetch = -2;  // -2: the environment not read yet; -1: the size rule; 0, 1: forced
}  // namespace

bool force_loop_prefetches(const size_t entries, const size_t particles, const size_t state_bytes) {
  if (g_prefetch == -2) {
    const char* e = std::getenv("COHDEM_PREFETCH");
    g_prefetch = e == nullptr ? -1 : std::strcmp(e, "0") == 0 ? 0 : std::strcmp(e, "1") == 0 ? 1 : -1;
  }
  if (g_prefetch >= 0) return g_prefetch == 1;
  return force_loop_record_bytes(entries, particles, state_bytes) >= kPrefetchBytes;
}

void set_force_loop_prefetch(const int mode) { g_prefetch = mode < 0 ? -1 : mode > 0 ? 1 : 0; }

}  // namespace cohdem
