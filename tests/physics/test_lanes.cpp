// The contacts evaluated four at a time in AVX2 lanes (src/sim/lanes.hpp: the linear law,
// Hertz-Mindlin and MEPA, each without and with EPSD rolling) must give the scalar laws'
// results bit for bit: forces, torques, histories and which contacts live, contact by
// contact, and so whole runs. Checked on a bed that reaches every branch the scalar code
// has: two species with their own parameters per material pair (linear: kt given or from
// kt_ratio; limit_damping on and off, tangential damping; Hertz-Mindlin: two E* and G*;
// MEPA: n = 1 and 3/2, the Coulomb offset, three kt forms; rolling damping on and off),
// frozen partners, periodic images, histories turned out of the tangent plane by small and
// by large angles, zero histories, sliding and sticking springs (tangential and rolling),
// tangential stiffnesses that fell or rose since the last step, MEPA's three branches, and
// live entries whose spheres have parted (history reset).
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <cstddef>
#include <cstring>
#include <string>

#include "fixture.hpp"
#include "sim/force_kernel.hpp"
#include "sim/lanes.hpp"
#include "sim/screen.hpp"

using namespace cohdem;
using namespace cohdem::testing;

namespace {

constexpr double kL = 0.03;  // periodic cell in x and y, m

enum class Law { Linear, LinearEpsd, LinearSds, Hertz, HertzEpsd, HertzSds, Mepa, MepaEpsd, MepaSds };

bool is_sds(const Law law) { return law == Law::LinearSds || law == Law::HertzSds || law == Law::MepaSds; }
bool rolls(const Law law) {
  return law == Law::LinearEpsd || law == Law::HertzEpsd || law == Law::MepaEpsd || is_sds(law);
}
bool is_linear(const Law law) { return law == Law::Linear || law == Law::LinearEpsd || law == Law::LinearSds; }
bool is_mepa(const Law law) { return law == Law::Mepa || law == Law::MepaEpsd || law == Law::MepaSds; }
const char* name_of(const Law law) {
  switch (law) {
    case Law::Linear: return "linear";
    case Law::LinearEpsd: return "linear + EPSD";
    case Law::LinearSds: return "linear + SDS";
    case Law::Hertz: return "Hertz-Mindlin";
    case Law::HertzEpsd: return "Hertz-Mindlin + EPSD";
    case Law::HertzSds: return "Hertz-Mindlin + SDS";
    case Law::Mepa: return "MEPA";
    case Law::MepaEpsd: return "MEPA + EPSD";
    case Law::MepaSds: return "MEPA + SDS";
  }
  return "";
}

// A parameter set with the keys of the law's rolling model alone: mu_r for both, eta_r for
// EPSD, k_r and gamma_r for SDS; none without rolling resistance.
ParamSet law_params(const Law law, std::initializer_list<std::pair<const char*, double>> kv) {
  ParamSet p;
  for (auto& [k, v] : kv) {
    const std::string key = k;
    const bool epsd_key = key == "eta_r", sds_key = key == "k_r" || key == "gamma_r";
    if (key == "mu_r" || epsd_key || sds_key) {
      if (!rolls(law) || (epsd_key && is_sds(law)) || (sds_key && !is_sds(law))) continue;
    }
    p.set(k, v);
  }
  return p;
}

// Where the lanes' history records (lanes.hpp) keep what the test sets and reads, in bytes:
// the tangential spring, its last stiffness (none: npos), EPSD's or SDS's spring (none: npos); MEPA's
// Dmax, Dp, branch at 0, 8, 16.
struct Layout {
  size_t size, fs, kt_prev, mk;
};
constexpr size_t kNone = ~size_t(0);
Layout layout_of(const Law law) {
  switch (law) {
    case Law::Linear: return {sizeof(LinearLaneHistory), 0, kNone, kNone};
    case Law::LinearEpsd: return {sizeof(LinearRollingLaneHistory), 0, kNone, offsetof(LinearRollingLaneHistory, mk)};
    case Law::LinearSds: return {sizeof(LinearRollingLaneHistory), 0, kNone, offsetof(LinearRollingLaneHistory, mk)};
    case Law::Hertz: return {sizeof(HertzLaneHistory), 0, offsetof(HertzLaneHistory, kt_prev), kNone};
    case Law::HertzEpsd:
      return {sizeof(HertzRollingLaneHistory), 0, offsetof(HertzRollingLaneHistory, kt_prev), offsetof(HertzRollingLaneHistory, mk)};
    case Law::HertzSds:
      return {sizeof(HertzRollingLaneHistory), 0, offsetof(HertzRollingLaneHistory, kt_prev), offsetof(HertzRollingLaneHistory, mk)};
    case Law::Mepa: return {sizeof(MepaLaneHistory), offsetof(MepaLaneHistory, fs), offsetof(MepaLaneHistory, kt_prev), kNone};
    case Law::MepaEpsd:
      return {sizeof(MepaRollingLaneHistory), offsetof(MepaRollingLaneHistory, fs), offsetof(MepaRollingLaneHistory, kt_prev),
              offsetof(MepaRollingLaneHistory, mk)};
    case Law::MepaSds:
      return {sizeof(MepaRollingLaneHistory), offsetof(MepaRollingLaneHistory, fs), offsetof(MepaRollingLaneHistory, kt_prev),
              offsetof(MepaRollingLaneHistory, mk)};
  }
  return {};
}

// 500 spheres of two species dropped onto a floor in a periodic cell (gravity 200 m/s^2, to
// settle in a few thousand steps), one in ten frozen; material pairs with parameters of
// their own.
std::unique_ptr<System> make_bed(Law law, int threads) {
  std::unique_ptr<System> s;
  const char* const rolling = is_sds(law) ? "sds" : rolls(law) ? "epsd" : "none";
  if (is_linear(law)) {
    s = make_system({{"a", 2500, 0, 0}, {"b", 1500, 0, 0}}, "linear", rolling,
                    law_params(law, {{"kn", 2e3}, {"e", 0.5}, {"mu", 0.5}, {"mu_r", 0.1}, {"k_r", 600}}), 1e-5,
                    {0, 0, -200.0}, 3e-4);
    // a-a: the defaults (kt = 2/7 kn), no rolling damping; a-b: kt given, limit_damping,
    // tangential and rolling damping; b-b: another restitution and friction, tangential and
    // rolling damping. SDS: springs about the tangential ones' stiffness, dashpots a fifth to
    // half of critical for a particle's mass (about 1e-5 kg).
    const ParamSet aa = law_params(law, {{"kn", 2e3}, {"e", 0.5}, {"mu", 0.5}, {"mu_r", 0.1}, {"k_r", 600}});
    const ParamSet ab = law_params(law, {{"kn", 3e3}, {"e", 0.2}, {"mu", 0.3}, {"kt", 1.1e3}, {"limit_damping", 1},
                                         {"damp_t", 0.5}, {"mu_r", 0.05}, {"eta_r", 0.3}, {"k_r", 300},
                                         {"gamma_r", 0.01}});
    const ParamSet bb = law_params(law, {{"kn", 1e3}, {"e", 0.9}, {"mu", 0.8}, {"damp_t", 1.0}, {"mu_r", 0.2},
                                         {"eta_r", 1.0}, {"k_r", 900}, {"gamma_r", 0.03}});
    s->set_model(make_contact_model("linear", rolling), {aa, ab, ab, bb});
  } else if (is_mepa(law)) {
    s = make_system({{"a", 2500, 0, 0}, {"b", 1500, 0, 0}}, "mepa", rolling,
                    law_params(law, {{"k1", 1e5}, {"k2", 5e5}, {"mu", 0.5}, {"mu_r", 0.1}, {"k_r", 2e4}}), 5e-6,
                    {0, 0, -200.0}, 3e-4);
    // a-a: n = 3/2, adhesion, the tangent kt (kt_form 0), no rolling damping; a-b: n = 1,
    // the cohesion-offset Coulomb base, limit_damping, the secant kt (kt_form 1), rolling
    // damping; b-b: n = 3/2, a given kt, tangential and rolling damping. SDS: springs and
    // dashpots of the tangential ones' order.
    const ParamSet aa = law_params(
        law, {{"k1", 1e5}, {"k2", 5e5}, {"kadh", 2e4}, {"gamma_n", 0.02}, {"mu", 0.5}, {"mu_r", 0.1}, {"k_r", 2e4}});
    const ParamSet ab =
        law_params(law, {{"k1", 2e3}, {"k2", 6e3}, {"kadh", 500}, {"n", 1}, {"coulomb_offset", 1}, {"gamma_n", 0.01},
                         {"limit_damping", 1}, {"kt_form", 1}, {"mu", 0.3}, {"mu_r", 0.05}, {"eta_r", 0.3},
                         {"k_r", 500}, {"gamma_r", 0.01}});
    const ParamSet bb =
        law_params(law, {{"k1", 5e4}, {"k2", 4e5}, {"kadh", 1e4}, {"gamma_n", 0.03}, {"kt", 800}, {"damp_t", 0.5},
                         {"mu", 0.8}, {"mu_r", 0.2}, {"eta_r", 1.0}, {"k_r", 800}, {"gamma_r", 0.02}});
    s->set_model(make_contact_model("mepa", rolling), {aa, ab, ab, bb});
  } else {
    s = make_system({{"a", 2500, 1e7, 0.25}, {"b", 1500, 5e6, 0.35}}, "hertz_mindlin", rolling,
                    law_params(law, {{"e", 0.5}, {"mu", 0.5}, {"mu_r", 0.1}, {"k_r", 300}}), 5e-6, {0, 0, -200.0}, 3e-4);
    // a-a: no rolling damping; a-b: limit_damping, rolling damping; b-b: others. SDS: its
    // spring about the tangential one's stiffness (some hundreds of N/m), a dashpot a fifth
    // to half of critical for a particle's mass (about 1e-5 kg).
    const ParamSet aa = law_params(law, {{"e", 0.5}, {"mu", 0.5}, {"mu_r", 0.1}, {"k_r", 300}});
    const ParamSet ab = law_params(law, {{"e", 0.2}, {"mu", 0.3}, {"mu_r", 0.05}, {"eta_r", 0.3}, {"k_r", 100},
                                         {"gamma_r", 0.01}, {"limit_damping", 1}, {"damp_t", 0.5}});
    const ParamSet bb =
        law_params(law, {{"e", 0.9}, {"mu", 0.8}, {"mu_r", 0.2}, {"eta_r", 1.0}, {"k_r", 500}, {"gamma_r", 0.03}});
    s->set_model(make_contact_model("hertz_mindlin", rolling), {aa, ab, ab, bb});
  }
  s->cfg.threads = threads;
  s->cfg.parallel_min = 0;
  s->cfg.domain.lo = {0, 0, 0};
  s->cfg.domain.hi = {kL, kL, 0};
  s->cfg.domain.periodic = {true, true, false};
  s->rng = Rng(11);
  s->walls.push_back(plane({0, 0, 0}, {0, 0, 1}, 0));
  for (int sp = 0; sp < 2; ++sp) {
    InsertSpec spec;
    spec.region.lo = {0, 0, 0};
    spec.region.hi = {kL, kL, 0.02};
    spec.size.kind = SizeDistribution::Kind::Uniform;
    spec.size.rmin = 1.0e-3;
    spec.size.rmax = 1.5e-3;
    spec.count = 250;
    spec.species = sp;
    EXPECT_EQ(s->insert(spec), 250u);
  }
  Rng rng(5);
  auto& P = s->particles;
  for (size_t i = 0; i < P.size(); ++i) {
    P.v[i] = Vec3{rng.normal(), rng.normal(), rng.normal()} * 0.3;
    P.omega[i] = Vec3{rng.normal(), rng.normal(), rng.normal()} * 300.0;
    if (i % 10 == 3) P.flag[i] = kFrozen;
  }
  s->prepare();
  return s;
}

struct Result {
  std::vector<Vec3> f, t, x, v, w;
  std::vector<std::byte> hist;
  std::vector<uint8_t> live;
};

Result state_of(const System& s) {
  return {s.particles.force, s.particles.torque, s.particles.x, s.particles.v, s.particles.omega, s.nl.hist.data,
          s.nl.hist.live};
}

// One call of the force loop (no kicks), scalar or in lanes.
Result force_call(System& s, bool lanes) {
  set_screen_avx2(lanes);
  const size_t n = s.particles.size();
  std::vector<PairResult> pair(s.nl.pair_count()), rev(n);
  std::vector<Vec3> fw(s.nl.wall_entry_count()), tw(fw.size()), cw(fw.size());
  ForceContext c{s.particles, s.nl, s.walls, s.cfg.dt, s.time, pair, rev, fw, tw, cw, s.cfg.gravity};
  c.keep_pair = false;
  s.model->compute(c);
  return state_of(s);
}

size_t differing(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  size_t d = 0;
  for (size_t i = 0; i < a.size(); ++i) d += std::memcmp(&a[i], &b[i], sizeof(Vec3)) != 0;
  return d;
}


// A random history vector for an entry of normal n: a random direction (most lie out of the
// tangent plane by large angles: the exact rescaling), or three in ten nearly in the plane (a
// turn of ~1e-3 rad: the series), of length 10^lo .. 10^hi; one in eight zero.
Vec3 random_history(Rng& rng, const Vec3& n, double lo, double hi, size_t& small_turn) {
  Vec3 h{rng.normal(), rng.normal(), rng.normal()};
  if (rng.uniform(0, 1) < 0.3) {
    h -= n * dot(n, h);
    h += n * (1e-3 * std::sqrt(norm2(h)));
    ++small_turn;
  }
  h *= std::pow(10.0, rng.uniform(lo, hi)) / std::sqrt(norm2(h));
  return rng.uniform(0, 1) < 0.125 ? Vec3{} : h;
}

// Whether s's model is LawT with every material pair on the lanes (else the comparisons
// below would compare the scalar law with itself).
template <class LawT>
bool on_lanes(const System& s) {
  const auto* m = dynamic_cast<const ContactModelImpl<LawT>*>(s.model.get());
  if (m == nullptr) return false;
  for (int i = 0; i < m->n(); ++i)
    for (int j = 0; j < m->n(); ++j)
      if (!LaneLaw<LawT>::usable(m->p(i, j))) return false;
  return LaneLaw<LawT>::kHave;
}

bool on_lanes_of(const Law law, const System& s) {
  switch (law) {
    case Law::Linear: return on_lanes<LinearLaw>(s);
    case Law::LinearEpsd: return on_lanes<LinearEpsdLaw>(s);
    case Law::LinearSds: return on_lanes<LinearSdsLaw>(s);
    case Law::Hertz: return on_lanes<HertzLaw>(s);
    case Law::HertzEpsd: return on_lanes<HertzEpsdLaw>(s);
    case Law::HertzSds: return on_lanes<HertzSdsLaw>(s);
    case Law::Mepa: return on_lanes<MepaLaw>(s);
    case Law::MepaEpsd: return on_lanes<MepaEpsdLaw>(s);
    case Law::MepaSds: return on_lanes<MepaSdsLaw>(s);
  }
  return false;
}

// One force evaluation, scalar and in lanes, from the same state with histories set by hand
// on every entry that touches and on some that do not (marked live: the law must end them).
void contact_by_contact(Law law, bool wide) {
  const bool was = screen_avx2_enabled(), was_wide = screen_avx512_enabled();
  set_screen_avx512(wide);
  auto s = make_bed(law, 1);
  ASSERT_TRUE(on_lanes_of(law, *s));
  s->run(3000);  // settling: contacts with histories, frozen partners, images
  auto& nl = s->nl;
  const size_t stride = s->model->state_size();
  const Layout lay = layout_of(law);
  ASSERT_EQ(stride, lay.size);
  const bool rolling = lay.mk != kNone, stiff = lay.kt_prev != kNone;
  ASSERT_GE(nl.hist.data.size(), nl.jdx.size() * stride);
  const auto& P = s->particles;
  auto rec = [&](std::vector<std::byte>& d, size_t k) { return d.data() + k * stride; };
  // Tangential springs of 1e-9 N to 1 N (sticking to sliding); Hertz-Mindlin: a last stiffness
  // of zero (a new contact) or 10 to 10^4 N/m (below and above the current 8 G* a, some
  // hundreds of N/m here), rolling springs of 1e-12 to 1e-5 N m (limit mu_r R* F_c ~ 1e-8;
  // SDS: forces, as the tangential ones).
  Rng rng(17);
  size_t touching = 0, parted = 0, small_turn = 0, frozen_partner = 0;
  for (size_t i = 0; i < P.size(); ++i) {
    for (uint32_t k = nl.start[i]; k < nl.start[i + 1]; ++k) {
      const uint32_t j = nl.jdx[k];
      const Vec3 d = P.x[i] - (P.x[j] + nl.shift[nl.image[k]]);
      const double dist = std::sqrt(norm2(d));
      const bool touch = dist < P.radius[i] + P.radius[j];
      if (!touch && rng.uniform(0, 1) > 0.15) continue;
      const Vec3 n = d * (1.0 / dist);
      const Vec3 fs = random_history(rng, n, -9, 0, small_turn);
      std::memcpy(rec(nl.hist.data, k) + lay.fs, &fs, sizeof fs);
      if (stiff) {
        const double kt_prev = rng.uniform(0, 1) < 0.3 ? 0.0 : std::pow(10.0, rng.uniform(1, 4));
        std::memcpy(rec(nl.hist.data, k) + lay.kt_prev, &kt_prev, sizeof kt_prev);
      }
      if (rolling) {
        // EPSD's moment; SDS's spring is a force, in the tangential spring's range.
        const Vec3 mk = is_sds(law) ? random_history(rng, n, -9, 0, small_turn)
                                    : random_history(rng, n, -12, -5, small_turn);
        std::memcpy(rec(nl.hist.data, k) + lay.mk, &mk, sizeof mk);
      }
      if (is_mepa(law) && touch) {
        // A plastic overlap of 0 to 1.5 delta^n (loading, un/reloading and the adhesive
        // branch all reached), its largest overlap at or above it.
        const double D = std::pow(P.radius[i] + P.radius[j] - dist, P.species[i] + P.species[j] == 1 ? 1.0 : 1.5);
        const double Dp = rng.uniform(0, 1.5) * D, Dmax = Dp * rng.uniform(1, 3);
        std::memcpy(rec(nl.hist.data, k), &Dmax, sizeof Dmax);
        std::memcpy(rec(nl.hist.data, k) + 8, &Dp, sizeof Dp);
      }
      nl.hist.live[k] = 1;
      touching += touch;
      parted += !touch;
      frozen_partner += touch && (P.flag[i] == kFrozen || P.flag[j] == kFrozen);
    }
  }
  const std::vector<std::byte> hist0 = nl.hist.data;
  const std::vector<uint8_t> live0 = nl.hist.live;
  const std::vector<std::byte> whist0 = nl.whist.data;  // the floor's contacts (scalar in both)
  const std::vector<uint8_t> wlive0 = nl.whist.live;
  const std::vector<Vec3> f0 = P.force, t0 = P.torque;
  Result a = force_call(*s, false);
  nl.hist.data = hist0;
  nl.hist.live = live0;
  nl.whist.data = whist0;
  nl.whist.live = wlive0;
  s->particles.force = f0;
  s->particles.torque = t0;
  const Result b = force_call(*s, true);
  set_screen_avx2(was);
  set_screen_avx512(was_wide);
  // Coverage: the bed must reach what it is meant to. A spring cut to its limit is at least
  // halved here (sliding); a stiffness that fell scales the spring by kt/kt_prev.
  std::vector<std::byte> h0 = hist0;
  size_t slid = 0, rolled = 0, softened = 0, branch[4] = {0, 0, 0, 0};
  for (size_t k = 0; k < nl.jdx.size(); ++k) {
    if (!a.live[k]) continue;
    Vec3 f0k, f1k;
    std::memcpy(&f0k, rec(h0, k) + lay.fs, sizeof f0k);
    std::memcpy(&f1k, rec(a.hist, k) + lay.fs, sizeof f1k);
    slid += norm2(f1k) < 0.25 * norm2(f0k);
    if (rolling) {
      Vec3 m0k, m1k;
      std::memcpy(&m0k, rec(h0, k) + lay.mk, sizeof m0k);
      std::memcpy(&m1k, rec(a.hist, k) + lay.mk, sizeof m1k);
      rolled += norm2(m1k) < 0.25 * norm2(m0k);
    }
    if (stiff) {
      double kp0, kp1;
      std::memcpy(&kp0, rec(h0, k) + lay.kt_prev, sizeof kp0);
      std::memcpy(&kp1, rec(a.hist, k) + lay.kt_prev, sizeof kp1);
      softened += kp0 > kp1 && kp1 > 0;
    }
    if (is_mepa(law)) {
      int32_t br;
      std::memcpy(&br, rec(a.hist, k) + 16, sizeof br);
      ++branch[br & 3];
    }
  }
  std::printf("[info] lanes: %zu touching, %zu parted, %zu small turns, %zu frozen partners, %zu sliding, "
              "%zu rolling springs cut, %zu stiffnesses fallen, MEPA branches %zu/%zu/%zu\n",
              touching, parted, small_turn, frozen_partner, slid, rolled, softened, branch[1], branch[2], branch[3]);
  EXPECT_GT(touching, 500u);
  EXPECT_GT(parted, 20u);
  EXPECT_GT(small_turn, 100u);
  EXPECT_GT(frozen_partner, 20u);
  EXPECT_GT(slid, 100u);
  if (rolling) EXPECT_GT(rolled, 100u);
  if (stiff) EXPECT_GT(softened, 100u);
  if (is_mepa(law))
    for (int b = 1; b <= 3; ++b) EXPECT_GT(branch[b], 50u) << "MEPA branch " << b;
  // Bit for bit (memcmp: the sign of a zero counts).
  EXPECT_EQ(differing(a.f, b.f), 0u);
  EXPECT_EQ(differing(a.t, b.t), 0u);
  EXPECT_TRUE(a.live == b.live);
  EXPECT_TRUE(a.hist == b.hist);
  const std::string what = std::string("lanes vs scalar, ") + name_of(law) + ": particles with any differing force or torque bit";
  report(what.c_str(), double(differing(a.f, b.f) + differing(a.t, b.t)), 0.0, 0, "==");
}

// Whole runs (800 steps of the bed settling: thousands of contact-steps), scalar and in
// lanes, on one and two threads.
void whole_runs(Law law, bool wide) {
  const bool was = screen_avx2_enabled(), was_wide = screen_avx512_enabled();
  set_screen_avx512(wide);
  Result r[2][2];
  size_t contacts = 0;
  for (int lanes = 0; lanes < 2; ++lanes)
    for (int nt = 1; nt <= 2; ++nt) {
      set_screen_avx2(lanes == 1);
      auto s = make_bed(law, nt);
      size_t c = 0;
      s->run(800, [&](const System& sys) { c += sys.pair_contact_count(); });
      r[lanes][nt - 1] = state_of(*s);
      contacts = c;
    }
  set_screen_avx2(was);
  set_screen_avx512(was_wide);
  omp_set_num_threads(1);
  std::printf("[info] lanes, whole runs: %zu pair contact-steps\n", contacts);
  EXPECT_GT(contacts, 20000u);
  for (int t = 0; t < 2; ++t) {
    EXPECT_EQ(differing(r[0][t].x, r[1][t].x), 0u) << t + 1 << " threads";
    EXPECT_EQ(differing(r[0][t].v, r[1][t].v), 0u) << t + 1 << " threads";
    EXPECT_EQ(differing(r[0][t].w, r[1][t].w), 0u) << t + 1 << " threads";
  }
  EXPECT_EQ(differing(r[1][0].x, r[1][1].x), 0u) << "lanes: 1 vs 2 threads";
}

}  // namespace

// Each law in four AVX2 lanes and, where the CPU has AVX-512, in eight (the screening then
// eight entries at a time as well: both are chosen by screen_avx512_enabled).
#define COHDEM_LANES_TESTS(Name, law)                                                                \
  TEST(Lanes, Name##ContactByContactAsTheScalarLaw) {                                               \
    if (!avx2_available()) GTEST_SKIP() << "no AVX2 on this CPU or build: the scalar law runs alone";   \
    contact_by_contact(law, false);                                                                 \
  }                                                                                                 \
  TEST(Lanes, Name##RunsAsTheScalarLawOnOneAndTwoThreads) {                                         \
    if (!avx2_available()) GTEST_SKIP() << "no AVX2 on this CPU or build: the scalar law runs alone";   \
    whole_runs(law, false);                                                                         \
  }                                                                                                 \
  TEST(Lanes, Name##InEightLanesContactByContactAsTheScalarLaw) {                                   \
    if (!avx512_available()) GTEST_SKIP() << "no AVX-512 on this CPU or build: four lanes run alone"; \
    contact_by_contact(law, true);                                                                  \
  }                                                                                                 \
  TEST(Lanes, Name##InEightLanesRunsAsTheScalarLawOnOneAndTwoThreads) {                             \
    if (!avx512_available()) GTEST_SKIP() << "no AVX-512 on this CPU or build: four lanes run alone"; \
    whole_runs(law, true);                                                                          \
  }
COHDEM_LANES_TESTS(LinearLaw, Law::Linear)
COHDEM_LANES_TESTS(LinearEpsd, Law::LinearEpsd)
COHDEM_LANES_TESTS(LinearSds, Law::LinearSds)
COHDEM_LANES_TESTS(HertzMindlin, Law::Hertz)
COHDEM_LANES_TESTS(HertzMindlinEpsd, Law::HertzEpsd)
COHDEM_LANES_TESTS(HertzMindlinSds, Law::HertzSds)
COHDEM_LANES_TESTS(Mepa, Law::Mepa)
COHDEM_LANES_TESTS(MepaEpsd, Law::MepaEpsd)
COHDEM_LANES_TESTS(MepaSds, Law::MepaSds)
#undef COHDEM_LANES_TESTS

TEST(Lanes, MepaSettingsOutsideTheLanesRunTheScalarLaw) {
  // dp_shift and exponents other than 1 and 3/2 are the scalar law's alone (lane_usable).
  for (const auto& extra : {std::pair{"dp_shift", 1.0}, std::pair{"n", 2.0}, std::pair{"n", 1.25}}) {
    auto s = make_system({{"a", 2500, 0, 0}}, "mepa", "epsd", params({{"k1", 1e5}, {"k2", 5e5}, {"mu", 0.5}, {"mu_r", 0.1}}),
                         5e-6);
    ParamSet p = params({{"k1", 1e5}, {"k2", 5e5}, {"mu", 0.5}, {"mu_r", 0.1}});
    p.set(extra.first, extra.second);
    s->set_model(make_contact_model("mepa", "epsd"), {p});
    EXPECT_FALSE(on_lanes<MepaEpsdLaw>(*s)) << extra.first << " = " << extra.second;
  }
  auto s = make_system({{"a", 2500, 0, 0}}, "mepa", "epsd", params({{"k1", 1e5}, {"k2", 5e5}, {"mu", 0.5}, {"mu_r", 0.1}}),
                       5e-6);
  EXPECT_TRUE(on_lanes<MepaEpsdLaw>(*s));
}

// The force loop asks for the touching entries' records ahead only from kPrefetchBytes of
// them (force_loop_prefetches); the bed here is far below that, so the rule alone would test
// one side. Forced on and off, on the scalar law and in lanes, on one and two threads: a
// prefetch changes no value, and neither may the loops it sits in.
TEST(Lanes, PrefetchOnAndOffRunTheSameBits) {
  const bool was = screen_avx2_enabled();
  Result r[2][2][2];  // [lanes][prefetch][threads - 1]
  for (int lanes = 0; lanes < 2; ++lanes) {
    if (lanes == 1 && !avx2_available()) continue;
    for (int pf = 0; pf < 2; ++pf)
      for (int nt = 1; nt <= 2; ++nt) {
        set_screen_avx2(lanes == 1);
        set_force_loop_prefetch(pf);
        auto s = make_bed(Law::MepaEpsd, nt);
        s->run(400);
        r[lanes][pf][nt - 1] = state_of(*s);
      }
  }
  set_force_loop_prefetch(-1);
  set_screen_avx2(was);
  omp_set_num_threads(1);
  for (int lanes = 0; lanes < (avx2_available() ? 2 : 1); ++lanes)
    for (int t = 0; t < 2; ++t) {
      EXPECT_EQ(differing(r[lanes][0][t].x, r[lanes][1][t].x), 0u) << "lanes " << lanes << ", " << t + 1 << " threads";
      EXPECT_EQ(differing(r[lanes][0][t].v, r[lanes][1][t].v), 0u) << "lanes " << lanes << ", " << t + 1 << " threads";
      EXPECT_EQ(differing(r[lanes][0][t].w, r[lanes][1][t].w), 0u) << "lanes " << lanes << ", " << t + 1 << " threads";
    }
  // The rule's threshold: records of a 643-particle ring shear bed (about 0.2 MB) stay below
  // it, those of the 32,000-sphere chute (5.7 MB with the linear law's 24-byte history) do not.
  EXPECT_FALSE(force_loop_prefetches(1700, 643, 80));
  EXPECT_TRUE(force_loop_prefetches(110972, 32000, 24));
}
