// The lanes of contacts at any register width: the laws' groups, their geometry and their
// stores, written once with GCC's vector extensions (the operators act lane by lane, as the
// scalar code's do on one contact). Included twice, inside the anonymous namespace of
//   - lanes_avx2.cpp (kW = 4, AVX2) and
//   - lanes_avx512.cpp (kW = 8, AVX-512),
// each of which first defines the width's primitives this file uses:
//   LANES_FN, LANES_TARGET (the function attribute and its target string), kW, V (kW doubles),
//   M (kW lane masks, all bits set or none); sqrtv, max0, sel, any, splat, msplat, loadv, store, make,
//   makem, gather (kW doubles a[idx[l]]), load3 (kW Vec3s into lanes), Quads / Pairs / quads / pairs (the lanes transposed
//   into records: q[l] the four doubles of lane l, p[l] two), Cols / load_quads / load_pairs
//   (records transposed into lanes), put_alive, par_load (a uniform group's parameter).
// Each scalar branch becomes a select between the values both sides compute; lanes past the
// chunk's end repeat its last contact and are not stored. No fused multiply-adds (AVX2 has
// none; the AVX-512 file is compiled with -ffp-contract=off), which would round differently
// from the scalar law.
#if !defined(LANES_FN) || !defined(LANES_TARGET)
#error "sim/lanes_body.hpp is included by lanes_avx2.cpp and lanes_avx512.cpp only"
#endif

#define LANES_LAMBDA __attribute__((target(LANES_TARGET), always_inline))

constexpr double kInfinity = std::numeric_limits<double>::infinity();

/// A group's material pairs' parameters, lane by lane: par(&T::m) is member m in each lane,
/// par_load'ed where all lanes share the pair (kU; one material, or the chute's flowing
/// spheres among themselves), else gathered. A switch (uint64_t member) gives a lane mask.
template <bool kU, class T>
struct Par {
  const LaneParamsOf<T>* __restrict P;
  const uint32_t* p;
  const LaneParamsOf<T>* __restrict u;  ///< the pair of lane 0 (all lanes' where kU)
  LANES_FN Par(const void* P_, const uint32_t* p_)
      : P(static_cast<const LaneParamsOf<T>*>(P_)), p(p_), u(P + p_[0]) {}
  LANES_FN V operator()(double T::*m) const {
    if constexpr (kU) return par_load(u, m);
    else return make([&](const uint32_t l) LANES_LAMBDA { return P[p[l]].p.*m; });
  }
  LANES_FN M operator()(uint64_t T::*m) const {
    if constexpr (kU) return par_load(u, m);
    else return makem([&](const uint32_t l) LANES_LAMBDA { return (long long)(P[p[l]].p.*m); });
  }
};

struct L3 { V x, y, z; };
LANES_FN L3 operator-(const L3& a, const L3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
LANES_FN L3 operator+(const L3& a, const L3& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
LANES_FN L3 operator*(const L3& a, const V s) { return {a.x * s, a.y * s, a.z * s}; }
LANES_FN V dot3(const L3& a, const L3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
LANES_FN L3 cross3(const L3& a, const L3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
LANES_FN L3 sel3(const M m, const L3& a, const L3& b) { return {sel(m, a.x, b.x), sel(m, a.y, b.y), sel(m, a.z, b.z)}; }

/// The Vec3 member m of records p[idx[0 .. kW)].
template <class T>
LANES_FN L3 gather3(const T* __restrict p, const uint32_t* idx, Vec3 T::*m) {
  const Vec3* a[kW];
  for (uint32_t l = 0; l < kW; ++l) a[l] = &(p[idx[l]].*m);
  L3 r;
  load3(a, r.x, r.y, r.z);
  return r;
}
/// p[idx[0 .. kW)].
LANES_FN L3 gather3(const Vec3* __restrict p, const uint32_t* idx) {
  const Vec3* a[kW];
  for (uint32_t l = 0; l < kW; ++l) a[l] = &p[idx[l]];
  L3 r;
  load3(a, r.x, r.y, r.z);
  return r;
}

/// The lanes' contacts: list entries, rows, partners, material pairs, and the kernel's
/// PairGeom in lanes (the same operations as sim/force_kernel.hpp's scalar geometry).
struct Group {
  uint32_t hh[kW], k[kW], i[kW], j[kW], p[kW];
  uint32_t valid;  ///< lanes that hold a contact of the chunk
  bool uniform;    ///< all lanes of one material pair (its parameters broadcast)
  M fi, fj;        ///< i, j free (not frozen)
  L3 n, vt, wi, wj;  ///< wi, wj: the spins
  V ri, rj, delta, rstar, mi, mj, mstar, vn, li, lj;
};

LANES_FN void geometry(const LaneInput& in, const ScreenHits& hits, const uint32_t h0, const uint32_t cnt,
                       const uint32_t g, Group& G) {
  for (uint32_t l = 0; l < kW; ++l) {
    G.hh[l] = h0 + std::min(g + l, cnt - 1);
    G.k[l] = hits.k[G.hh[l]];
    G.i[l] = hits.row[G.hh[l]];
    G.j[l] = in.jdx[G.k[l]];
  }
  G.valid = std::min(kW, cnt - g);
  // One material: one pair, no species read.
  if (in.nmat == 1) {
    for (uint32_t l = 0; l < kW; ++l) G.p[l] = 0;
    G.uniform = true;
  } else {
    for (uint32_t l = 0; l < kW; ++l)
      G.p[l] = uint32_t(size_t(in.species[G.i[l]]) * in.nmat + size_t(in.species[G.j[l]]));
    G.uniform = true;
    for (uint32_t l = 1; l < kW; ++l) G.uniform = G.uniform && G.p[l] == G.p[0];
  }
  const uint8_t* const flag = in.flag;
  G.fi = makem([&](const uint32_t l) LANES_LAMBDA { return -(long long)(flag[G.i[l]] == kFree); });
  G.fj = makem([&](const uint32_t l) LANES_LAMBDA { return -(long long)(flag[G.j[l]] == kFree); });
  G.ri = gather(in.radius, G.i);
  G.rj = gather(in.radius, G.j);
  const V rsum = G.ri + G.rj;
  // The screened pairs' separations: consecutive hits, so one load each where the group is
  // full (most groups), else gathered with the last contact repeated.
  V d2;
  L3 dxyz;
  if (G.valid == kW) {
    const uint32_t b = h0 + g;
    d2 = loadv(hits.d2 + b);
    dxyz = L3{loadv(hits.dx + b), loadv(hits.dy + b), loadv(hits.dz + b)};
  } else {
    d2 = gather(hits.d2, G.hh);
    dxyz = L3{gather(hits.dx, G.hh), gather(hits.dy, G.hh), gather(hits.dz, G.hh)};
  }
  const V dist = sqrtv(d2);
  const V inv = splat(1.0) / dist;
  G.n = dxyz * inv;
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
  const V m0 = dot3(h, h);
  const V hn = dot3(n, h);
  L3 r = h - n * hn;
  const V hn2 = hn * hn;
  const V x = hn2 / m0;
  V f = 1.0 + x * (0.5 + x * (0.375 + x * 0.3125));
  // The exact factor (a division and a square root) only where a lane whose history is kept
  // turned by more than the series covers: almost never (a branch that predicts well); the
  // lanes take the same values as with both computed and selected.
  const M series = hn2 < 1e-4 * m0, used = m0 > 0.0;
  if (__builtin_expect(any(used & ~series), 0)) {
    const V m1 = dot3(r, r);
    f = sel(series, f, sel(m1 > 0.0, sqrtv(m0 / m1), splat(1.0)));
  }
  r = r * f;
  h = sel3(used, r, h);
}

/// h *= limit_scale(|h|^2, lim) (core/vec3.hpp) in lanes: the lanes over the limit scaled
/// to it, the others left as they are (the scalar code multiplies them by exactly 1, which
/// changes no bit). Returns the lanes over. The division, the square root and the products
/// only where a lane is over: sticking contacts, most of a packing's, skip them.
LANES_FN M limit4(L3& h, const V lim) {
  const V m2 = dot3(h, h);
  const M over = m2 > lim * lim;
  if (any(over)) h = h * sel(over, lim / sqrtv(m2), splat(1.0));
  return over;
}

/// apply_limit (models/damping/restitution.hpp) in lanes: the damping force of gamma_n.
LANES_FN V apply_limit4(const M limit, const V gamma, const V vn, const V f_el) {
  const V fd0 = -gamma * vn;
  const M lim_on = limit & (f_el + fd0 < 0.0) & (fd0 < 0.0);
  return sel(lim_on, -max0(f_el), fd0);
}
/// LinearRestitutionDamping / TsujiDamping::apply with apply_limit: the damping force, and
/// gamma_n in gamma.
LANES_FN V damping4(const V two_beta, const M limit, const V mstar, const V kn, const V vn, const V f_el, V& gamma) {
  gamma = two_beta * sqrtv(mstar * kn);
  return apply_limit4(limit, gamma, vn, f_el);
}

/// TangentialCommon::update after its stiffness step: increment, trial force, Coulomb limit.
/// Returns the tangential force; fs becomes the new spring force.
LANES_FN L3 spring4(L3& fs, const L3& vt, const V kt, const V dt, const V gamma_t, const V mu, const V fc) {
  fs = fs - vt * (kt * dt);
  L3 ft = fs - vt * gamma_t;
  const M slide = limit4(ft, mu * fc);
  fs = sel3(slide, ft, fs);
  return ft;
}

/// TangentialCommon::update with a stiffness record (State::kt_prev), after its rotation
/// (the caller's rotate_into_plane4): the spring scaled by kt/kt_prev where the stiffness
/// fell, then spring4; kt_prev becomes kt.
LANES_FN L3 spring_prev4(L3& fs, V& kt_prev, const L3& vt, const V kt, const V dt, const V gamma_t, const V mu,
                         const V fc) {
  fs = sel3((kt_prev > 0.0) & (kt < kt_prev), fs * (kt / kt_prev), fs);
  kt_prev = kt;
  return spring4(fs, vt, kt, dt, gamma_t, mu, fc);
}

/// Evaluates the chunk's groups with Group's kU: the uniform variant where one material pair
/// fills the group, else the mixed one.
using GroupFn = void (*)(const LaneInput&, const Group&, uint32_t, LaneOut&);
template <GroupFn kUniform, GroupFn kMixed>
LANES_FN void drive(const LaneInput& in, const ScreenHits& hits, const uint32_t h0, const uint32_t cnt, LaneOut& out) {
  static_assert(kLaneChunk % kW == 0, "the stores of a group stay inside LaneOut");
  for (uint32_t g = 0; g < cnt; g += kW) {
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
/// finite): J = I + m r^2 of a free body, 0 (not read) of a frozen one. I is the solid
/// sphere's, computed as sphere_inertia (particles/particle_store.hpp) computes the stored one,
/// ((0.4 m) r) r, so the same bits: two gathers fewer a group (MEPA + EPSD over the linear law
/// 1.5-6 % lower, BM_ForceAlternate, fifty-third round).
LANES_FN V rolling_inertia4(const Group& G) {
  const V Ji = sel(G.fi, 0.4 * G.mi * G.ri * G.ri + G.mi * G.ri * G.ri, splat(0.0));
  const V Jj = sel(G.fj, 0.4 * G.mj * G.rj * G.rj + G.mj * G.rj * G.rj, splat(0.0));
  return sel(G.fj, sel(G.fi, Ji * Jj / (Ji + Jj), Jj), Ji);
}
/// EPSD's stiffness k_r and viscous coefficient eta_r 2 sqrt(I_r k_r): they need only the
/// geometry and the normal law's kn. The Hertz-Mindlin and MEPA groups compute them as soon
/// as kn is known, so that the division and square root overlap the rest of the law (3-4 %
/// faster for Hertz-Mindlin + EPSD); the linear group at the end, which measured 3-4 %
/// faster there (BM_ForceAlternate, the variants built side by side).
struct EpsdCoef { V kr, visc; };
LANES_FN EpsdCoef epsd_coef4(const Group& G, const V kn, const V mu_r, const V two_eta_r,
                             const M damped) {
  const V kr = 2.25 * kn * mu_r * mu_r * G.rstar * G.rstar;
  // eta_r = 0 (the default, and the ring shear cases'): no viscous part (epsd4 selects the
  // spring alone), so no I_r and no square root. A branch on the material pairs' switch, the
  // same from group to group.
  if (!any(damped)) return {kr, splat(0.0)};
  return {kr, two_eta_r * sqrtv(rolling_inertia4(G) * kr)};
}
/// EpsdRolling::apply in lanes: mk is the spring's history, already turned into the new
/// tangent plane (the caller's rotate_into_plane4); returns the moment on i. c: epsd_coef4;
/// damped: eta_r > 0.
LANES_FN L3 epsd4(const Group& G, L3& mk, const EpsdCoef& c, const V fc, const V mu_r, const M damped, const V dt) {
  const L3 wrel = G.wi - G.wj;
  const L3 wr = wrel - G.n * dot3(G.n, wrel);
  mk = mk - wr * (c.kr * dt);
  const M slide = limit4(mk, mu_r * G.rstar * fc);
  const L3 damped_m = mk - wr * c.visc;
  // eta_r = 0 leaves the spring alone (the scalar law's branch; damped_m would differ from it
  // only in the sign of a zero, or where I_r k_r is not finite).
  return sel3(damped & ~slide, damped_m, mk);
}

/// SdsRolling::apply in lanes: fk is the spring's force, already turned into the new tangent
/// plane (the caller's rotate_into_plane4); returns the moment on i.
LANES_FN L3 sds4(const Group& G, L3& fk, const V fc, const V k_r, const V gamma_r, const V mu_r, const V dt) {
  const L3 vr = cross3(G.wi - G.wj, G.n) * G.rstar;
  fk = fk - vr * (k_r * dt);
  const L3 damp = vr * gamma_r;
  L3 f = fk - damp;
  const M slide = limit4(f, mu_r * fc);
  fk = sel3(slide, f + damp, fk);
  return cross3(G.n, f) * G.rstar;
}

/// The rolling moment on i of a group with EPSD (c: epsd_coef4) or SDS, the spring mk (EPSD's
/// moment, SDS's force) already turned into the new tangent plane; LP: the law's lane
/// parameters, read through par.
template <int kRoll, class LP, class ParT>
LANES_FN L3 rolling4(const Group& G, L3& mk, const EpsdCoef& c, const V fc, const ParT& par, const V dt) {
  if constexpr (kRoll == kLaneSds)
    return sds4(G, mk, fc, par(&LP::k_r), par(&LP::gamma_r), par(&LP::mu_r), dt);
  else
    return epsd4(G, mk, c, fc, par(&LP::mu_r), par(&LP::damped), dt);
}

/// ContactLaw::evaluate's assembly for two spheres (lever arms r - delta/2) and the stores.
LANES_FN void put(const Group& G, const uint32_t g, const M alive, const V fn, const L3& ft, const L3* mr, const V a,
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
  auto st = [o](const size_t off, const V v) LANES_LAMBDA { store(reinterpret_cast<double*>(o + off), v); };
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

/// f(l) for each lane l that holds a contact of the chunk: all written out where the group
/// is full (most groups), so the stores need no loop.
template <class F>
LANES_FN void each_lane(const Group& G, F&& f) {
  if (G.valid == kW) {
#pragma GCC unroll 8
    for (uint32_t l = 0; l < kW; ++l) f(l);
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
  each_lane(G, [&](const uint32_t l) LANES_LAMBDA {
    double* const r = lanes4::rec(h, G.k[l]);
    (store_part(r, l, parts), ...);
  });
}

// The records' layouts that the loads and stores below assume by their offsets (lanes.hpp's
// same_layout checks the records against the laws' State).
static_assert(sizeof(LinearLaneHistory) == 24 && offsetof(LinearLaneHistory, fs) == 0);
static_assert(sizeof(LinearRollingLaneHistory) == 48 && offsetof(LinearRollingLaneHistory, fs) == 0 &&
              offsetof(LinearRollingLaneHistory, mk) == 24);
static_assert(sizeof(HertzLaneHistory) == 32 && offsetof(HertzLaneHistory, fs) == 0 &&
              offsetof(HertzLaneHistory, kt_prev) == 24);
static_assert(sizeof(HertzRollingLaneHistory) == 56 && offsetof(HertzRollingLaneHistory, fs) == 0 &&
              offsetof(HertzRollingLaneHistory, kt_prev) == 24 && offsetof(HertzRollingLaneHistory, mk) == 32);
static_assert(sizeof(MepaLaneHistory) == 56 && offsetof(MepaLaneHistory, Dp) == 8 &&
              offsetof(MepaLaneHistory, branch) == 16 && offsetof(MepaLaneHistory, fs) == 24 &&
              offsetof(MepaLaneHistory, kt_prev) == 48);
static_assert(sizeof(MepaRollingLaneHistory) == 80 && offsetof(MepaRollingLaneHistory, Dp) == 8 &&
              offsetof(MepaRollingLaneHistory, branch) == 16 && offsetof(MepaRollingLaneHistory, fs) == 24 &&
              offsetof(MepaRollingLaneHistory, kt_prev) == 48 && offsetof(MepaRollingLaneHistory, mk) == 56);

/// One group of contacts of the linear law (after their geometry); kU: one material pair;
/// kRoll: its rolling resistance (kLaneNoRolling, kLaneEpsd, kLaneSds).
template <bool kU, int kRoll>
LANES_FN void linear_group(const LaneInput& in, const Group& G, const uint32_t g, LaneOut& out) {
  const void* const P = in.params;
  constexpr bool kRolls = kRoll != kLaneNoRolling;
  using LH = std::conditional_t<kRolls, LinearRollingLaneHistory, LinearLaneHistory>;
  auto* const H = static_cast<LH*>(in.hist);
  using LP = LinearLaneParams;
  const Par<kU, LP> par(P, G.p);
  // The records first, and their turns into the new tangent plane: they depend only on the
  // history and the normal, so the out-of-order window overlaps their divisions with the
  // laws' chains below. {fs}, or {fs, mk} read as {fs, mk.x} and {mk.y, mk.z}.
  L3 fs, mk;
  if constexpr (kRolls) {
    const Cols h0 = load_quads(H, G.k, 0);
    V mk_y, mk_z;
    load_pairs(H, G.k, 4, mk_y, mk_z);
    fs = L3{h0.v[0], h0.v[1], h0.v[2]};
    mk = L3{h0.v[3], mk_y, mk_z};
    rotate_into_plane4(mk, G.n);
  } else {
    fs = gather3(H, G.k, &LH::fs);
  }
  rotate_into_plane4(fs, G.n);
  // LinearNormal.
  const V kn = par(&LP::kn);
  const M alive = G.delta > 0.0;
  const V f_el = kn * G.delta;
  V gamma;
  const V fn = f_el + damping4(par(&LP::two_beta), par(&LP::limit), G.mstar, kn, G.vn, f_el, gamma);
  const V fc = max0(fn);  // NormalBase::coulomb_base
  const L3 ft = spring4(fs, G.vt, par(&LP::kt), splat(in.dt), par(&LP::damp_t) * gamma, par(&LP::mu), fc);
  // LinearNormal's contact radius, read only when asked for.
  const V a = in.want_a ? sqrtv(G.rstar * G.delta) : splat(0.0);
  // The records back (the force loop resets those of contacts that ended: LaneOut::alive).
  if constexpr (kRolls) {
    // (kn is a parameter here: EPSD's coefficient computed at the start measured 3-4 % slower)
    EpsdCoef ec{};
    if constexpr (kRoll == kLaneEpsd) ec = epsd_coef4(G, kn, par(&LP::mu_r), par(&LP::two_eta_r), par(&LP::damped));
    const L3 mr = rolling4<kRoll, LP>(G, mk, ec, fc, par, splat(in.dt));
    put(G, g, alive, fn, ft, &mr, a, out);
    store_records(G, H, At<Quads>{0, quads(fs.x, fs.y, fs.z, mk.x)}, At<Pairs>{4, pairs(mk.y, mk.z)});
  } else {
    put(G, g, alive, fn, ft, nullptr, a, out);
    // 24 bytes: {x, y} then z of each lane.
    const Pairs xy = pairs(fs.x, fs.y);
    double z[kW];
    store(z, fs.z);
    each_lane(G, [&](const uint32_t l) LANES_LAMBDA {
      double* const r = lanes4::rec(H, G.k[l]);
      _mm_storeu_pd(r, xy.p[l]);
      r[2] = z[l];
    });
  }
}

/// One group of contacts of Hertz-Mindlin (after their geometry); kU: one material pair;
/// kRoll: its rolling resistance (kLaneNoRolling, kLaneEpsd, kLaneSds).
template <bool kU, int kRoll>
LANES_FN void hertz_group(const LaneInput& in, const Group& G, const uint32_t g, LaneOut& out) {
  const void* const P = in.params;
  constexpr bool kRolls = kRoll != kLaneNoRolling;
  using LH = std::conditional_t<kRolls, HertzRollingLaneHistory, HertzLaneHistory>;
  auto* const H = static_cast<LH*>(in.hist);
  using LP = HertzLaneParams;
  const Par<kU, LP> par(P, G.p);
  const V dt = splat(in.dt);
  // The records first, read whole as they are written below ({fs, kt_prev} at 0 and, with
  // rolling, {kt_prev, mk} at 24), and turned into the new tangent plane (see linear_group).
  const Cols h0 = load_quads(H, G.k, 0);
  L3 fs{h0.v[0], h0.v[1], h0.v[2]};
  V kt_prev = h0.v[3];
  rotate_into_plane4(fs, G.n);
  L3 mk{};
  if constexpr (kRolls) {
    const Cols h1 = load_quads(H, G.k, 3);
    mk = L3{h1.v[1], h1.v[2], h1.v[3]};
    rotate_into_plane4(mk, G.n);
  }
  // HertzNormal (the lanes of ended contacts compute what no one reads).
  const M alive = G.delta > 0.0;
  const V a = sqrtv(G.rstar * G.delta);
  const V kn = par(&LP::two_Estar) * a;
  EpsdCoef ec{};
  if constexpr (kRoll == kLaneEpsd) ec = epsd_coef4(G, kn, par(&LP::mu_r), par(&LP::two_eta_r), par(&LP::damped));
  const V f_el = (2.0 / 3.0) * kn * G.delta;
  V gamma;
  const V fn = f_el + damping4(par(&LP::two_beta), par(&LP::limit), G.mstar, kn, G.vn, f_el, gamma);
  const V fc = max0(fn);
  // MindlinTangential: kt = 8 G* a; a spring whose stiffness fell is scaled by kt/kt_prev.
  const V kt = par(&LP::eight_Gstar) * a;
  const L3 ft = spring_prev4(fs, kt_prev, G.vt, kt, dt, par(&LP::damp_kt) * gamma, par(&LP::mu), fc);
  // The records back (the force loop resets those of contacts that ended).
  const Quads a0 = quads(fs.x, fs.y, fs.z, kt_prev);
  if constexpr (kRolls) {
    const L3 mr = rolling4<kRoll, LP>(G, mk, ec, fc, par, dt);
    put(G, g, alive, fn, ft, &mr, a, out);
    // {kt_prev, mk} at 24 (kt_prev written twice, the same value).
    store_records(G, H, At<Quads>{0, a0}, At<Quads>{3, quads(kt_prev, mk.x, mk.y, mk.z)});
  } else {
    put(G, g, alive, fn, ft, nullptr, a, out);
    store_records(G, H, At<Quads>{0, a0});
  }
}

/// One group of contacts of MEPA (after their geometry); kU: one material pair; kRoll: its
/// rolling resistance (kLaneNoRolling, kLaneEpsd, kLaneSds).
template <bool kU, int kRoll>
LANES_FN void mepa_group(const LaneInput& in, const Group& G, const uint32_t g, LaneOut& out) {
  const void* const P = in.params;
  constexpr bool kRolls = kRoll != kLaneNoRolling;
  using LH = std::conditional_t<kRolls, MepaRollingLaneHistory, MepaLaneHistory>;
  auto* const H = static_cast<LH*>(in.hist);
  using LP = MepaLaneParams;
  const Par<kU, LP> par(P, G.p);
  const V dt = splat(in.dt);
  // The springs' records first, {fs, kt_prev} at 24 and, with rolling, mk at 56, turned into
  // the new tangent plane (see linear_group): their divisions overlap the normal law's
  // square root. {Dmax, Dp} at 0 where the normal law reads it.
  L3 mk{};
  const Cols h1 = load_quads(H, G.k, 3);
  L3 fs{h1.v[0], h1.v[1], h1.v[2]};
  V kt_prev = h1.v[3];
  rotate_into_plane4(fs, G.n);
  if constexpr (kRolls) {
    mk = gather3(H, G.k, &LH::mk);
    rotate_into_plane4(mk, G.n);
  }
  V Dmax, Dp;
  load_pairs(H, G.k, 0, Dmax, Dp);
  // HystereticNormal::apply with fixed stiffnesses (lane_usable): D = delta^n with
  // delta^(n-1) = 1 (n = 1) or sqrt(delta) (n = 3/2); the branch of the larger of f1, f2,
  // bounded below by the adhesive -A.
  const M alive = G.delta > 0.0;
  const V d = G.delta;
  const V dn1 = sel(par(&LP::n_is_1), splat(1.0), sqrtv(d));
  const V D = d * dn1;
  const V A = par(&LP::kadh) * D;
  const V k1 = par(&LP::k1), k2 = par(&LP::k2);
  const V f1 = k1 * D, f2 = k2 * (D - Dp);
  const M load = f2 >= f1;
  const M adh = ~load & ~(f2 > -A);
  const V f = sel(load, f1, sel(adh, -A, f2));
  const V Dp_new = D * par(&LP::plastic);
  const V Dmax1 = sel(load, D, Dmax), Dp1 = sel(load, Dp_new, Dp);
  const V f0 = par(&LP::f0);
  const V f_el = f0 + f;
  const V f_adh = A - f0;
  const V kn = par(&LP::n_k2) * dn1;
  EpsdCoef ec{};
  if constexpr (kRoll == kLaneEpsd) ec = epsd_coef4(G, kn, par(&LP::mu_r), par(&LP::two_eta_r), par(&LP::damped));
  const V k_load = k1 * dn1;
  // ViscousDamping.
  const V gamma = par(&LP::gamma_n);
  const V fn = f_el + apply_limit4(par(&LP::limit), gamma, G.vn, f_el);
  const V fc = max0(sel(par(&LP::offset), f_el + f_adh, f_el));  // coulomb_base
  // HystTangential: a fixed kt, or kt_ratio k1 delta^(n-1) kt_mult.
  const V kt = sel(par(&LP::kt_const), par(&LP::kt_c), par(&LP::kt_ratio) * k_load * par(&LP::kt_mult));
  // The rolling before the tangential spring: the two chains are independent, and the rolling
  // one then overlaps the spring's instead of ending the group (EPSD: 1-2 % faster,
  // BM_ForceAlternate).
  L3 mr{};
  if constexpr (kRolls) mr = rolling4<kRoll, LP>(G, mk, ec, fc, par, dt);
  const L3 ft = spring_prev4(fs, kt_prev, G.vt, kt, dt, par(&LP::gamma_t), par(&LP::mu), fc);
  const V a = in.want_a ? sqrtv(G.rstar * d) : splat(0.0);
  // The records back (the force loop resets those of contacts that ended). The branch is an
  // int32 followed by 4 bytes of padding: its lane holds it zero-extended, so the padding
  // stays zero as the scalar law leaves it. Without rolling: {Dmax, Dp, branch, fs.x} at 0
  // and {fs, kt_prev} at 24 (fs.x written twice).
  const M br = load ? msplat(1) : (adh ? msplat(3) : msplat(2));
  if constexpr (kRolls) {
    // {Dmax, Dp, branch, fs.x} at 0 and {fs.y, fs.z} at 32 before the forces' stores,
    // {kt_prev, mk} at 48 after them.
    store_records(G, H, At<Quads>{0, quads(Dmax1, Dp1, V(br), fs.x)}, At<Pairs>{4, pairs(fs.y, fs.z)});
    put(G, g, alive, fn, ft, &mr, a, out);
    store_records(G, H, At<Quads>{6, quads(kt_prev, mk.x, mk.y, mk.z)});
  } else {
    store_records(G, H, At<Quads>{0, quads(Dmax1, Dp1, V(br), fs.x)}, At<Quads>{3, quads(fs.x, fs.y, fs.z, kt_prev)});
    put(G, g, alive, fn, ft, nullptr, a, out);
  }
}

/// An entry point of lanes.hpp's list (COHDEM_LANE_ENTRIES), outside the includer's
/// anonymous namespace: the law's group, uniform and mixed, over a chunk.
#define COHDEM_LANE_DEFINE(law, suffix, rolling, width)                                                    \
  __attribute__((target(LANES_TARGET))) void law##suffix##_lanes_##width(                                  \
      const LaneInput& in, const ScreenHits& hits, const uint32_t h0, const uint32_t cnt, LaneOut& out) {   \
    drive<law##_group<true, rolling>, law##_group<false, rolling>>(in, hits, h0, cnt, out);                \
  }

#undef LANES_LAMBDA
