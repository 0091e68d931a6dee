// The lanes of contacts in AVX2 registers (see lanes.hpp). Written with GCC's vector
// extensions (the operators act lane by lane, as the scalar code's do on one contact) in
// functions compiled for AVX2 alone: no fused multiply-adds, which would round differently
// from the scalar law. Each scalar branch becomes a select between the values both sides
// compute; lanes past the chunk's end repeat its last contact and are not stored.
#include "sim/lanes.hpp"

#include <algorithm>
#include <limits>

#include "particles/particle_store.hpp"

#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace cohdem {

LinearLaneParams lane_params(const LinearLaw::Params& p) {
  LinearLaneParams q;
  q.kn = p.normal.kn;
  q.two_beta = 2.0 * p.damping.beta;
  q.limit = p.damping.limit ? 1.0 : 0.0;
  q.mu = p.tangential.mu;
  // LinearTangential::apply: kt > 0 ? kt : kt_ratio * kn, with kn = LinearNormal's kn.
  q.kt = p.tangential.kt > 0 ? p.tangential.kt : p.tangential.kt_ratio * p.normal.kn;
  q.damp_t = p.tangential.damp_t;
  return q;
}

HertzEpsdLaneParams lane_params(const HertzEpsdLaw::Params& p) {
  HertzEpsdLaneParams q;
  q.two_Estar = 2.0 * p.normal.Estar;
  q.two_beta = 2.0 * p.damping.beta;
  q.limit = p.damping.limit ? 1.0 : 0.0;
  q.mu = p.tangential.mu;
  q.eight_Gstar = 8.0 * p.tangential.Gstar;
  q.damp_kt = p.tangential.damp_kt;
  q.mu_r = p.rolling.mu_r;
  q.eta_r = p.rolling.eta_r;
  return q;
}

MepaEpsdLaneParams lane_params(const MepaEpsdLaw::Params& p) {
  const auto& np = p.normal;
  const auto& tp = p.tangential;
  MepaEpsdLaneParams q;
  q.k1 = np.k1;
  q.k2 = np.k2;
  q.plastic = np.plastic;
  q.kadh = np.kadh;
  q.f0 = np.f0;
  q.n = np.n;
  q.n_is_1 = np.n == 1.0 ? 1.0 : 0.0;
  q.offset = np.offset ? 1.0 : 0.0;
  q.gamma_n = p.damping.gamma_n;
  q.limit = p.damping.limit ? 1.0 : 0.0;
  q.mu = tp.mu;
  q.kt_const = tp.kt_const ? 1.0 : 0.0;
  q.kt_c = tp.kt_c;
  q.kt_ratio = tp.kt_ratio;
  q.kt_mult = tp.kt_mult;
  q.damp_t = tp.damp_t;
  q.mu_r = p.rolling.mu_r;
  q.eta_r = p.rolling.eta_r;
  return q;
}

bool lane_usable(const MepaEpsdLaw::Params& p) {
  const auto& np = p.normal;
  // HystereticNormal::apply with p.fixed, x_is_n and no shift; pow_nm1 as 1 or a square root;
  // HystTangential without kt_hertz (never with fixed stiffnesses; checked all the same).
  return np.fixed && np.x_is_n && !np.shift && (np.n == 1.0 || np.n == 1.5) && !p.tangential.kt_hertz;
}

#if defined(__x86_64__)

namespace {

typedef double V4 __attribute__((vector_size(32)));
typedef long long M4 __attribute__((vector_size(32)));  // lane masks: all ones or zero

#define LANES_FN __attribute__((target("avx2"), always_inline)) inline

constexpr double kInfinity = std::numeric_limits<double>::infinity();

LANES_FN V4 sqrt4(const V4 a) { return V4(_mm256_sqrt_pd(__m256d(a))); }
/// std::max(a, 0.0) lane by lane: a < 0 ? 0 : a (a -0 or a NaN passes through, as there).
LANES_FN V4 max0(const V4 a) { return V4(_mm256_max_pd(_mm256_setzero_pd(), __m256d(a))); }
LANES_FN V4 sel(const M4 m, const V4 a, const V4 b) { return m ? a : b; }
LANES_FN V4 splat(const double s) { return V4{s, s, s, s}; }
LANES_FN void store(double* dst, const V4 a) { _mm256_storeu_pd(dst, __m256d(a)); }

/// Four doubles a[idx[0..3]].
LANES_FN V4 gather(const double* __restrict a, const uint32_t* idx) {
  return V4{a[idx[0]], a[idx[1]], a[idx[2]], a[idx[3]]};
}
/// Member m of four records p[idx[0..3]].
template <class T>
LANES_FN V4 gather(const T* __restrict p, const uint32_t* idx, double T::*m) {
  return V4{p[idx[0]].*m, p[idx[1]].*m, p[idx[2]].*m, p[idx[3]].*m};
}

/// A material pair's parameter m in each lane: one broadcast where all four lanes share the
/// pair (kU; one material, or the chute's flowing spheres among themselves), else gathered.
template <bool kU, class T>
LANES_FN V4 par(const T* __restrict P, const uint32_t* p, double T::*m) {
  if constexpr (kU) return splat(P[p[0]].*m);
  else return gather(P, p, m);
}

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
    G.p[l] = uint32_t(size_t(in.species[G.i[l]]) * in.nmat + size_t(in.species[G.j[l]]));
  }
  G.valid = std::min(4u, cnt - g);
  G.uniform = G.p[0] == G.p[1] && G.p[0] == G.p[2] && G.p[0] == G.p[3];
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
  const V4 fser = 1.0 + x * (0.5 + x * (0.375 + x * 0.3125));
  const V4 m1 = dot3(r, r);
  const V4 fex = sel(m1 > 0.0, sqrt4(m0 / m1), splat(1.0));
  r = r * sel(hn2 < 1e-4 * m0, fser, fex);
  h = sel3(m0 > 0.0, r, h);
}

/// limit_scale (core/vec3.hpp) in lanes; over: m2 > lim^2.
LANES_FN V4 limit_scale4(const V4 m2, const V4 lim, M4& over) {
  over = m2 > lim * lim;
  return sel(over, lim / sqrt4(sel(over, m2, splat(1.0))), splat(1.0));
}

/// LinearRestitutionDamping / TsujiDamping::apply with apply_limit: the damping force, and
/// gamma_n in gamma.
/// apply_limit (models/damping/restitution.hpp) in lanes: the damping force of gamma_n.
LANES_FN V4 apply_limit4(const V4 limit, const V4 gamma, const V4 vn, const V4 f_el) {
  const V4 fd0 = -gamma * vn;
  const M4 lim_on = (limit != 0.0) & (f_el + fd0 < 0.0) & (fd0 < 0.0);
  return sel(lim_on, -max0(f_el), fd0);
}
LANES_FN V4 damping4(const V4 two_beta, const V4 limit, const V4 mstar, const V4 kn, const V4 vn, const V4 f_el,
                     V4& gamma) {
  gamma = two_beta * sqrt4(mstar * kn);
  return apply_limit4(limit, gamma, vn, f_el);
}


/// TangentialCommon::update after its stiffness step: increment, trial force, Coulomb limit.
/// Returns the tangential force; fs becomes the new spring force.
LANES_FN L3 spring4(L3& fs, const L3& vt, const V4 kt, const V4 dt, const V4 gamma_t, const V4 mu, const V4 fc) {
  fs = fs - vt * (kt * dt);
  L3 ft = fs - vt * gamma_t;
  M4 slide;
  ft = ft * limit_scale4(dot3(ft, ft), mu * fc, slide);
  fs = sel3(slide, ft, fs);
  return ft;
}

/// TangentialCommon::update with a stiffness record (State::kt_prev): rotation, the spring
/// scaled by kt/kt_prev where the stiffness fell, then spring4; kt_prev becomes kt.
LANES_FN L3 spring_prev4(L3& fs, V4& kt_prev, const L3& n, const L3& vt, const V4 kt, const V4 dt, const V4 gamma_t,
                         const V4 mu, const V4 fc) {
  rotate_into_plane4(fs, n);
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

LANES_FN M4 is_inf(const V4 a) { return (a == kInfinity) | (a == -kInfinity); }

/// EpsdRolling::apply in lanes: mk is the spring's history; returns the moment on i.
LANES_FN L3 epsd4(const LaneInput& in, const Group& G, L3& mk, const V4 kn, const V4 fc, const V4 mu_r,
                  const V4 eta_r, const V4 dt) {
  const L3 wrel = G.wi - G.wj;
  const L3 wr = wrel - G.n * dot3(G.n, wrel);
  rotate_into_plane4(mk, G.n);
  const V4 kr = 2.25 * kn * mu_r * mu_r * G.rstar * G.rstar;
  mk = mk - wr * (kr * dt);
  M4 slide;
  mk = mk * limit_scale4(dot3(mk, mk), mu_r * G.rstar * fc, slide);
  // I_r = Ji Jj / (Ji + Jj), J = I + m r^2; a frozen body (I = inf) adds nothing.
  const V4 Ii = sel(G.fi, gather(in.inertia, G.i), splat(kInfinity));
  const V4 Ij = sel(G.fj, gather(in.inertia, G.j), splat(kInfinity));
  const M4 wi = is_inf(Ii), wj = is_inf(Ij);
  const V4 Ji = sel(wi, splat(0.0), Ii + G.mi * G.ri * G.ri), Jj = sel(wj, splat(0.0), Ij + G.mj * G.rj * G.rj);
  const V4 Ir = sel(wj, Ji, sel(wi, Jj, Ji * Jj / (Ji + Jj)));
  const L3 damped = mk - wr * (eta_r * 2.0 * sqrt4(Ir * kr));
  // eta_r = 0 leaves the spring alone (the scalar law's branch; damped would differ from it
  // only in the sign of a zero, or where I_r k_r is not finite).
  return sel3(eta_r > 0.0, sel3(slide, mk, damped), mk);
}

/// ContactLaw::evaluate's assembly for two spheres (lever arms r - delta/2) and the stores.
LANES_FN void put(const Group& G, const uint32_t g, const V4 fn, const L3& ft, const L3* mr, const V4 a, LaneOut& out) {
  const L3 nxft = cross3(G.n, ft);
  const L3 f = G.n * fn + ft;
  L3 ti = nxft * -G.li, tj = nxft * -G.lj;
  if (mr != nullptr) {
    ti = ti + *mr;
    tj = tj - *mr;
  }
  store(out.fx + g, f.x);
  store(out.fy + g, f.y);
  store(out.fz + g, f.z);
  store(out.tix + g, ti.x);
  store(out.tiy + g, ti.y);
  store(out.tiz + g, ti.z);
  store(out.tjx + g, tj.x);
  store(out.tjy + g, tj.y);
  store(out.tjz + g, tj.z);
  store(out.a + g, a);
}

/// The lanes of a Vec3 history member, zeroed where the contact ended (ContactLaw: s = State{}).
struct Lanes3 { alignas(32) double x[4], y[4], z[4]; };
LANES_FN void keep(const L3& h, const M4 alive, Lanes3& o) {
  _mm256_store_pd(o.x, __m256d(alive & M4(h.x)));
  _mm256_store_pd(o.y, __m256d(alive & M4(h.y)));
  _mm256_store_pd(o.z, __m256d(alive & M4(h.z)));
}

/// One group of four contacts of the linear law (after their geometry); kU: one material pair.
template <bool kU>
__attribute__((target("avx2"), always_inline)) inline void linear_group(
    const LaneInput& in, const Group& G, const uint32_t g, LaneOut& out) {
  const auto* const P = static_cast<const LinearLaneParams*>(in.params);
  auto* const H = static_cast<LinearLaneHistory*>(in.hist);
  using LP = LinearLaneParams;
  // LinearNormal.
  const V4 kn = par<kU>(P, G.p, &LP::kn);
  const M4 alive = G.delta > 0.0;
  const V4 f_el = kn * G.delta;
  V4 gamma;
  const V4 fn = f_el + damping4(par<kU>(P, G.p, &LP::two_beta), par<kU>(P, G.p, &LP::limit), G.mstar, kn, G.vn, f_el, gamma);
  const V4 fc = max0(fn);  // NormalBase::coulomb_base
  // LinearTangential: kt fixed per material pair.
  L3 fs = gather3(H, G.k, &LinearLaneHistory::fs);
  rotate_into_plane4(fs, G.n);
  const L3 ft = spring4(fs, G.vt, par<kU>(P, G.p, &LP::kt), splat(in.dt), par<kU>(P, G.p, &LP::damp_t) * gamma,
                        par<kU>(P, G.p, &LP::mu), fc);
  // LinearNormal's contact radius, read only when asked for.
  put(G, g, fn, ft, nullptr, in.want_a ? sqrt4(G.rstar * G.delta) : splat(0.0), out);
  Lanes3 s;
  keep(fs, alive, s);
  const int am = _mm256_movemask_pd(__m256d(alive));
  for (uint32_t l = 0; l < G.valid; ++l) {
    out.alive[g + l] = uint8_t((am >> l) & 1);
    H[G.k[l]].fs = Vec3{s.x[l], s.y[l], s.z[l]};
  }
}

/// One group of four contacts of Hertz-Mindlin + EPSD (after their geometry); kU: one material pair.
template <bool kU>
__attribute__((target("avx2"), always_inline)) inline void hertz_epsd_group(
    const LaneInput& in, const Group& G, const uint32_t g, LaneOut& out) {
  const auto* const P = static_cast<const HertzEpsdLaneParams*>(in.params);
  auto* const H = static_cast<HertzEpsdLaneHistory*>(in.hist);
  using LP = HertzEpsdLaneParams;
  using LH = HertzEpsdLaneHistory;
  const V4 dt = splat(in.dt);
  // HertzNormal (the lanes of ended contacts compute what no one reads).
  const M4 alive = G.delta > 0.0;
  const V4 a = sqrt4(G.rstar * G.delta);
  const V4 kn = par<kU>(P, G.p, &LP::two_Estar) * a;
  const V4 f_el = (2.0 / 3.0) * kn * G.delta;
  V4 gamma;
  const V4 fn = f_el + damping4(par<kU>(P, G.p, &LP::two_beta), par<kU>(P, G.p, &LP::limit), G.mstar, kn, G.vn, f_el, gamma);
  const V4 fc = max0(fn);
  // MindlinTangential: kt = 8 G* a; a spring whose stiffness fell is scaled by kt/kt_prev.
  const V4 kt = par<kU>(P, G.p, &LP::eight_Gstar) * a;
  L3 fs = gather3(H, G.k, &LH::fs);
  V4 kt_prev = gather(H, G.k, &LH::kt_prev);
  const L3 ft = spring_prev4(fs, kt_prev, G.n, G.vt, kt, dt, par<kU>(P, G.p, &LP::damp_kt) * gamma,
                             par<kU>(P, G.p, &LP::mu), fc);
  L3 mk = gather3(H, G.k, &LH::mk);
  const L3 mr = epsd4(in, G, mk, kn, fc, par<kU>(P, G.p, &LP::mu_r), par<kU>(P, G.p, &LP::eta_r), dt);
  put(G, g, fn, ft, &mr, a, out);
  Lanes3 s, m;
  keep(fs, alive, s);
  keep(mk, alive, m);
  const V4 ktp = V4(_mm256_and_pd(__m256d(alive), __m256d(kt_prev)));
  alignas(32) double kp[4];
  _mm256_store_pd(kp, __m256d(ktp));
  const int am = _mm256_movemask_pd(__m256d(alive));
  for (uint32_t l = 0; l < G.valid; ++l) {
    out.alive[g + l] = uint8_t((am >> l) & 1);
    H[G.k[l]] = LH{Vec3{s.x[l], s.y[l], s.z[l]}, kp[l], Vec3{m.x[l], m.y[l], m.z[l]}};
  }
}

/// One group of four contacts of MEPA + EPSD (after their geometry); kU: one material pair.
template <bool kU>
__attribute__((target("avx2"), always_inline)) inline void mepa_epsd_group(
    const LaneInput& in, const Group& G, const uint32_t g, LaneOut& out) {
  const auto* const P = static_cast<const MepaEpsdLaneParams*>(in.params);
  auto* const H = static_cast<MepaEpsdLaneHistory*>(in.hist);
  using LP = MepaEpsdLaneParams;
  using LH = MepaEpsdLaneHistory;
  const V4 dt = splat(in.dt);
  // HystereticNormal::apply with fixed stiffnesses (lane_usable): D = delta^n with
  // delta^(n-1) = 1 (n = 1) or sqrt(delta) (n = 3/2); the branch of the larger of f1, f2,
  // bounded below by the adhesive -A.
  const M4 alive = G.delta > 0.0;
  const V4 d = G.delta;
  const V4 dn1 = sel(par<kU>(P, G.p, &LP::n_is_1) != 0.0, splat(1.0), sqrt4(d));
  const V4 D = d * dn1;
  const V4 A = par<kU>(P, G.p, &LP::kadh) * D;
  const V4 k1 = par<kU>(P, G.p, &LP::k1), k2 = par<kU>(P, G.p, &LP::k2);
  const V4 Dmax = gather(H, G.k, &LH::Dmax), Dp = gather(H, G.k, &LH::Dp);
  const V4 f1 = k1 * D, f2 = k2 * (D - Dp);
  const M4 load = f2 >= f1;
  const M4 adh = ~load & ~(f2 > -A);
  const V4 f = sel(load, f1, sel(adh, -A, f2));
  const V4 Dp_new = D * par<kU>(P, G.p, &LP::plastic);
  const V4 Dmax1 = sel(load, D, Dmax), Dp1 = sel(load, Dp_new, Dp);
  const V4 f0 = par<kU>(P, G.p, &LP::f0);
  const V4 f_el = f0 + f;
  const V4 f_adh = A - f0;
  const V4 kn = par<kU>(P, G.p, &LP::n) * k2 * dn1;
  const V4 k_load = k1 * dn1;
  // ViscousDamping.
  const V4 gamma = par<kU>(P, G.p, &LP::gamma_n);
  const V4 fn = f_el + apply_limit4(par<kU>(P, G.p, &LP::limit), gamma, G.vn, f_el);
  const V4 fc = max0(sel(par<kU>(P, G.p, &LP::offset) != 0.0, f_el + f_adh, f_el));  // coulomb_base
  // HystTangential: a fixed kt, or kt_ratio k1 delta^(n-1) kt_mult.
  const V4 kt = sel(par<kU>(P, G.p, &LP::kt_const) != 0.0, par<kU>(P, G.p, &LP::kt_c),
                    par<kU>(P, G.p, &LP::kt_ratio) * k_load * par<kU>(P, G.p, &LP::kt_mult));
  L3 fs = gather3(H, G.k, &LH::fs);
  V4 kt_prev = gather(H, G.k, &LH::kt_prev);
  const L3 ft = spring_prev4(fs, kt_prev, G.n, G.vt, kt, dt, par<kU>(P, G.p, &LP::damp_t) * gamma,
                             par<kU>(P, G.p, &LP::mu), fc);
  L3 mk = gather3(H, G.k, &LH::mk);
  const L3 mr = epsd4(in, G, mk, kn, fc, par<kU>(P, G.p, &LP::mu_r), par<kU>(P, G.p, &LP::eta_r), dt);
  put(G, g, fn, ft, &mr, in.want_a ? sqrt4(G.rstar * d) : splat(0.0), out);
  Lanes3 s, m;
  keep(fs, alive, s);
  keep(mk, alive, m);
  alignas(32) double kp[4], dm[4], dpl[4];
  _mm256_store_pd(kp, _mm256_and_pd(__m256d(alive), __m256d(kt_prev)));
  _mm256_store_pd(dm, _mm256_and_pd(__m256d(alive), __m256d(Dmax1)));
  _mm256_store_pd(dpl, _mm256_and_pd(__m256d(alive), __m256d(Dp1)));
  const int am = _mm256_movemask_pd(__m256d(alive));
  const int lm = _mm256_movemask_pd(__m256d(load)), bm = _mm256_movemask_pd(__m256d(adh));
  for (uint32_t l = 0; l < G.valid; ++l) {
    const bool al = (am >> l) & 1;
    out.alive[g + l] = uint8_t(al);
    LH& h = H[G.k[l]];
    h.Dmax = dm[l];
    h.Dp = dpl[l];
    h.branch = !al ? 0 : (((lm >> l) & 1) ? 1 : (((bm >> l) & 1) ? 3 : 2));
    h.fs = Vec3{s.x[l], s.y[l], s.z[l]};
    h.kt_prev = kp[l];
    h.mk = Vec3{m.x[l], m.y[l], m.z[l]};
  }
}

}  // namespace

__attribute__((target("avx2"))) void linear_lanes_avx2(const LaneInput& in, const ScreenHits& hits, const uint32_t h0,
                                                       const uint32_t cnt, LaneOut& out) {
  drive<linear_group<true>, linear_group<false>>(in, hits, h0, cnt, out);
}

__attribute__((target("avx2"))) void hertz_epsd_lanes_avx2(const LaneInput& in, const ScreenHits& hits,
                                                           const uint32_t h0, const uint32_t cnt, LaneOut& out) {
  drive<hertz_epsd_group<true>, hertz_epsd_group<false>>(in, hits, h0, cnt, out);
}

__attribute__((target("avx2"))) void mepa_epsd_lanes_avx2(const LaneInput& in, const ScreenHits& hits,
                                                          const uint32_t h0, const uint32_t cnt, LaneOut& out) {
  drive<mepa_epsd_group<true>, mepa_epsd_group<false>>(in, hits, h0, cnt, out);
}

#else

void linear_lanes_avx2(const LaneInput&, const ScreenHits&, uint32_t, uint32_t, LaneOut&) {}
void hertz_epsd_lanes_avx2(const LaneInput&, const ScreenHits&, uint32_t, uint32_t, LaneOut&) {}
void mepa_epsd_lanes_avx2(const LaneInput&, const ScreenHits&, uint32_t, uint32_t, LaneOut&) {}

#endif

}  // namespace cohdem
