// The force loop's screening: which list entries of a batch of consecutive rows touch or are
// live, with their pair vectors and squared distances (src/sim/force_kernel.hpp, pass 1).
//
// Three implementations give the same output bit for bit: `screen_scalar` (inline in the
// kernel, any CPU), `screen_avx2` (x86-64 with AVX2, chosen at run time by
// `screen_avx2_enabled`), which screens four consecutive entries at a time (of one row or
// of several), and `screen_avx512` (eight at a time where the CPU has AVX-512,
// `screen_avx512_enabled`). Both compute, per entry, x_j (+ its periodic shift when the entry has one),
// d = x_i - x_j, d2 = (dx dx + dy dy) + dz dz and rsum = r_i + r_j, in that order and
// without fused multiply-adds, and pick the entry when d2 < rsum^2 or it is live; the
// picked entries are listed in ascending order.
#pragma once
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "core/vec3.hpp"
#include "neighbor/neighbor_list.hpp"

namespace cohdem {

/// List entries screened together before their touching ones are evaluated in one loop
/// (chute: about 70 contacts per batch; 128 entries ran about as fast as the old per-row
/// loop, 512 entries 6-11 % faster on the three peer problems).
inline constexpr uint32_t kBatch = 512;

/// The picked entries of one batch (structure of arrays: the AVX2 screening stores four
/// lanes of each at once). Room for kBatch + 8: a group of four (AVX2) or eight (AVX-512)
/// writes all its lanes and counts only the picked ones. Left uninitialised (no zero fill per
/// batch).
struct ScreenHits {
  static constexpr uint32_t kCap = kBatch + 8;
  uint32_t k[kCap];    ///< list entry
  uint32_t row[kCap];  ///< its row (particle i)
  double dx[kCap], dy[kCap], dz[kCap];  ///< x_i - x_j (shifted image)
  double d2[kCap];     ///< |x_i - x_j|^2
};

/// What the screening reads: the list's and the particles' arrays.
struct ScreenInput {
  const uint32_t* start;
  const uint32_t* jdx;
  const uint8_t* image;
  const uint8_t* live;
  const Vec3* shift;
  const Vec3* x;
  const double* radius;
  uint32_t entries;  ///< length of jdx, image and live (the list)
};

/// Two doubles in one vector register (SSE2 on x86-64, NEON on AArch64), for the x and y
/// components of a Vec3 in the screening.
typedef double V2 __attribute__((vector_size(16)));
static_assert(offsetof(Vec3, y) == offsetof(Vec3, x) + sizeof(double), "load_xy reads x and y as one 16-byte block");
COHDEM_INLINE V2 load_xy(const Vec3& v) {
  V2 r;
  std::memcpy(&r, &v.x, sizeof r);
  return r;
}

/// Screens entry k of row i (x_i, r_i given) into slot nh of h; returns 1 when picked.
COHDEM_INLINE uint32_t screen_entry(const ScreenInput& s, const V2 xi_xy, const double xi_z, const double ri,
                                    const uint32_t i, const uint32_t k, const uint32_t nh, ScreenHits& h) {
  const uint32_t j = s.jdx[k];
  // Most entries see j in place (kNoShift, a shift of +0): adding it could change only the
  // sign of a zero coordinate, so skipping it changes no result and saves three loads and
  // three additions per entry.
  const uint8_t im = s.image[k];
  V2 xj_xy = load_xy(s.x[j]);
  double xj_z = s.x[j].z;
  if (im != kNoShift) {
    xj_xy += load_xy(s.shift[im]);
    xj_z += s.shift[im].z;
  }
  // x and y in one register: the same operations, in the same order, as on a Vec3.
  const V2 d_xy = xi_xy - xj_xy;
  const double dz = xi_z - xj_z;
  const V2 sq = d_xy * d_xy;
  const double rsum = ri + s.radius[j];
  const double d2 = (sq[0] + sq[1]) + dz * dz;
  h.k[nh] = k;
  h.row[nh] = i;
  h.dx[nh] = d_xy[0];
  h.dy[nh] = d_xy[1];
  h.dz[nh] = dz;
  h.d2[nh] = d2;
  return uint32_t((d2 < rsum * rsum) | (s.live[k] != 0));
}

/// Screens the entries [kb, ke) of rows i0..i1 (rows below b only) one at a time. Returns
/// the number picked.
COHDEM_INLINE uint32_t screen_scalar(const ScreenInput& s, const long i0, const long i1, const long b, const uint32_t kb,
                                     const uint32_t ke, ScreenHits& h) {
  uint32_t nh = 0;
  for (long i = i0; i <= i1 && i < b; ++i) {
    const uint32_t k0 = std::max(s.start[i], kb), k1 = std::min(s.start[i + 1], ke);
    const V2 xi_xy = load_xy(s.x[i]);
    const double xi_z = s.x[i].z;
    const double ri = s.radius[i];
    for (uint32_t k = k0; k < k1; ++k) nh += screen_entry(s, xi_xy, xi_z, ri, uint32_t(i), k, nh, h);
  }
  return nh;
}

/// The same as screen_scalar, four consecutive entries at a time in AVX2 registers (x86-64
/// only; call it only when screen_avx2_enabled()).
uint32_t screen_avx2(const ScreenInput& s, long i0, long i1, long b, uint32_t kb, uint32_t ke, ScreenHits& h);
/// The same, eight entries at a time in AVX-512 registers (x86-64 only; call it only when
/// screen_avx512_enabled()).
uint32_t screen_avx512(const ScreenInput& s, long i0, long i1, long b, uint32_t kb, uint32_t ke, ScreenHits& h);

/// The largest of p[0..n), at least `floor`, without a branch per element (a running
/// maximum compiled as compare and branch mispredicts on about every other entry of a list
/// row). Four independent maxima, so that the selects do not wait on each other.
COHDEM_INLINE uint32_t max_index_scalar(const uint32_t* p, const uint32_t n, const uint32_t floor) {
  uint32_t m[4] = {floor, floor, floor, floor};
  uint32_t q = 0;
  for (; q + 4 <= n; q += 4)
    for (uint32_t l = 0; l < 4; ++l) m[l] = p[q + l] > m[l] ? p[q + l] : m[l];
  for (; q < n; ++q) m[0] = p[q] > m[0] ? p[q] : m[0];
  return std::max(std::max(m[0], m[1]), std::max(m[2], m[3]));
}
/// The same, eight at a time in AVX2 registers (call it only when screen_avx2_enabled()).
uint32_t max_index_avx2(const uint32_t* p, uint32_t n, uint32_t floor);

/// Whether the force loops take their AVX2 paths (screening, lanes, finish; the list build's
/// search): the CPU has AVX2, the build is for x86-64, and the environment does not say
/// COHDEM_SIMD=0 (for comparisons; read once).
bool screen_avx2_enabled();
/// Whether the screening takes eight entries at a time in AVX-512 registers (screen_avx512)
/// instead of four in AVX2: the AVX2 paths are on, the CPU and the operating system have
/// AVX-512 F, VL, DQ and BW, and the environment does not say COHDEM_SIMD=avx2 (read once).
bool screen_avx512_enabled();
/// The screening's name for logs and summary.json: "avx512", "avx2" or "scalar".
const char* screen_simd_name();

/// The records the force loop's touching entries reach: `entries` list entries' histories of
/// `state_bytes` each and, per particle, its reverse sums (a PairResult), velocity and spin,
/// four Vec3s in all.
inline size_t force_loop_record_bytes(const size_t entries, const size_t particles, const size_t state_bytes) {
  return entries * state_bytes + particles * 4 * sizeof(Vec3);
}
/// Whether the force loop asks for those records a few contacts ahead of their use. That
/// pays where they come from beyond the core's own caches and costs where they do not (the
/// addresses' loads and arithmetic, about 20 instructions a contact): 6-9 % of the force loop
/// on beds of 512-4096 spheres such as the ring shear main job's, and 3-21 % gained on the
/// 32,000-sphere chutes (docs/performance-history.md, fifty-fourth round). So it asks from
/// kPrefetchBytes of them on (force_loop_record_bytes). COHDEM_PREFETCH=0 or 1 in the
/// environment turns it off or on at any size (read once; for comparisons); the results are
/// the same bits.
inline constexpr size_t kPrefetchBytes = size_t(2) << 20;
bool force_loop_prefetches(size_t entries, size_t particles, size_t state_bytes);
/// Tests: -1 the rule above, 0 never, 1 always (overrides the environment).
void set_force_loop_prefetch(int mode);
/// Override the choices (tests: every path on one machine); call them between runs, not
/// during one. Each is refused (left off) where the CPU lacks the instructions.
void set_screen_avx2(bool on);
void set_screen_avx512(bool on);
/// Whether this CPU and build have the AVX2 paths at all, whatever COHDEM_SIMD says.
bool avx2_available();
/// Whether this CPU, operating system and build have the AVX-512 screening.
bool avx512_available();

}  // namespace cohdem
