// The lanes of contacts in AVX2 registers (see lanes.hpp). Written with GCC's vector
// extensions (the operators act lane by lane, as the scalar code's do on one contact) in
// functions compiled for AVX2 alone: no fused multiply-adds, which would round differently
// from the scalar law. Each scalar branch becomes a select between the values both sides
// compute; lanes past the chunk's end repeat its last contact and are not stored.
#include "sim/lanes.hpp"

#include <algorithm>
#include <type_traits>
#include <cstddef>
#include <cstring>
#include <limits>

#include "particles/particle_store.hpp"

#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace cohdem {

namespace {

constexpr uint64_t mask_of(const bool on) { return on ? ~uint64_t(0) : 0; }

/// EPSD's fields of the lane parameters (0 without rolling resistance).
template <class Q, class R>
void rolling_params(Q& q, const R& r) {
  if constexpr (requires { r.mu_r; }) {
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
HertzLaneParams lane_params(const HertzLaw::Params& p) { return hertz_params(p); }
HertzLaneParams lane_params(const HertzEpsdLaw::Params& p) { return hertz_params(p); }
MepaLaneParams lane_params(const MepaLaw::Params& p) { return mepa_params(p); }
MepaLaneParams lane_params(const MepaEpsdLaw::Params& p) { return mepa_params(p); }
bool lane_usable(const MepaLaw::Params& p) { return mepa_usable(p); }
bool lane_usable(const MepaEpsdLaw::Params& p) { return mepa_usable(p); }

#if defined(__x86_64__)

namespace {

typedef double V4 __attribute__((vector_size(32)));
typedef long long M4 __attribute__((vector_size(32)));  // lane masks: all ones or zero

#define LANES_FN __attribute__((target("avx2"), always_inline)) inline

constexpr double kInfinity = std::numeric_limits<double>::infinity();

LANES_FN V4 sqrt4(const V4 a) { return V4(_mm256_sqrt_pd(__m256d(a))); }
/// std::max(a, 0.0) lane by lane: a < 0 ? 0 : a (a -0 or a NaN passes through, as there).
LANES_FN V4 max0(const V4 a) { return V4(_mm256_max_pd(_mm256_setzero_pd(), __m256d(a))); }
/// m ? a : b lane by lane, m a lane mask (all bits set or none): one blend on m's sign bits
/// (`m ? a : b` also compares a mask loaded from the parameters with zero first).
LANES_FN V4 sel(const M4 m, const V4 a, const V4 b) {
  return V4(_mm256_blendv_pd(__m256d(b), __m256d(a), _mm256_castsi256_pd(__m256i(m))));
}
LANES_FN V4 splat(const double s) { return V4{s, s, s, s}; }
LANES_FN void store(double* dst, const V4 a) { _mm256_storeu_pd(dst, __m256d(a)); }

/// Four doubles a[idx[0..3]].
LANES_FN V4 gather(const double* __restrict a, const uint32_t* idx) {
  return V4{a[idx[0]], a[idx[1]], a[idx[2]], a[idx[3]]};
}

/// A group's material pairs' parameters, lane by lane: par(&T::m) is member m in each lane,
/// read from the pair's four copies (LaneParamsOf::wide: one aligned load, often an operand)
/// where all four lanes share the pair (kU; one material, or the chute's flowing spheres
/// among themselves), else gathered. A switch (uint64_t member) gives a lane mask.
template <bool kU, class T>
struct Par {
  const LaneParamsOf<T>* __restrict P;
  const uint32_t* p;
  const LaneParamsOf<T>* __restrict u;  ///< the pair of lane 0 (all lanes' where kU)
  LANES_FN Par(const void* P_, const uint32_t* p_)
      : P(static_cast<const LaneParamsOf<T>*>(P_)), p(p_), u(P + p_[0]) {}
  /// The four copies of member m.
  template <class F>
  LANES_FN const uint64_t* wide(F T::*m) const {
    const size_t f = size_t(reinterpret_cast<const char*>(&(u->p.*m)) - reinterpret_cast<const char*>(&u->p)) / 8;
    return u->wide[f];
  }
  LANES_FN V4 operator()(double T::*m) const {
    if constexpr (kU) return V4(_mm256_load_pd(reinterpret_cast<const double*>(wide(m))));
    else return V4{P[p[0]].p.*m, P[p[1]].p.*m, P[p[2]].p.*m, P[p[3]].p.*m};
  }
  LANES_FN M4 operator()(uint64_t T::*m) const {
    if constexpr (kU) {
      return M4(_mm256_load_si256(reinterpret_cast<const __m256i*>(wide(m))));
    } else {
      return M4{(long long)(P[p[0]].p.*m), (long long)(P[p[1]].p.*m), (long long)(P[p[2]].p.*m),
                (long long)(P[p[3]].p.*m)};
    }
  }
};

struct L3 { V4 x, y, z; };
LANES_FN L3 operator-(const L3& a, const L3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
LANES_FN L3 operator+(const L3& a, const L3& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
LANES_FN L3 operator*(const L3& a, const V4 s) { return {a.x * s, a.y * s, a.z * s}; }
LANES_FN V4 dot3(const L3& a, const L3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
LANES_FN L3 cross3(const L3& a, const L3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
LANES_FN L3 sel3(const M4 m, const L3& a, const L3& b) { return {sel(m, a.x, b.x), sel(m, a.y, b.y), sel(m, a.z, b.z)}; }

/// x, y, z of the Vec3s *a[0..3], one lane each (two 16-byte loads, two inserts and two
/// unpacks for x and y).
LANES_FN L3 load3(const Vec3* const* a) {
  const __m256d t0 = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(&a[0]->x)), _mm_loadu_pd(&a[2]->x), 1);
  const __m256d t1 = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(&a[1]->x)), _mm_loadu_pd(&a[3]->x), 1);
  L3 r;
  r.x = V4(_mm256_unpacklo_pd(t0, t1));
  r.y = V4(_mm256_unpackhi_pd(t0, t1));
  r.z = V4(_mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadh_pd(_mm_load_sd(&a[0]->z), &a[1]->z)),
                                _mm_loadh_pd(_mm_load_sd(&a[2]->z), &a[3]->z), 1));
  return r;
}
/// The Vec3 member m of records p[idx[0..3]].
template <class T>
LANES_FN L3 gather3(const T* __restrict p, const uint32_t* idx, Vec3 T::*m) {
  const Vec3* const a[4] = {&(p[idx[0]].*m), &(p[idx[1]].*m), &(p[idx[2]].*m), &(p[idx[3]].*m)};
  return load3(a);
}
/// p[idx[0..3]].
LANES_FN L3 gather3(const Vec3* __restrict p, const uint32_t* idx) {
  const Vec3* const a[4] = {&p[idx[0]], &p[idx[1]], &p[idx[2]], &p[idx[3]]};
  return load3(a);
}

/// The lanes' contacts: list entries, rows, partners, material pairs, and the kernel's
/// PairGeom in lanes (the same operations as sim/force_kernel.hpp's scalar geometry).
struct Group {
  uint32_t hh[4], k[4], i[4], j[4], p[4];
  uint32_t valid;  ///< lanes that hold a contact of the chunk
  bool uniform;    ///< all four lanes of one material pair (its parameters broadcast)
  M4 fi, fj;       ///< i, j free (not frozen)
  L3 n, vt, wi, wj;  ///< wi, wj: the spins
  V4 ri, rj, delta, rstar, mi, mj, mstar, vn, li, lj;
};

LANES_FN void geometry(const LaneInput& in, const ScreenHits& hits, const uint32_t h0, const uint32_t cnt,
                       const uint32_t g, Group& G) {
  for (uint32_t l = 0; l < 4; ++l) {
    G.hh[l] = h0 + std::min(g + l, cnt - 1);
    G.k[l] = hits.k[G.hh[l]];
    G.i[l] = hits.row[G.hh[l]];
    G.j[l] = in.jdx[G.k[l]];
  }
  G.valid = std::min(4u, cnt - g);
  // One material: one pair, no species read.
  if (in.nmat == 1) {
    G.p[0] = G.p[1] = G.p[2] = G.p[3] = 0;
    G.uniform = true;
  } else {
    for (uint32_t l = 0; l < 4; ++l)
      G.p[l] = uint32_t(size_t(in.species[G.i[l]]) * in.nmat + size_t(in.species[G.j[l]]));
    G.uniform = G.p[0] == G.p[1] && G.p[0] == G.p[2] && G.p[0] == G.p[3];
  }
  const uint8_t* const flag = in.flag;
  G.fi = M4{-(flag[G.i[0]] == kFree), -(flag[G.i[1]] == kFree), -(flag[G.i[2]] == kFree), -(flag[G.i[3]] == kFree)};
  G.fj = M4{-(flag[G.j[0]] == kFree), -(flag[G.j[1]] == kFree), -(flag[G.j[2]] == kFree), -(flag[G.j[3]] == kFree)};
  G.ri = gather(in.radius, G.i);
  G.rj = gather(in.radius, G.j);
  const V4 rsum = G.ri + G.rj;
  const V4 dist = sqrt4(gather(hits.d2, G.hh));
  const V4 inv = splat(1.0) / dist;
  G.n = L3{gather(hits.dx, G.hh), gather(hits.dy, G.hh), gather(hits.dz, G.hh)} * inv;
  G.delta = rsum - dist;
  G.rstar = G.ri * G.rj / rsum;
  G.mi = sel(G.fi, gather(in.mass, G.i), splat(kInfinity));
  G.mj = sel(G.fj, gather(in.mass, G.j), splat(kInfinity));
  G.mstar = sel(G.fi & G.fj, G.mi * G.mj / (G.mi + G.mj), sel(G.fi, G.mi, G.mj));
  const L3 vij = gather3(in.v, G.i) - gather3(in.v, G.j);
  G.vn = dot3(vij, G.n);
  G.li = G.ri - 0.5 * G.delta;
  G.lj = G.rj - 0.5 * G.delta;
  G.wi = gather3(in.omega, G.i);
  G.wj = gather3(in.omega, G.j);
  const L3 w = G.wi * G.li + G.wj * G.lj;
  const L3 vrel = vij - cross3(w, G.n);
  G.vt = vrel - G.n * dot3(vrel, G.n);
}

/// rotate_into_plane (core/vec3.hpp) in lanes: the series factor for small turns, else the
/// exact one; a zero history stays as it is.
LANES_FN void rotate_into_plane4(L3& h, const L3& n) {
  const V4 m0 = dot3(h, h);
  const V4 hn = dot3(n, h);
  L3 r = h - n * hn;
  const V4 hn2 = hn * hn;
  const V4 x = hn2 / m0;
  V4 f = 1.0 + x * (0.5 + x * (0.375 + x * 0.3125));
  // The exact factor (a division and a square root) only where a lane whose history is kept
  // turned by more than the series covers: almost never (a branch that predicts well); the
  // lanes take the same values as with both computed and selected.
  const M4 series = hn2 < 1e-4 * m0, used = m0 > 0.0;
  if (__builtin_expect(_mm256_movemask_pd(__m256d(used & ~series)) != 0, 0)) {
    const V4 m1 = dot3(r, r);
    f = sel(series, f, sel(m1 > 0.0, sqrt4(m0 / m1), splat(1.0)));
  }
  r = r * f;
  h = sel3(used, r, h);
}

/// h *= limit_scale(|h|^2, lim) (core/vec3.hpp) in lanes: the lanes over the limit scaled
/// to it, the others left as they are (the scalar code multiplies them by exactly 1, which
/// changes no bit). Returns the lanes over. The division, the square root and the products
/// only where a lane is over: sticking contacts, most of a packing's, skip them.
LANES_FN M4 limit4(L3& h, const V4 lim) {
  const V4 m2 = dot3(h, h);
  const M4 over = m2 > lim * lim;
  if (_mm256_movemask_pd(__m256d(over)) != 0) h = h * sel(over, lim / sqrt4(m2), splat(1.0));
  return over;
}

/// LinearRestitutionDamping / TsujiDamping::apply with apply_limit: the damping force, and
/// gamma_n in gamma.
/// apply_limit (models/damping/restitution.hpp) in lanes: the damping force of gamma_n.
LANES_FN V4 apply_limit4(const M4 limit, const V4 gamma, const V4 vn, const V4 f_el) {
  const V4 fd0 = -gamma * vn;
  const M4 lim_on = limit & (f_el + fd0 < 0.0) & (fd0 < 0.0);
  return sel(lim_on, -max0(f_el), fd0);
}
LANES_FN V4 damping4(const V4 two_beta, const M4 limit, const V4 mstar, const V4 kn, const V4 vn, const V4 f_el,
                     V4& gamma) {
  gamma = two_beta * sqrt4(mstar * kn);
  return apply_limit4(limit, gamma, vn, f_el);
}


/// TangentialCommon::update after its stiffness step: increment, trial force, Coulomb limit.
/// Returns the tangential force; fs becomes the new spring force.
LANES_FN L3 spring4(L3& fs, const L3& vt, const V4 kt, const V4 dt, const V4 gamma_t, const V4 mu, const V4 fc) {
  fs = fs - vt * (kt * dt);
  L3 ft = fs - vt * gamma_t;
  const M4 slide = limit4(ft, mu * fc);
  fs = sel3(slide, ft, fs);
  return ft;
}

/// TangentialCommon::update with a stiffness record (State::kt_prev), after its rotation
/// (the caller's rotate_into_plane4): the spring scaled by kt/kt_prev where the stiffness
/// fell, then spring4; kt_prev becomes kt.
LANES_FN L3 spring_prev4(L3& fs, V4& kt_prev, const L3& vt, const V4 kt, const V4 dt, const V4 gamma_t,
                         const V4 mu, const V4 fc) {
  fs = sel3((kt_prev > 0.0) & (kt < kt_prev), fs * (kt / kt_prev), fs);
  kt_prev = kt;
  return spring4(fs, vt, kt, dt, gamma_t, mu, fc);
}

/// Evaluates the chunk's groups with Group's kU: the uniform variant where one material pair
/// fills the group, else the mixed one.
using GroupFn = void (*)(const LaneInput&, const Group&, uint32_t, LaneOut&);
template <GroupFn kUniform, GroupFn kMixed>
LANES_FN void drive(const LaneInput& in, const ScreenHits& hits, const uint32_t h0, const uint32_t cnt, LaneOut& out) {
  for (uint32_t g = 0; g < cnt; g += 4) {
    Group G;
    geometry(in, hits, h0, cnt, g, G);
    if (G.uniform)
      kUniform(in, G, g, out);
    else
      kMixed(in, G, g, out);
  }
}

/// EPSD's I_r = Ji Jj / (Ji + Jj), J = I + m r^2; a frozen body adds nothing. The scalar law
/// tests I = inf, which is the frozen bodies' (a free particle's inertia, 0.4 m r^2, is
/// finite): J = I + m r^2 of a free body, 0 (not read) of a frozen one.
LANES_FN V4 rolling_inertia4(const LaneInput& in, const Group& G) {
  const V4 Ji = sel(G.fi, gather(in.inertia, G.i) + G.mi * G.ri * G.ri, splat(0.0));
  const V4 Jj = sel(G.fj, gather(in.inertia, G.j) + G.mj * G.rj * G.rj, splat(0.0));
  return sel(G.fj, sel(G.fi, Ji * Jj / (Ji + Jj), Jj), Ji);
}
/// EPSD's stiffness k_r and viscous coefficient eta_r 2 sqrt(I_r k_r): they need only the
/// geometry and the normal law's kn. The Hertz-Mindlin and MEPA groups compute them as soon
/// as kn is known, so that the division and square root overlap the rest of the law (3-4 %
/// faster for Hertz-Mindlin + EPSD); the linear group at the end, which measured 3-4 %
/// faster there (BM_ForceAlternate, the variants built side by side).
struct EpsdCoef { V4 kr, visc; };
LANES_FN EpsdCoef epsd_coef4(const LaneInput& in, const Group& G, const V4 kn, const V4 mu_r, const V4 two_eta_r,
                             const M4 damped) {
  const V4 kr = 2.25 * kn * mu_r * mu_r * G.rstar * G.rstar;
  // eta_r = 0 (the default, and the ring shear cases'): no viscous part (epsd4 selects the
  // spring alone), so no I_r and no square root. A branch on the material pairs' switch, the
  // same from group to group.
  if (_mm256_movemask_pd(__m256d(damped)) == 0) return {kr, splat(0.0)};
  return {kr, two_eta_r * sqrt4(rolling_inertia4(in, G) * kr)};
}
/// EpsdRolling::apply in lanes: mk is the spring's history, already turned into the new
/// tangent plane (the caller's rotate_into_plane4); returns the moment on i. c: epsd_coef4;
/// damped: eta_r > 0.
LANES_FN L3 epsd4(const Group& G, L3& mk, const EpsdCoef& c, const V4 fc, const V4 mu_r, const M4 damped,
                  const V4 dt) {
  const L3 wrel = G.wi - G.wj;
  const L3 wr = wrel - G.n * dot3(G.n, wrel);
  mk = mk - wr * (c.kr * dt);
  const M4 slide = limit4(mk, mu_r * G.rstar * fc);
  const L3 damped_m = mk - wr * c.visc;
  // eta_r = 0 leaves the spring alone (the scalar law's branch; damped_m would differ from it
  // only in the sign of a zero, or where I_r k_r is not finite).
  return sel3(damped & ~slide, damped_m, mk);
}

/// out.alive[g .. g + 4) from the alive lanes' sign bits in one 4-byte store (lanes past the
/// chunk's end write bytes that no one reads: g + 4 <= kLaneChunk).
constexpr uint32_t alive_bytes(const int m) {
  return uint32_t(m & 1) | uint32_t((m >> 1) & 1) << 8 | uint32_t((m >> 2) & 1) << 16 | uint32_t((m >> 3) & 1) << 24;
}
constexpr uint32_t kAliveBytes[16] = {alive_bytes(0),  alive_bytes(1),  alive_bytes(2),  alive_bytes(3),
                                      alive_bytes(4),  alive_bytes(5),  alive_bytes(6),  alive_bytes(7),
                                      alive_bytes(8),  alive_bytes(9),  alive_bytes(10), alive_bytes(11),
                                      alive_bytes(12), alive_bytes(13), alive_bytes(14), alive_bytes(15)};
LANES_FN void put_alive(const M4 alive, const uint32_t g, LaneOut& out) {
  const uint32_t b = kAliveBytes[_mm256_movemask_pd(__m256d(alive))];
  std::memcpy(out.alive + g, &b, sizeof b);
}

/// ContactLaw::evaluate's assembly for two spheres (lever arms r - delta/2) and the stores.
LANES_FN void put(const Group& G, const uint32_t g, const M4 alive, const V4 fn, const L3& ft, const L3* mr, const V4 a,
                  LaneOut& out) {
  put_alive(alive, g, out);
  const L3 nxft = cross3(G.n, ft);
  const L3 f = G.n * fn + ft;
  L3 ti = nxft * -G.li, tj = nxft * -G.lj;
  if (mr != nullptr) {
    ti = ti + *mr;
    tj = tj - *mr;
  }
  // The ten stores at fixed offsets from one address (hidden from the optimizer, which
  // otherwise keeps an address per array across the groups, spilled to the stack).
  char* o = reinterpret_cast<char*>(&out) + size_t(g) * sizeof(double);
  asm("" : "+r"(o));
  auto st = [o](const size_t off, const V4 v) __attribute__((target("avx2"), always_inline)) {
    store(reinterpret_cast<double*>(o + off), v);
  };
  st(offsetof(LaneOut, fx), f.x);
  st(offsetof(LaneOut, fy), f.y);
  st(offsetof(LaneOut, fz), f.z);
  st(offsetof(LaneOut, tix), ti.x);
  st(offsetof(LaneOut, tiy), ti.y);
  st(offsetof(LaneOut, tiz), ti.z);
  st(offsetof(LaneOut, tjx), tj.x);
  st(offsetof(LaneOut, tjy), tj.y);
  st(offsetof(LaneOut, tjz), tj.z);
  st(offsetof(LaneOut, a), a);
}

/// The histories are written back one whole record per lane, from the lanes transposed
/// (unpacks and 128-bit permutes), instead of one double at a time: quads(a, b, c, d)[l] =
/// {a[l], b[l], c[l], d[l]}, a 32-byte store; pairs(a, b)[l] = {a[l], b[l]}, a 16-byte store.
struct Quads { __m256d q[4]; };
struct Pairs { __m128d p[4]; };
LANES_FN Quads quads(const V4 a, const V4 b, const V4 c, const V4 d) {
  const __m256d t0 = _mm256_unpacklo_pd(__m256d(a), __m256d(b));  // a0 b0 a2 b2
  const __m256d t1 = _mm256_unpackhi_pd(__m256d(a), __m256d(b));  // a1 b1 a3 b3
  const __m256d t2 = _mm256_unpacklo_pd(__m256d(c), __m256d(d));  // c0 d0 c2 d2
  const __m256d t3 = _mm256_unpackhi_pd(__m256d(c), __m256d(d));  // c1 d1 c3 d3
  return {{_mm256_permute2f128_pd(t0, t2, 0x20), _mm256_permute2f128_pd(t1, t3, 0x20),
           _mm256_permute2f128_pd(t0, t2, 0x31), _mm256_permute2f128_pd(t1, t3, 0x31)}};
}
LANES_FN Pairs pairs(const V4 a, const V4 b) {
  const __m256d t0 = _mm256_unpacklo_pd(__m256d(a), __m256d(b));  // a0 b0 a2 b2
  const __m256d t1 = _mm256_unpackhi_pd(__m256d(a), __m256d(b));  // a1 b1 a3 b3
  return {{_mm256_castpd256_pd128(t0), _mm256_castpd256_pd128(t1), _mm256_extractf128_pd(t0, 1),
           _mm256_extractf128_pd(t1, 1)}};
}
/// The record of list entry k as doubles (the loads and stores go to fixed offsets in it).
template <class H>
LANES_FN double* rec(H* h, const uint32_t k) { return reinterpret_cast<double*>(h + k); }
/// The lanes of the four doubles at offset o of each lane's record (entries k[0..3]), read as
/// the stores write them: a 4x4 transpose is its own inverse.
template <class H>
LANES_FN Quads load_quads(H* h, const uint32_t* k, const uint32_t o) {
  return quads(V4(_mm256_loadu_pd(rec(h, k[0]) + o)), V4(_mm256_loadu_pd(rec(h, k[1]) + o)),
               V4(_mm256_loadu_pd(rec(h, k[2]) + o)), V4(_mm256_loadu_pd(rec(h, k[3]) + o)));
}
/// The same for two doubles at offset o: their lanes in a, b.
template <class H>
LANES_FN void load_pairs(H* h, const uint32_t* k, const uint32_t o, V4& a, V4& b) {
  const __m256d t02 =
      _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(rec(h, k[0]) + o)), _mm_loadu_pd(rec(h, k[2]) + o), 1);
  const __m256d t13 =
      _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(rec(h, k[1]) + o)), _mm_loadu_pd(rec(h, k[3]) + o), 1);
  a = V4(_mm256_unpacklo_pd(t02, t13));
  b = V4(_mm256_unpackhi_pd(t02, t13));
}

/// f(l) for each lane l that holds a contact of the chunk: all four written out where the
/// group is full (most groups), so the stores need no loop.
template <class F>
LANES_FN void each_lane(const Group& G, F&& f) {
  if (G.valid == 4) {
    f(0), f(1), f(2), f(3);
  } else {
    for (uint32_t l = 0; l < G.valid; ++l) f(l);
  }
}

/// Each lane's record (entry G.k[l]) written from the transposed lanes: parts At{o, v} of
/// quads (32 bytes) or pairs (16 bytes) at offset o, in doubles, in the order given.
template <class T>
struct At {
  uint32_t o;
  const T& v;
};
LANES_FN void store_part(double* r, const uint32_t l, const At<Quads>& a) { _mm256_storeu_pd(r + a.o, a.v.q[l]); }
LANES_FN void store_part(double* r, const uint32_t l, const At<Pairs>& a) { _mm_storeu_pd(r + a.o, a.v.p[l]); }
template <class H, class... T>
LANES_FN void store_records(const Group& G, H* h, const At<T>&... parts) {
  each_lane(G, [&](const uint32_t l) __attribute__((target("avx2"), always_inline)) {
    double* const r = rec(h, G.k[l]);
    (store_part(r, l, parts), ...);
  });
}

// The records' layouts that the loads and stores below assume by their offsets (lanes.hpp's
// same_layout checks the records against the laws' State).
static_assert(sizeof(LinearLaneHistory) == 24 && offsetof(LinearLaneHistory, fs) == 0);
static_assert(sizeof(LinearEpsdLaneHistory) == 48 && offsetof(LinearEpsdLaneHistory, fs) == 0 &&
              offsetof(LinearEpsdLaneHistory, mk) == 24);
static_assert(sizeof(HertzLaneHistory) == 32 && offsetof(HertzLaneHistory, fs) == 0 &&
              offsetof(HertzLaneHistory, kt_prev) == 24);
static_assert(sizeof(HertzEpsdLaneHistory) == 56 && offsetof(HertzEpsdLaneHistory, fs) == 0 &&
              offsetof(HertzEpsdLaneHistory, kt_prev) == 24 && offsetof(HertzEpsdLaneHistory, mk) == 32);
static_assert(sizeof(MepaLaneHistory) == 56 && offsetof(MepaLaneHistory, Dp) == 8 &&
              offsetof(MepaLaneHistory, branch) == 16 && offsetof(MepaLaneHistory, fs) == 24 &&
              offsetof(MepaLaneHistory, kt_prev) == 48);
static_assert(sizeof(MepaEpsdLaneHistory) == 80 && offsetof(MepaEpsdLaneHistory, Dp) == 8 &&
              offsetof(MepaEpsdLaneHistory, branch) == 16 && offsetof(MepaEpsdLaneHistory, fs) == 24 &&
              offsetof(MepaEpsdLaneHistory, kt_prev) == 48 && offsetof(MepaEpsdLaneHistory, mk) == 56);

/// One group of four contacts of the linear law (after their geometry); kU: one material
/// pair; kRoll: with EPSD rolling resistance.
template <bool kU, bool kRoll>
__attribute__((target("avx2"), always_inline)) inline void linear_group(
    const LaneInput& in, const Group& G, const uint32_t g, LaneOut& out) {
  const void* const P = in.params;
  using LH = std::conditional_t<kRoll, LinearEpsdLaneHistory, LinearLaneHistory>;
  auto* const H = static_cast<LH*>(in.hist);
  using LP = LinearLaneParams;
  const Par<kU, LP> par(P, G.p);
  // The records first, and their turns into the new tangent plane: they depend only on the
  // history and the normal, so the out-of-order window overlaps their divisions with the
  // laws' chains below. {fs}, or {fs, mk} read as {fs, mk.x} and {mk.y, mk.z}.
  L3 fs, mk;
  if constexpr (kRoll) {
    const Quads h0 = load_quads(H, G.k, 0);
    V4 mk_y, mk_z;
    load_pairs(H, G.k, 4, mk_y, mk_z);
    fs = L3{V4(h0.q[0]), V4(h0.q[1]), V4(h0.q[2])};
    mk = L3{V4(h0.q[3]), mk_y, mk_z};
    rotate_into_plane4(mk, G.n);
  } else {
    fs = gather3(H, G.k, &LH::fs);
  }
  rotate_into_plane4(fs, G.n);
  // LinearNormal.
  const V4 kn = par(&LP::kn);
  const M4 alive = G.delta > 0.0;
  const V4 f_el = kn * G.delta;
  V4 gamma;
  const V4 fn = f_el + damping4(par(&LP::two_beta), par(&LP::limit), G.mstar, kn, G.vn, f_el, gamma);
  const V4 fc = max0(fn);  // NormalBase::coulomb_base
  const L3 ft = spring4(fs, G.vt, par(&LP::kt), splat(in.dt), par(&LP::damp_t) * gamma,
                        par(&LP::mu), fc);
  // LinearNormal's contact radius, read only when asked for.
  const V4 a = in.want_a ? sqrt4(G.rstar * G.delta) : splat(0.0);
  // The records back (the force loop resets those of contacts that ended: LaneOut::alive).
  if constexpr (kRoll) {
    // (kn is a parameter here: the coefficient computed at the start measured 3-4 % slower)
    const EpsdCoef ec = epsd_coef4(in, G, kn, par(&LP::mu_r), par(&LP::two_eta_r), par(&LP::damped));
    const L3 mr = epsd4(G, mk, ec, fc, par(&LP::mu_r), par(&LP::damped), splat(in.dt));
    put(G, g, alive, fn, ft, &mr, a, out);
    store_records(G, H, At<Quads>{0, quads(fs.x, fs.y, fs.z, mk.x)}, At<Pairs>{4, pairs(mk.y, mk.z)});
  } else {
    put(G, g, alive, fn, ft, nullptr, a, out);
    // 24 bytes: {x, y} then z of each lane.
    const Pairs xy = pairs(fs.x, fs.y);
    alignas(32) double z[4];
    _mm256_store_pd(z, __m256d(fs.z));
    each_lane(G, [&](const uint32_t l) __attribute__((target("avx2"), always_inline)) {
      double* const r = rec(H, G.k[l]);
      _mm_storeu_pd(r, xy.p[l]);
      r[2] = z[l];
    });
  }
}

/// One group of four contacts of Hertz-Mindlin (after their geometry); kU: one material pair;
/// kRoll: with EPSD rolling resistance.
template <bool kU, bool kRoll>
__attribute__((target("avx2"), always_inline)) inline void hertz_group(
    const LaneInput& in, const Group& G, const uint32_t g, LaneOut& out) {
  const void* const P = in.params;
  using LH = std::conditional_t<kRoll, HertzEpsdLaneHistory, HertzLaneHistory>;
  auto* const H = static_cast<LH*>(in.hist);
  using LP = HertzLaneParams;
  const Par<kU, LP> par(P, G.p);
  const V4 dt = splat(in.dt);
  // The records first, read whole as they are written below ({fs, kt_prev} at 0 and, with
  // rolling, {kt_prev, mk} at 24), and turned into the new tangent plane (see linear_group).
  const Quads h0 = load_quads(H, G.k, 0);
  L3 fs{V4(h0.q[0]), V4(h0.q[1]), V4(h0.q[2])};
  V4 kt_prev = V4(h0.q[3]);
  rotate_into_plane4(fs, G.n);
  L3 mk{};
  if constexpr (kRoll) {
    const Quads h1 = load_quads(H, G.k, 3);
    mk = L3{V4(h1.q[1]), V4(h1.q[2]), V4(h1.q[3])};
    rotate_into_plane4(mk, G.n);
  }
  // HertzNormal (the lanes of ended contacts compute what no one reads).
  const M4 alive = G.delta > 0.0;
  const V4 a = sqrt4(G.rstar * G.delta);
  const V4 kn = par(&LP::two_Estar) * a;
  EpsdCoef ec{};
  if constexpr (kRoll) ec = epsd_coef4(in, G, kn, par(&LP::mu_r), par(&LP::two_eta_r), par(&LP::damped));
  const V4 f_el = (2.0 / 3.0) * kn * G.delta;
  V4 gamma;
  const V4 fn = f_el + damping4(par(&LP::two_beta), par(&LP::limit), G.mstar, kn, G.vn, f_el, gamma);
  const V4 fc = max0(fn);
  // MindlinTangential: kt = 8 G* a; a spring whose stiffness fell is scaled by kt/kt_prev.
  const V4 kt = par(&LP::eight_Gstar) * a;
  const L3 ft = spring_prev4(fs, kt_prev, G.vt, kt, dt, par(&LP::damp_kt) * gamma,
                             par(&LP::mu), fc);
  // The records back (the force loop resets those of contacts that ended).
  const Quads a0 = quads(fs.x, fs.y, fs.z, kt_prev);
  if constexpr (kRoll) {
    const L3 mr = epsd4(G, mk, ec, fc, par(&LP::mu_r), par(&LP::damped), dt);
    put(G, g, alive, fn, ft, &mr, a, out);
    // {kt_prev, mk} at 24 (kt_prev written twice, the same value).
    store_records(G, H, At<Quads>{0, a0}, At<Quads>{3, quads(kt_prev, mk.x, mk.y, mk.z)});
  } else {
    put(G, g, alive, fn, ft, nullptr, a, out);
    store_records(G, H, At<Quads>{0, a0});
  }
}

/// One group of four contacts of MEPA (after their geometry); kU: one material pair; kRoll:
/// with EPSD rolling resistance.
template <bool kU, bool kRoll>
__attribute__((target("avx2"), always_inline)) inline void mepa_group(
    const LaneInput& in, const Group& G, const uint32_t g, LaneOut& out) {
  const void* const P = in.params;
  using LH = std::conditional_t<kRoll, MepaEpsdLaneHistory, MepaLaneHistory>;
  auto* const H = static_cast<LH*>(in.hist);
  using LP = MepaLaneParams;
  const Par<kU, LP> par(P, G.p);
  const V4 dt = splat(in.dt);
  // The springs' records first, {fs, kt_prev} at 24 and, with rolling, mk at 56, turned into
  // the new tangent plane (see linear_group): their divisions overlap the normal law's
  // square root. {Dmax, Dp} at 0 where the normal law reads it.
  L3 mk{};
  const Quads h1 = load_quads(H, G.k, 3);
  L3 fs{V4(h1.q[0]), V4(h1.q[1]), V4(h1.q[2])};
  V4 kt_prev = V4(h1.q[3]);
  rotate_into_plane4(fs, G.n);
  if constexpr (kRoll) {
    mk = gather3(H, G.k, &LH::mk);
    rotate_into_plane4(mk, G.n);
  }
  V4 Dmax, Dp;
  load_pairs(H, G.k, 0, Dmax, Dp);
  // HystereticNormal::apply with fixed stiffnesses (lane_usable): D = delta^n with
  // delta^(n-1) = 1 (n = 1) or sqrt(delta) (n = 3/2); the branch of the larger of f1, f2,
  // bounded below by the adhesive -A.
  const M4 alive = G.delta > 0.0;
  const V4 d = G.delta;
  const V4 dn1 = sel(par(&LP::n_is_1), splat(1.0), sqrt4(d));
  const V4 D = d * dn1;
  const V4 A = par(&LP::kadh) * D;
  const V4 k1 = par(&LP::k1), k2 = par(&LP::k2);
  const V4 f1 = k1 * D, f2 = k2 * (D - Dp);
  const M4 load = f2 >= f1;
  const M4 adh = ~load & ~(f2 > -A);
  const V4 f = sel(load, f1, sel(adh, -A, f2));
  const V4 Dp_new = D * par(&LP::plastic);
  const V4 Dmax1 = sel(load, D, Dmax), Dp1 = sel(load, Dp_new, Dp);
  const V4 f0 = par(&LP::f0);
  const V4 f_el = f0 + f;
  const V4 f_adh = A - f0;
  const V4 kn = par(&LP::n_k2) * dn1;
  EpsdCoef ec{};
  if constexpr (kRoll) ec = epsd_coef4(in, G, kn, par(&LP::mu_r), par(&LP::two_eta_r), par(&LP::damped));
  const V4 k_load = k1 * dn1;
  // ViscousDamping.
  const V4 gamma = par(&LP::gamma_n);
  const V4 fn = f_el + apply_limit4(par(&LP::limit), gamma, G.vn, f_el);
  const V4 fc = max0(sel(par(&LP::offset), f_el + f_adh, f_el));  // coulomb_base
  // HystTangential: a fixed kt, or kt_ratio k1 delta^(n-1) kt_mult.
  const V4 kt = sel(par(&LP::kt_const), par(&LP::kt_c), par(&LP::kt_ratio) * k_load * par(&LP::kt_mult));
  // EPSD before the tangential spring: the two chains are independent, and the rolling one
  // then overlaps the spring's instead of ending the group (1-2 % faster, BM_ForceAlternate).
  L3 mr{};
  if constexpr (kRoll) mr = epsd4(G, mk, ec, fc, par(&LP::mu_r), par(&LP::damped), dt);
  const L3 ft = spring_prev4(fs, kt_prev, G.vt, kt, dt, par(&LP::gamma_t), par(&LP::mu), fc);
  const V4 a = in.want_a ? sqrt4(G.rstar * d) : splat(0.0);
  // The records back (the force loop resets those of contacts that ended). The branch is an
  // int32 followed by 4 bytes of padding: its lane holds it zero-extended, so the padding
  // stays zero as the scalar law leaves it. Without rolling: {Dmax, Dp, branch, fs.x} at 0
  // and {fs, kt_prev} at 24 (fs.x written twice).
  const M4 br = load ? M4{1, 1, 1, 1} : (adh ? M4{3, 3, 3, 3} : M4{2, 2, 2, 2});
  if constexpr (kRoll) {
    // {Dmax, Dp, branch, fs.x} at 0 and {fs.y, fs.z} at 32 before the forces' stores,
    // {kt_prev, mk} at 48 after them.
    store_records(G, H, At<Quads>{0, quads(Dmax1, Dp1, V4(br), fs.x)}, At<Pairs>{4, pairs(fs.y, fs.z)});
    put(G, g, alive, fn, ft, &mr, a, out);
    store_records(G, H, At<Quads>{6, quads(kt_prev, mk.x, mk.y, mk.z)});
  } else {
    store_records(G, H, At<Quads>{0, quads(Dmax1, Dp1, V4(br), fs.x)}, At<Quads>{3, quads(fs.x, fs.y, fs.z, kt_prev)});
    put(G, g, alive, fn, ft, nullptr, a, out);
  }
}

}  // namespace

#define COHDEM_LANES_ENTRY(name, group, roll)                                                                         \
  __attribute__((target("avx2"))) void name(const LaneInput& in, const ScreenHits& hits, const uint32_t h0,            \
                                            const uint32_t cnt, LaneOut& out) {                                         \
    drive<group<true, roll>, group<false, roll>>(in, hits, h0, cnt, out);                                               \
  }
COHDEM_LANES_ENTRY(linear_lanes_avx2, linear_group, false)
COHDEM_LANES_ENTRY(linear_epsd_lanes_avx2, linear_group, true)
COHDEM_LANES_ENTRY(hertz_lanes_avx2, hertz_group, false)
COHDEM_LANES_ENTRY(hertz_epsd_lanes_avx2, hertz_group, true)
COHDEM_LANES_ENTRY(mepa_lanes_avx2, mepa_group, false)
COHDEM_LANES_ENTRY(mepa_epsd_lanes_avx2, mepa_group, true)
#undef COHDEM_LANES_ENTRY

#else

void linear_lanes_avx2(const LaneInput&, const ScreenHits&, uint32_t, uint32_t, LaneOut&) {}
void linear_epsd_lanes_avx2(const LaneInput&, const ScreenHits&, uint32_t, uint32_t, LaneOut&) {}
void hertz_lanes_avx2(const LaneInput&, const ScreenHits&, uint32_t, uint32_t, LaneOut&) {}
void hertz_epsd_lanes_avx2(const LaneInput&, const ScreenHits&, uint32_t, uint32_t, LaneOut&) {}
void mepa_lanes_avx2(const LaneInput&, const ScreenHits&, uint32_t, uint32_t, LaneOut&) {}
void mepa_epsd_lanes_avx2(const LaneInput&, const ScreenHits&, uint32_t, uint32_t, LaneOut&) {}

#endif

}  // namespace cohdem
