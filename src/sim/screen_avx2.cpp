// The force loop's screening in AVX2 registers (see screen.hpp): four entries of a row at a
// time, the picked ones left-packed into ScreenHits with one permutation per array. The
// function is compiled for AVX2 alone (no FMA: a fused multiply-add would round d2
// differently from the scalar screening) and called only when the CPU has it.
#include "sim/screen.hpp"

#include <algorithm>
#include <array>
#include <cstdlib>
#include <cstring>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace cohdem {

namespace {

int g_avx2 = -1;  // -1: not decided yet

#if defined(__x86_64__)
/// For each 4-bit mask of picked lanes, the lanes in ascending order, then lane 0 again:
/// as 32-bit halves for vpermps on doubles, and as bytes for pshufb on 32-bit entries.
struct PackTable {
  alignas(32) int32_t dbl[16][8];
  alignas(16) uint8_t u32[16][16];
};
constexpr PackTable make_pack_table() {
  PackTable t{};
  for (int m = 0; m < 16; ++m) {
    int n = 0;
    std::array<int, 4> lanes{0, 0, 0, 0};
    for (int l = 0; l < 4; ++l)
      if (m & (1 << l)) lanes[size_t(n++)] = l;
    for (int o = 0; o < 4; ++o) {
      const int l = lanes[size_t(o)];
      t.dbl[m][2 * o] = 2 * l;
      t.dbl[m][2 * o + 1] = 2 * l + 1;
      for (int b = 0; b < 4; ++b) t.u32[m][4 * o + b] = uint8_t(4 * l + b);
    }
  }
  return t;
}
constexpr PackTable kPack = make_pack_table();

/// Stores the lanes of v in the order of the permutation p (32-bit halves) at dst.
__attribute__((target("avx2"), always_inline)) inline void put_packed(double* dst, const __m256d v, const __m256i p) {
  _mm256_storeu_pd(dst, _mm256_castps_pd(_mm256_permutevar8x32_ps(_mm256_castpd_ps(v), p)));
}
#endif

}  // namespace

#if defined(__x86_64__)

namespace {

/// Adds the periodic shifts of the group of four entries from k, lane by lane as
/// screen_entry does (only where an entry has one). Out of line: rare, and inline its
/// registers would spill the common path's.
[[gnu::noinline]] __attribute__((target("avx2"))) void shift_lanes(const ScreenInput& s, const uint32_t k, __m256d* xyz) {
  alignas(32) double px[4], py[4], pz[4];
  _mm256_store_pd(px, xyz[0]);
  _mm256_store_pd(py, xyz[1]);
  _mm256_store_pd(pz, xyz[2]);
  for (int l = 0; l < 4; ++l) {
    const uint8_t im = s.image[k + uint32_t(l)];
    if (im != kNoShift) {
      px[l] += s.shift[im].x;
      py[l] += s.shift[im].y;
      pz[l] += s.shift[im].z;
    }
  }
  xyz[0] = _mm256_load_pd(px);
  xyz[1] = _mm256_load_pd(py);
  xyz[2] = _mm256_load_pd(pz);
}

}  // namespace

__attribute__((target("avx2,popcnt"))) uint32_t screen_avx2(const ScreenInput& s, const long i0, const long i1,
                                                            const long b, const uint32_t kb, const uint32_t ke,
                                                            ScreenHits& h) {
  const uint32_t* const __restrict start = s.start;
  const uint32_t* const __restrict jdx = s.jdx;
  const uint8_t* const __restrict image = s.image;
  const uint8_t* const __restrict live = s.live;
  const Vec3* const __restrict x = s.x;
  const double* const __restrict radius = s.radius;
  Vec3* const __restrict force = s.force;
  Vec3* const __restrict torque = s.torque;
  constexpr uint32_t kAllInPlace = 0x01010101u * kNoShift;
  // Groups of four start below `full`: their four entries lie in the list.
  const uint32_t full = s.entries >= 4 ? s.entries - 3 : 0;
  const __m128i four = _mm_set1_epi32(4);
  const __m128i zero8 = _mm_setzero_si128();
  uint32_t nh = 0;
  for (long i = i0; i <= i1 && i < b; ++i) {
    const uint32_t k0 = std::max(start[i], kb), k1 = std::min(start[i + 1], ke);
    if (start[i] >= kb) {
      force[i] = Vec3{};
      torque[i] = Vec3{};
    }
    const __m256d xi = _mm256_set1_pd(x[i].x), yi = _mm256_set1_pd(x[i].y), zi = _mm256_set1_pd(x[i].z);
    const double ri = radius[i];
    const __m256d riv = _mm256_set1_pd(ri);
    const __m128i rowv = _mm_set1_epi32(int32_t(i));
    __m128i kv = _mm_add_epi32(_mm_set1_epi32(int32_t(k0)), _mm_setr_epi32(0, 1, 2, 3));  // the lanes' entries
    const __m128i k1v = _mm_set1_epi32(int32_t(k1));  // signed compare: the list is shorter than 2^31 entries
    uint32_t k = k0;
    // Lanes past the row's end are read (entries of the next rows, valid partners) and not
    // picked; the list's last three entries go one at a time.
    const uint32_t kg = std::min(k1, full);
    for (; k < kg; k += 4) {
      const uint32_t j0 = jdx[k], j1 = jdx[k + 1], j2 = jdx[k + 2], j3 = jdx[k + 3];
      // x and y of the four partners: (x0 y0 x2 y2), (x1 y1 x3 y3) -> (x0 x1 x2 x3), (y0 ..).
      const __m256d t0 = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(&x[j0].x)), _mm_loadu_pd(&x[j2].x), 1);
      const __m256d t1 = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(&x[j1].x)), _mm_loadu_pd(&x[j3].x), 1);
      __m256d X = _mm256_unpacklo_pd(t0, t1), Y = _mm256_unpackhi_pd(t0, t1);
      __m256d Z = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadh_pd(_mm_load_sd(&x[j0].z), &x[j1].z)),
                                       _mm_loadh_pd(_mm_load_sd(&x[j2].z), &x[j3].z), 1);
      const __m256d R = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadh_pd(_mm_load_sd(&radius[j0]), &radius[j1])),
                                             _mm_loadh_pd(_mm_load_sd(&radius[j2]), &radius[j3]), 1);
      uint32_t im4;
      std::memcpy(&im4, image + k, sizeof im4);
      if (im4 != kAllInPlace) [[unlikely]] {
        __m256d xyz[3] = {X, Y, Z};  // a copy: X, Y and Z stay in registers on the common path
        shift_lanes(s, k, xyz);
        X = xyz[0];
        Y = xyz[1];
        Z = xyz[2];
      }
      const __m256d dx = _mm256_sub_pd(xi, X), dy = _mm256_sub_pd(yi, Y), dz = _mm256_sub_pd(zi, Z);
      const __m256d d2 = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(dx, dx), _mm256_mul_pd(dy, dy)), _mm256_mul_pd(dz, dz));
      const __m256d rs = _mm256_add_pd(riv, R);
      uint32_t m = uint32_t(_mm256_movemask_pd(_mm256_cmp_pd(d2, _mm256_mul_pd(rs, rs), _CMP_LT_OQ)));
      uint32_t lv4;
      std::memcpy(&lv4, live + k, sizeof lv4);
      m |= ~uint32_t(_mm_movemask_epi8(_mm_cmpeq_epi8(_mm_cvtsi32_si128(int32_t(lv4)), zero8)));
      m &= uint32_t(_mm_movemask_ps(_mm_castsi128_ps(_mm_cmpgt_epi32(k1v, kv))));  // lanes of the row
      // Left-pack the picked lanes: all four lanes are written, nh advances by the picked.
      const __m256i pd = _mm256_load_si256(reinterpret_cast<const __m256i*>(kPack.dbl[m]));
      // hp: &h, hidden from the optimiser in each group, so that it addresses the six arrays
      // as hp + constant + nh (one register) instead of keeping six pointers on the stack.
      ScreenHits* hp = &h;
      asm("" : "+r"(hp));
      put_packed(hp->dx + nh, dx, pd);
      put_packed(hp->dy + nh, dy, pd);
      put_packed(hp->dz + nh, dz, pd);
      put_packed(hp->d2 + nh, d2, pd);
      _mm_storeu_si128(reinterpret_cast<__m128i*>(hp->k + nh),
                       _mm_shuffle_epi8(kv, _mm_load_si128(reinterpret_cast<const __m128i*>(kPack.u32[m]))));
      _mm_storeu_si128(reinterpret_cast<__m128i*>(hp->row + nh), rowv);
      kv = _mm_add_epi32(kv, four);
      nh += uint32_t(__builtin_popcount(m));
    }
    if (k < k1) [[unlikely]] {
      const V2 xi_xy = load_xy(x[i]);
      for (; k < k1; ++k) nh += screen_entry(s, xi_xy, x[i].z, ri, uint32_t(i), k, nh, h);
    }
  }
  return nh;
}

bool screen_avx2_enabled() {
  if (g_avx2 < 0) {
    const char* e = std::getenv("COHDEM_SIMD");
    g_avx2 = (e != nullptr && std::strcmp(e, "0") == 0) ? 0 : (__builtin_cpu_supports("avx2") ? 1 : 0);
  }
  return g_avx2 == 1;
}

void set_screen_avx2(const bool on) { g_avx2 = (on && __builtin_cpu_supports("avx2")) ? 1 : 0; }

#else

uint32_t screen_avx2(const ScreenInput& s, const long i0, const long i1, const long b, const uint32_t kb,
                     const uint32_t ke, ScreenHits& h) {
  return screen_scalar(s, i0, i1, b, kb, ke, h);
}
bool screen_avx2_enabled() { return false; }
void set_screen_avx2(bool) { g_avx2 = 0; }

#endif

}  // namespace cohdem
