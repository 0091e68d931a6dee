// The linear law's contacts four at a time in AVX2 registers (see lanes.hpp). Written with
// GCC's vector extensions (the operators act lane by lane, as the scalar code's do on one
// contact) in functions compiled for AVX2 alone: no fused multiply-adds, which would round
// differently from the scalar law. Each scalar branch becomes a select between the values
// both sides compute; lanes past the chunk's end repeat its last contact and are not stored.
#include "sim/lanes.hpp"

#include <algorithm>
#include <cstring>
#include <limits>

#include "particles/particle_store.hpp"

#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace cohdem {

LinearLaneParams linear_lane_params(const LinearLaw::Params& p) {
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

#if defined(__x86_64__)

namespace {

typedef double V4 __attribute__((vector_size(32)));
typedef long long M4 __attribute__((vector_size(32)));  // lane masks: all ones or zero

#define LANES_FN __attribute__((target("avx2"), always_inline)) inline

LANES_FN V4 sqrt4(const V4 a) { return V4(_mm256_sqrt_pd(__m256d(a))); }
/// std::max(a, 0.0) lane by lane: a < 0 ? 0 : a (a -0 or a NaN passes through, as there).
LANES_FN V4 max0(const V4 a) { return V4(_mm256_max_pd(_mm256_setzero_pd(), __m256d(a))); }
LANES_FN V4 sel(const M4 m, const V4 a, const V4 b) { return m ? a : b; }
LANES_FN V4 splat(const double s) { return V4{s, s, s, s}; }

/// Four doubles from a[i0..i3].
LANES_FN V4 gather(const double* __restrict a, const uint32_t* idx) {
  return V4{a[idx[0]], a[idx[1]], a[idx[2]], a[idx[3]]};
}

struct L3 { V4 x, y, z; };
/// x, y, z of four Vec3s p[idx[0..3]], one lane each.
LANES_FN L3 gather3(const Vec3* __restrict p, const uint32_t* idx) {
  const __m256d t0 = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(&p[idx[0]].x)), _mm_loadu_pd(&p[idx[2]].x), 1);
  const __m256d t1 = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(&p[idx[1]].x)), _mm_loadu_pd(&p[idx[3]].x), 1);
  L3 r;
  r.x = V4(_mm256_unpacklo_pd(t0, t1));
  r.y = V4(_mm256_unpackhi_pd(t0, t1));
  r.z = V4(_mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadh_pd(_mm_load_sd(&p[idx[0]].z), &p[idx[1]].z)),
                                _mm_loadh_pd(_mm_load_sd(&p[idx[2]].z), &p[idx[3]].z), 1));
  return r;
}

LANES_FN V4 dot3(const L3& a, const L3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

/// One group of four contacts (lanes whose hit lies past the chunk repeat its last one).
__attribute__((target("avx2"))) void group(const LaneInput& in, const ScreenHits& hits, const uint32_t h0,
                                          const uint32_t cnt, const uint32_t g, LaneOut& out) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  uint32_t hh[4], k[4], i[4], j[4], pidx[4];
  for (uint32_t l = 0; l < 4; ++l) {
    hh[l] = h0 + std::min(g + l, cnt - 1);
    k[l] = hits.k[hh[l]];
    i[l] = hits.row[hh[l]];
    j[l] = in.jdx[k[l]];
    pidx[l] = uint32_t(size_t(in.species[i[l]]) * in.nmat + size_t(in.species[j[l]]));
  }
  const M4 fi = M4{-(in.flag[i[0]] == kFree), -(in.flag[i[1]] == kFree), -(in.flag[i[2]] == kFree),
                   -(in.flag[i[3]] == kFree)};
  const M4 fj = M4{-(in.flag[j[0]] == kFree), -(in.flag[j[1]] == kFree), -(in.flag[j[2]] == kFree),
                   -(in.flag[j[3]] == kFree)};
  // The material pairs' parameters.
  const LinearLaneParams* const P = in.params;
  const V4 kn{P[pidx[0]].kn, P[pidx[1]].kn, P[pidx[2]].kn, P[pidx[3]].kn};
  const V4 two_beta{P[pidx[0]].two_beta, P[pidx[1]].two_beta, P[pidx[2]].two_beta, P[pidx[3]].two_beta};
  const V4 limit{P[pidx[0]].limit, P[pidx[1]].limit, P[pidx[2]].limit, P[pidx[3]].limit};
  const V4 mu{P[pidx[0]].mu, P[pidx[1]].mu, P[pidx[2]].mu, P[pidx[3]].mu};
  const V4 kt{P[pidx[0]].kt, P[pidx[1]].kt, P[pidx[2]].kt, P[pidx[3]].kt};
  const V4 damp_t{P[pidx[0]].damp_t, P[pidx[1]].damp_t, P[pidx[2]].damp_t, P[pidx[3]].damp_t};

  // Geometry (the kernel's PairGeom).
  const V4 ri = gather(in.radius, i), rj = gather(in.radius, j);
  const V4 rsum = ri + rj;
  const V4 dist = sqrt4(gather(hits.d2, hh));
  const V4 inv = splat(1.0) / dist;
  L3 n;
  n.x = gather(hits.dx, hh) * inv;
  n.y = gather(hits.dy, hh) * inv;
  n.z = gather(hits.dz, hh) * inv;
  const V4 delta = rsum - dist;
  const V4 rstar = ri * rj / rsum;
  const V4 mi = sel(fi, gather(in.mass, i), splat(inf));
  const V4 mj = sel(fj, gather(in.mass, j), splat(inf));
  const V4 mstar = sel(fi & fj, mi * mj / (mi + mj), sel(fi, mi, mj));
  const L3 vi = gather3(in.v, i), vj = gather3(in.v, j);
  const L3 vij{vi.x - vj.x, vi.y - vj.y, vi.z - vj.z};
  const V4 vn = dot3(vij, n);
  const V4 li = ri - 0.5 * delta, lj = rj - 0.5 * delta;
  const L3 wi = gather3(in.omega, i), wj = gather3(in.omega, j);
  const L3 w{wi.x * li + wj.x * lj, wi.y * li + wj.y * lj, wi.z * li + wj.z * lj};
  // vrel = vij - w x n
  const L3 vrel{vij.x - (w.y * n.z - w.z * n.y), vij.y - (w.z * n.x - w.x * n.z), vij.z - (w.x * n.y - w.y * n.x)};
  const V4 vrn = dot3(vrel, n);
  const L3 vt{vrel.x - n.x * vrn, vrel.y - n.y * vrn, vrel.z - n.z * vrn};

  // LinearNormal.
  const M4 alive = delta > 0.0;
  const V4 f_el = kn * delta;
  // LinearRestitutionDamping (apply_limit: with limit_damping, a damping force that would
  // make the total attractive leaves -max(f_el, 0)).
  const V4 gamma = two_beta * sqrt4(mstar * kn);
  const V4 fd0 = -gamma * vn;
  const M4 lim_on = (limit != 0.0) & (f_el + fd0 < 0.0) & (fd0 < 0.0);
  const V4 fd = sel(lim_on, -max0(f_el), fd0);
  const V4 fn = f_el + fd;
  const V4 fc = max0(fn);  // NormalBase::coulomb_base

  // LinearTangential (TangentialCommon::update). 1. The history into the tangent plane,
  // its length kept (rotate_into_plane: series factor for small turns, else the exact one).
  L3 fs = gather3(in.fs, k);
  {
    const V4 m0 = dot3(fs, fs);
    const V4 hn = n.x * fs.x + n.y * fs.y + n.z * fs.z;
    L3 h{fs.x - n.x * hn, fs.y - n.y * hn, fs.z - n.z * hn};
    const V4 hn2 = hn * hn;
    const M4 series = hn2 < 1e-4 * m0;
    const V4 x = hn2 / m0;
    const V4 fser = 1.0 + x * (0.5 + x * (0.375 + x * 0.3125));
    const V4 m1 = dot3(h, h);
    const V4 fex = sel(m1 > 0.0, sqrt4(m0 / m1), splat(1.0));
    const V4 fac = sel(series, fser, fex);
    h.x *= fac;
    h.y *= fac;
    h.z *= fac;
    const M4 turn = m0 > 0.0;
    fs.x = sel(turn, h.x, fs.x);
    fs.y = sel(turn, h.y, fs.y);
    fs.z = sel(turn, h.z, fs.z);
  }
  // 3. the increment, the trial force; 4. the Coulomb limit (limit_scale).
  const V4 ktdt = kt * in.dt;
  fs.x -= vt.x * ktdt;
  fs.y -= vt.y * ktdt;
  fs.z -= vt.z * ktdt;
  const V4 gamma_t = damp_t * gamma;
  L3 ft{fs.x - vt.x * gamma_t, fs.y - vt.y * gamma_t, fs.z - vt.z * gamma_t};
  const V4 lim = mu * fc;
  const V4 f2 = dot3(ft, ft);
  const M4 slide = f2 > lim * lim;
  const V4 scale = sel(slide, lim / sqrt4(sel(slide, f2, splat(1.0))), splat(1.0));
  ft.x *= scale;
  ft.y *= scale;
  ft.z *= scale;
  fs.x = sel(slide, ft.x, fs.x);
  fs.y = sel(slide, ft.y, fs.y);
  fs.z = sel(slide, ft.z, fs.z);

  // ContactLaw::evaluate's assembly (two spheres: lever arms r - delta/2).
  const L3 nxft{n.y * ft.z - n.z * ft.y, n.z * ft.x - n.x * ft.z, n.x * ft.y - n.y * ft.x};
  const V4 mli = -li, mlj = -lj;
  _mm256_storeu_pd(out.fx + g, __m256d(n.x * fn + ft.x));
  _mm256_storeu_pd(out.fy + g, __m256d(n.y * fn + ft.y));
  _mm256_storeu_pd(out.fz + g, __m256d(n.z * fn + ft.z));
  _mm256_storeu_pd(out.tix + g, __m256d(nxft.x * mli));
  _mm256_storeu_pd(out.tiy + g, __m256d(nxft.y * mli));
  _mm256_storeu_pd(out.tiz + g, __m256d(nxft.z * mli));
  _mm256_storeu_pd(out.tjx + g, __m256d(nxft.x * mlj));
  _mm256_storeu_pd(out.tjy + g, __m256d(nxft.y * mlj));
  _mm256_storeu_pd(out.tjz + g, __m256d(nxft.z * mlj));
  // LinearNormal's contact radius (read only for live contacts).
  _mm256_storeu_pd(out.a + g, __m256d(in.want_a ? sqrt4(rstar * delta) : splat(0.0)));
  const int am = _mm256_movemask_pd(__m256d(alive));
  // The histories: a contact that ended starts again from zero (ContactLaw: s = State{}).
  alignas(32) double sx[4], sy[4], sz[4];
  _mm256_store_pd(sx, __m256d(alive & M4(fs.x)));
  _mm256_store_pd(sy, __m256d(alive & M4(fs.y)));
  _mm256_store_pd(sz, __m256d(alive & M4(fs.z)));
  const uint32_t nl = std::min(4u, cnt - g);
  for (uint32_t l = 0; l < nl; ++l) {
    out.alive[g + l] = uint8_t((am >> l) & 1);
    in.fs[k[l]] = Vec3{sx[l], sy[l], sz[l]};
  }
}

}  // namespace

__attribute__((target("avx2"))) void linear_lanes_avx2(const LaneInput& in, const ScreenHits& hits, const uint32_t h0,
                                                       const uint32_t cnt, LaneOut& out) {
  for (uint32_t g = 0; g < cnt; g += 4) group(in, hits, h0, cnt, g, out);
}

#else

void linear_lanes_avx2(const LaneInput&, const ScreenHits&, uint32_t, uint32_t, LaneOut&) {}

#endif

}  // namespace cohdem
