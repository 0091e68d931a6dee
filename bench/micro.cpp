// Micro-benchmarks (Google Benchmark): the bulk pair-force loop per contact model, the
// neighbor build and the contact-history merge, on a dense periodic packing.
//
//   ./build/cohdem_bench                       # all
//   ./build/cohdem_bench --benchmark_filter=Force
//
// BM_ForceAlternate/A/B alternates two laws' force loops in one process and reports the
// ratio of their CPU times paired block by block (issue 6's MEPA-over-linear bound; a law
// against itself is the control):
//   ./build/cohdem_bench --benchmark_filter=BM_ForceAlternate/ --benchmark_repetitions=3
//
// Every benchmark reports items_per_second = particle-steps per second of the part it times
// (particles handled per second), so the numbers add up like costs per particle-step.
//
// The packing: N spheres (d = 1, density 1) on a simple cubic lattice of spacing 0.99 d with
// a random jitter of 0.004 d, periodic in x, y and z: every particle has six touching
// neighbours (three list entries per particle in the half list, all of them contacts) and
// random velocities and spins, so tangential and rolling histories are loaded.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <cstdlib>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/error.hpp"
#include "core/rng.hpp"
#include "io/case_file.hpp"
#include "models/registry.hpp"
#include "sim/force_context.hpp"
#include "sim/screen.hpp"
#include "sim/system.hpp"

using namespace cohdem;

namespace {

/// Parameters per preset, in the LJ-like units of the chute (kn = 2e5, E = 5e7).
ParamSet params_for(const std::string& model, const std::string& rolling, const double eta_r = 0.3) {
  ParamSet p;
  if (model == "linear") { p.set("kn", 2e5); p.set("e", 0.9); p.set("mu", 0.5); }
  else if (model == "hertz_mindlin") { p.set("e", 0.9); p.set("mu", 0.5); }
  else if (model == "mepa") {  // n = 3/2, about the linear force at delta = 0.01 d
    p.set("k1", 2e6); p.set("k2", 1e7); p.set("kadh", 1e5); p.set("n", 1.5); p.set("gamma_n", 13.0); p.set("mu", 0.5);
  } else if (model == "walton") {  // K_R = 2 pi Y 2R* ~ 2e5 N/m
    p.set("Y", 6.4e4); p.set("Fc0", 1.0); p.set("beta_n", 0.03); p.set("mu", 0.5);
  } else if (model == "luding") {
    p.set("k1", 2e5); p.set("k2", 1e6); p.set("kc", 1e4); p.set("gamma_n", 13.0); p.set("mu", 0.5);
  } else {
    // A preset this file does not know yet (MEPA, Walton, ...): fill every required key with
    // a plausible value by name; presets that need more are skipped (see SkipWithError).
    auto m = make_contact_model(model, rolling);
    for (const auto& s : m->specs()) {
      if (!s.required) continue;
      const std::string k = s.name;
      double v = 0.5;
      if (k == "kn" || k == "k1" || k == "kp") v = 2e5;
      else if (k == "e") v = 0.9;
      else if (k == "n") v = 1.5;
      p.set(k, std::max(v, s.min_open ? s.min * 1.01 + 1e-9 : s.min));
    }
  }
  if (rolling != "none") p.set("mu_r", 0.1);
  if (rolling == "epsd") p.set("eta_r", eta_r);
  if (rolling == "sds") {  // the chute's LAMMPS port (bench/chute_hmr.toml)
    p.set("k_r", 5e4);
    p.set("gamma_r", 25.0);
  }
  return p;
}

/// Dense periodic lattice of n^3 spheres.
std::unique_ptr<System> lattice(int n, const std::string& model, const std::string& rolling, double eta_r = 0.3,
                                uint64_t seed = 7) {
  auto s = std::make_unique<System>();
  s->materials = {{"grain", 1.0, 5e7, 0.3}};
  s->cfg.dt = 1e-4;
  s->cfg.gravity = {0, 0, 0};
  s->cfg.skin = 0.1;
  s->cfg.threads = 1;
  const double a = 0.99, L = a * n;
  s->cfg.domain.lo = {0, 0, 0};
  s->cfg.domain.hi = {L, L, L};
  s->cfg.domain.periodic = {true, true, true};
  s->set_model(make_contact_model(model, rolling), {params_for(model, rolling, eta_r)});
  Rng rng(seed);
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        auto j = [&] { return rng.uniform(-0.002, 0.002); };
        const Vec3 pos{(x + 0.5) * a + j(), (y + 0.5) * a + j(), (z + 0.5) * a + j()};
        const Vec3 v{rng.uniform(-0.1, 0.1), rng.uniform(-0.1, 0.1), rng.uniform(-0.1, 0.1)};
        const Vec3 w{rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)};
        s->add_particle(0, 0.5, pos, v, w);
      }
  return s;
}

struct ModelCase {
  const char* model;
  const char* rolling;
  double eta_r = 0.3;  ///< EPSD's viscous damping ratio (with rolling resistance)
};

/// "model" or "model+rolling", as the benchmarks are named.
std::string tag_of(const ModelCase& m) {
  return std::string(m.model) + (std::string(m.rolling) == "none" ? "" : "+" + std::string(m.rolling)) +
         (std::string(m.rolling) == "epsd" && m.eta_r == 0 ? "0" : "");
}

/// This thread's CPU time, s.
double thread_cpu_seconds() {
  timespec t;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

/// One model's lattice (lists built once, histories loaded by a few real steps) and its
/// force context, as in a run that records no contacts (one thread: no per-pair stores).
struct ForceLoop {
  std::unique_ptr<System> s;
  std::vector<PairResult> pr, rev;
  std::vector<Vec3> fw, tww, cw;
  std::unique_ptr<ForceContext> ctx;
  std::vector<std::byte> hist0;  ///< the contacts' histories after the set-up steps
  ForceLoop(const int n, const ModelCase mc) : s(lattice(n, mc.model, mc.rolling, mc.eta_r)) {
    s->prepare();
    s->run(5);
    hist0 = s->nl.hist.data;
    pr.resize(s->nl.pair_count());
    rev.resize(s->particles.size());
    ctx = std::make_unique<ForceContext>(
        ForceContext{s->particles, s->nl, s->walls, s->cfg.dt, s->time, pr, rev, fw, tww, cw});
    ctx->keep_pair = false;
  }
  /// The histories back to those after the set-up steps. The positions and velocities do not
  /// change from call to call, so each call loads the springs by one more step of the same
  /// motion: within a few hundred calls every tangential and rolling spring reaches its
  /// Coulomb limit, and the loop would time a bed in which every contact slides, a state no
  /// packing is in (the set-up steps' contacts all stick).
  void restore() { std::copy(hist0.begin(), hist0.end(), s->nl.hist.data.begin()); }
  /// Loads the springs by `calls` more force calls and makes that the state restore()
  /// returns to.
  void load(const int calls) {
    for (int c = 0; c < calls; ++c) compute();
    hist0 = s->nl.hist.data;
  }
  /// One force call (both passes).
  void compute() {
    s->model->compute(*ctx);
    benchmark::DoNotOptimize(s->particles.force.data());
    benchmark::ClobberMemory();
  }
  /// One force call; returns its thread CPU time, s.
  double call() {
    const double t0 = thread_cpu_seconds();
    compute();
    return thread_cpu_seconds() - t0;
  }
};

/// The benchmark's lattice (Arg: spheres per side) of mc, or null with the benchmark skipped
/// and the reason given.
std::unique_ptr<ForceLoop> force_loop(benchmark::State& st, const ModelCase mc) {
  try {
    return std::make_unique<ForceLoop>(int(st.range(0)), mc);
  } catch (const std::exception& e) {
    st.SkipWithError(e.what());
    return nullptr;
  }
}

/// The bulk force loop (both passes) of one contact model, lists built once.
void BM_Force(benchmark::State& st, ModelCase mc) {
  const std::unique_ptr<ForceLoop> L = force_loop(st, mc);
  if (!L) return;
  for (auto _ : st) L->compute();
  const System& s = *L->s;
  st.SetItemsProcessed(int64_t(st.iterations()) * int64_t(s.particles.size()));
  st.counters["contacts_per_particle"] = double(s.pair_contact_count()) / double(s.particles.size());
  st.counters["particles"] = double(s.particles.size());
}

/// The q-quantile of v (linear between order statistics).
double quantile(std::vector<double> v, const double q) {
  std::sort(v.begin(), v.end());
  const double x = q * double(v.size() - 1);
  const size_t i = size_t(x);
  return i + 1 < v.size() ? v[i] + (x - double(i)) * (v[i + 1] - v[i]) : v.back();
}
/// The alternating benchmarks' counters: ratio (the median of B's time over A's, block pair
/// by block pair), ratio_q1 and ratio_q3 (its quartiles), a_ms and b_ms (the median times per
/// call), blocks.
void ratio_counters(benchmark::State& st, const std::vector<double>& ratio, const std::vector<double>& ta,
                    const std::vector<double>& tb) {
  st.counters["ratio"] = quantile(ratio, 0.5);
  st.counters["ratio_q1"] = quantile(ratio, 0.25);
  st.counters["ratio_q3"] = quantile(ratio, 0.75);
  st.counters["a_ms"] = 1e3 * quantile(ta, 0.5);
  st.counters["b_ms"] = 1e3 * quantile(tb, 0.5);
  st.counters["blocks"] = double(ratio.size());
}

/// Two models' force loops (BM_Force's lattice) alternated in one process, in blocks of a few
/// calls each: the ratio of their costs on a shared machine, where the host's load drifts
/// over seconds and separate runs (micro_table.py's rounds) pair badly. Each iteration is one
/// block of A then one of B; a block's first call, the one that brings its data back into
/// the caches, is not timed (a run calls the same loop step after step). Each block starts
/// from the histories of the set-up steps (ForceLoop::restore): every block times the same
/// contacts, sticking as in a packing at rest. BM_ForceAlternateSliding: the histories are
/// first loaded by kSlideCalls calls, after which every spring of the lattice is at its
/// Coulomb limit, and each block starts from those: every contact sliding, as in a bed that
/// shears (the state the benchmark drifted into before the fifty-first round). Counters: ratio =
/// the median over the iterations of B's CPU time per call over A's in the same iteration
/// (ratio_q1, ratio_q3: its quartiles); a_ms, b_ms: the median CPU time per call.
constexpr int kSlideCalls = 1500;
/// widths: A's blocks on the AVX2 paths (four lanes) and B's on the AVX-512 ones (eight lanes,
/// the screening eight entries at a time), else both on the default.
void BM_ForceAlternateIn(benchmark::State& st, ModelCase a, ModelCase b, const int load_calls,
                         const bool widths = false) {
  const int n = int(st.range(0));
  std::unique_ptr<ForceLoop> A, B;
  try {
    A = std::make_unique<ForceLoop>(n, a);
    B = std::make_unique<ForceLoop>(n, b);
  } catch (const std::exception& e) {
    st.SkipWithError(e.what());
    return;
  }
  if (load_calls > 0) {
    A->load(load_calls);
    B->load(load_calls);
  }
  constexpr int kBlock = 4;  // calls per block, the first untimed
  std::vector<double> ratio, ta, tb;
  const bool wide0 = screen_avx512_enabled();
  for (auto _ : st) {
    double sa = 0, sb = 0;
    if (widths) set_screen_avx512(false);
    A->restore();
    for (int c = 0; c < kBlock; ++c) {
      const double t = A->call();
      if (c > 0) sa += t;
    }
    if (widths) set_screen_avx512(true);
    B->restore();
    for (int c = 0; c < kBlock; ++c) {
      const double t = B->call();
      if (c > 0) sb += t;
    }
    ratio.push_back(sb / sa);
    ta.push_back(sa / (kBlock - 1));
    tb.push_back(sb / (kBlock - 1));
  }
  set_screen_avx512(wide0);
  if (ratio.empty()) return;
  ratio_counters(st, ratio, ta, tb);
  // the contact lanes the default path ran (8: AVX-512, 4: AVX2, 0: scalar)
  if (!widths) st.counters["lanes"] = screen_avx512_enabled() ? 8.0 : screen_avx2_enabled() ? 4.0 : 0.0;
}
void BM_ForceAlternate(benchmark::State& st, ModelCase a, ModelCase b) { BM_ForceAlternateIn(st, a, b, 0); }
void BM_ForceAlternateSliding(benchmark::State& st, ModelCase a, ModelCase b) {
  BM_ForceAlternateIn(st, a, b, kSlideCalls);
}
/// One law in four AVX2 lanes (a) and in eight AVX-512 lanes (b), two lattices of it
/// alternated block by block: ratio is the eight lanes' time over the four lanes'.
void BM_LaneWidths(benchmark::State& st, ModelCase mc) { BM_ForceAlternateIn(st, mc, mc, 0, true); }

/// BM_PrefetchAlternate's and BM_CasePrefetch's loop: per iteration a block of `block` calls
/// of `timed` (each returns its seconds; a block's first is not counted) with the prefetch
/// off, then one with it on, `reset()` before each block; then the ratio counters, and the
/// records of `s` as force_loop_prefetches counts them (`bytes`) with its choice.
template <class Reset, class Timed>
void prefetch_alternate(benchmark::State& st, const System& s, const int block, Reset&& reset, Timed&& timed) {
  std::vector<double> ratio, ta, tb;
  for (auto _ : st) {
    double t[2] = {0, 0};
    for (int on = 0; on < 2; ++on) {
      set_force_loop_prefetch(on);
      reset();
      for (int c = 0; c < block; ++c) {
        const double dt = timed();
        if (c > 0) t[on] += dt;
      }
    }
    ratio.push_back(t[1] / t[0]);
    ta.push_back(t[0] / (block - 1));
    tb.push_back(t[1] / (block - 1));
  }
  set_force_loop_prefetch(-1);
  if (ratio.empty()) return;
  ratio_counters(st, ratio, ta, tb);
  const size_t entries = s.nl.jdx.size(), n = s.particles.size(), state = s.model->state_size();
  st.counters["bytes"] = double(force_loop_record_bytes(entries, n, state));
  st.counters["prefetch_auto"] = force_loop_prefetches(entries, n, state) ? 1.0 : 0.0;
}

/// The force loop's prefetch of the touching entries' records (force_loop_prefetches) off (A)
/// and on (B), alternated block by block on one lattice of one law (each block from the same
/// histories, as BM_ForceAlternate): ratio below 1 where asking ahead pays. bytes: the
/// lattice's records as the rule counts them (it asks from kPrefetchBytes on); prefetch_auto:
/// what the rule chooses for this lattice.
void BM_PrefetchAlternate(benchmark::State& st, ModelCase mc) {
  const std::unique_ptr<ForceLoop> L = force_loop(st, mc);
  if (!L) return;
  prefetch_alternate(st, *L->s, 4, [&] { L->restore(); }, [&] { return L->call(); });
}

/// A whole step (integration, rebuild check, forces) on the lattice.
void BM_Step(benchmark::State& st, ModelCase mc) {
  const int n = int(st.range(0));
  auto s = lattice(n, mc.model, mc.rolling, mc.eta_r);
  s->prepare();
  for (auto _ : st) s->step_once(true);  // as `cohdem run` steps between outputs (fused opening)
  st.SetItemsProcessed(int64_t(st.iterations()) * int64_t(s->particles.size()));
}

/// Neighbor build: binning, pair search, transposed index, wall candidates; no history
/// (fresh lists, nothing to carry over). No re-sort (the lattice is already in order).
void BM_NeighborBuild(benchmark::State& st) {
  const int n = int(st.range(0));
  auto s = lattice(n, "linear", "none");
  s->prepare();
  for (auto _ : st) {
    std::fill(s->nl.hist.live.begin(), s->nl.hist.live.end(), 0);
    s->nl.build(s->particles, s->walls, s->cfg.domain, s->cfg.skin, 0.0, false);
  }
  st.SetItemsProcessed(int64_t(st.iterations()) * int64_t(s->particles.size()));
  st.counters["entries_per_particle"] = double(s->nl.pair_count()) / double(s->particles.size());
}

/// Neighbor build with every contact live: the same as above plus the history merge (keys of
/// live contacts, sort, carry-over). The merge cost is this minus BM_NeighborBuild.
void BM_NeighborBuildWithHistory(benchmark::State& st) {
  const int n = int(st.range(0));
  auto s = lattice(n, "hertz_mindlin", "epsd");
  s->prepare();
  s->run(2);
  const auto live = s->nl.hist.live;
  for (auto _ : st) {
    st.PauseTiming();
    s->nl.hist.live = live;  // every contact live again (they all are; a no-op guard)
    st.ResumeTiming();
    s->nl.build(s->particles, s->walls, s->cfg.domain, s->cfg.skin, 0.0, false);
  }
  st.SetItemsProcessed(int64_t(st.iterations()) * int64_t(s->particles.size()));
  st.counters["live_per_particle"] = double(s->pair_contact_count()) / double(s->particles.size());
  st.counters["lost_contacts"] = double(s->nl.stats.lost_contacts);
}

/// The case file of the case benchmarks: COHDEM_BENCH_CASE, else the chute as
/// bench/lammps_data_to_case.py writes it to build/bench/chute.toml, else as
/// bench/peer_compare.py leaves it in build/bench/peers/chute.toml.
std::string bench_case() {
  if (const char* env = std::getenv("COHDEM_BENCH_CASE")) return env;
  for (const char* path : {"build/bench/chute.toml", "build/bench/peers/chute.toml"})
    if (std::FILE* f = std::fopen(path, "r")) {
      std::fclose(f);
      return path;
    }
  return "build/bench/chute.toml";  // missing: the benchmark reports it and is skipped
}

/// Whole steps of a case file (bench_case(): by default the chute). Skipped when the file is
/// not there. Arg: threads.
void BM_CaseStep(benchmark::State& st) {
  const std::string path = bench_case();
  std::unique_ptr<System> s;
  try {
    const Case c = load_case_file(path, {"simulation.threads=" + std::to_string(st.range(0))});
    s = build_system(c);
    s->prepare();
  } catch (const std::exception& e) {
    st.SkipWithError((path + ": " + e.what()).c_str());
    return;
  }
  for (auto _ : st) s->step_once(true);  // as `cohdem run` steps between outputs (fused opening)
  st.SetItemsProcessed(int64_t(st.iterations()) * int64_t(s->particles.size()));
  st.counters["contacts_per_particle"] = double(s->contact_count()) / double(s->particles.size());
  st.counters["entries_per_particle"] = double(s->nl.pair_count()) / double(s->particles.size());
}

/// The same on whole steps of the case benchmarks' case (bench_case(), by default the chute;
/// one thread): blocks of kBlock steps with the prefetch off, then on, the run going on from
/// block to block. ratio: the on-blocks' CPU time over the off-blocks', block pair by pair.
void BM_CasePrefetch(benchmark::State& st) {
  const std::string path = bench_case();
  std::unique_ptr<System> s;
  try {
    const Case c = load_case_file(path, {"simulation.threads=1"});
    s = build_system(c);
    s->prepare();
  } catch (const std::exception& e) {
    st.SkipWithError((path + ": " + e.what()).c_str());
    return;
  }
  prefetch_alternate(st, *s, 6, [] {}, [&] {
    const double t0 = thread_cpu_seconds();
    s->step_once(true);  // as BM_CaseStep
    return thread_cpu_seconds() - t0;
  });
}

/// The neighbor build of a case in mid-run (bench_case(), as BM_CaseStep): the case is
/// run for COHDEM_BENCH_WARM steps (default 300), so that its particles have left the cell
/// order of the last re-sort as they do between re-sorts, then the lists are rebuilt from that
/// state (no re-sort; the live contacts' history carried over each time). Arg: threads.
/// The case of bench_case() on `threads` threads, run for COHDEM_BENCH_WARM steps (default
/// 300); null (the benchmark skipped with the error) where it cannot be loaded or run.
std::unique_ptr<System> warmed_case(benchmark::State& st, const long threads) {
  const std::string path = bench_case();
  const char* warm = std::getenv("COHDEM_BENCH_WARM");
  try {
    std::unique_ptr<System> s = build_system(load_case_file(path, {"simulation.threads=" + std::to_string(threads)}));
    s->prepare();
    s->run(uint64_t(warm ? std::atol(warm) : 300));
    return s;
  } catch (const std::exception& e) {
    st.SkipWithError((path + ": " + e.what()).c_str());
    return nullptr;
  }
}

void BM_CaseNeighborBuild(benchmark::State& st) {
  const std::unique_ptr<System> s = warmed_case(st, st.range(0));
  if (!s) return;
  const double reach = s->reach();
  for (auto _ : st) s->nl.build(s->particles, s->walls, s->cfg.domain, s->cfg.skin, reach, false);
  st.SetItemsProcessed(int64_t(st.iterations()) * int64_t(s->particles.size()));
  st.counters["entries_per_particle"] = double(s->nl.pair_count()) / double(s->particles.size());
  st.counters["lost_contacts"] = double(s->nl.stats.lost_contacts);
}

/// The local check before a list build (NeighborList::recheck) on a case in mid-run
/// (bench_case(), warmed as BM_CaseNeighborBuild: the displacements since the warm-up's last
/// build): its pass over the particles, the blocks and, where it keeps the lists, the copy
/// of the drift's origin; to set against BM_CaseNeighborBuild, the build it saves. Counter
/// `kept`: whether it keeps the lists for that state. Arg: threads.
void BM_CaseLocalCheck(benchmark::State& st) {
  const std::unique_ptr<System> s = warmed_case(st, st.range(0));
  if (!s) return;
  s->nl.parallel_min = s->cfg.parallel_min;
  bool kept = false;
  for (auto _ : st) kept = s->nl.recheck(s->particles, s->walls, s->cfg.skin);
  st.SetItemsProcessed(int64_t(st.iterations()) * int64_t(s->particles.size()));
  st.counters["kept"] = kept;
}

/// The force loop's list screening alone (sim/screen.hpp) on a case in mid-run (bench_case(),
/// warmed as BM_CaseNeighborBuild): every entry of the lists screened in the kernel's batches
/// of kBatch, by the AVX2 path and by the AVX-512 one in turn within each iteration (the
/// scalar one too, as a reference), so that both see the same spell of the host. Reports each
/// one's ns per list entry and avx512_over_avx2, the median of the iterations' time ratios.
/// Skipped where the CPU lacks AVX-512.
void BM_CaseScreen(benchmark::State& st) {
  if (!avx512_available() || !avx2_available()) {
    st.SkipWithError("this CPU or build has no AVX-512 screening");
    return;
  }
  const std::unique_ptr<System> s = warmed_case(st, 1);
  if (!s) return;
  const NeighborList& nl = s->nl;
  const long n = long(s->particles.size());
  const uint32_t entries = uint32_t(std::min({nl.jdx.size(), nl.image.size(), nl.hist.live.size()}));
  const ScreenInput in{nl.start.data(), nl.jdx.data(), nl.image.data(), nl.hist.live.data(), nl.shift.data(),
                       s->particles.x.data(), s->particles.radius.data(), entries};
  using Fn = uint32_t (*)(const ScreenInput&, long, long, long, uint32_t, uint32_t, ScreenHits&);
  auto sweep = [&](const Fn fn) {  // the kernel's batching (force_kernel.hpp, sweep and batch_end)
    static ScreenHits hits;
    uint64_t picked = 0;
    long i = 0;
    for (uint32_t k = nl.start[0]; i < n;) {
      const uint32_t ke = std::min(k + kBatch, nl.start[size_t(n)]);
      long i1 = i;
      while (i1 < n && nl.start[size_t(i1 + 1)] <= ke) ++i1;
      picked += fn(in, i, i1, n, k, ke, hits);
      i = i1;
      k = ke;
    }
    return picked;
  };
  auto timed = [&](const Fn fn, uint64_t& picked) {
    const auto t0 = std::chrono::steady_clock::now();
    picked = sweep(fn);
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  };
  const Fn scalar = [](const ScreenInput& a, long b, long c, long d, uint32_t e, uint32_t f, ScreenHits& h) {
    return screen_scalar(a, b, c, d, e, f, h);
  };
  std::vector<double> ratios;
  double t2 = 0, t5 = 0, t1 = 0;
  uint64_t p2 = 0, p5 = 0, p1 = 0;
  for (auto _ : st) {
    double a2, b5;
    if (ratios.size() % 2 == 0) {  // the order alternates
      a2 = timed(screen_avx2, p2);
      b5 = timed(screen_avx512, p5);
    } else {
      b5 = timed(screen_avx512, p5);
      a2 = timed(screen_avx2, p2);
    }
    t1 += timed(scalar, p1);
    t2 += a2;
    t5 += b5;
    ratios.push_back(b5 / a2);
  }
  if (p1 != p2 || p1 != p5) st.SkipWithError("the screenings picked different numbers of entries");
  std::sort(ratios.begin(), ratios.end());
  const double per = 1e9 / (double(st.iterations()) * double(entries));
  st.SetItemsProcessed(int64_t(st.iterations()) * int64_t(n));
  st.counters["scalar_ns_per_entry"] = t1 * per;
  st.counters["avx2_ns_per_entry"] = t2 * per;
  st.counters["avx512_ns_per_entry"] = t5 * per;
  st.counters["avx512_over_avx2"] = ratios[ratios.size() / 2];
  st.counters["picked_per_entry"] = double(p5) / double(entries);
}

/// COHDEM_BENCH_ITERS=N fixes the iteration count (for valgrind/callgrind comparisons).
benchmark::internal::Benchmark* iters(benchmark::internal::Benchmark* b) {
  if (const char* e = std::getenv("COHDEM_BENCH_ITERS")) b->Iterations(std::atol(e));
  return b;
}

void register_all() {
  std::vector<ModelCase> cases = {{"linear", "none"}, {"linear", "epsd"}, {"hertz_mindlin", "none"},
                                  {"hertz_mindlin", "epsd"}, {"hertz_mindlin", "sds"}};
  // Presets that land later (MEPA, Walton, ...) are picked up from the registry.
  static std::vector<std::string> extra;
  for (const auto& name : contact_model_names())
    if (name != "linear" && name != "hertz_mindlin") extra.push_back(name);
  for (const auto& name : extra) {
    cases.push_back({name.c_str(), "none"});
    try {  // some presets have no rolling choice (walton: its bending moment fills the slot)
      make_contact_model(name, "epsd");
      cases.push_back({name.c_str(), "epsd"});
    } catch (const std::exception&) {
    }
  }
  for (const auto& c : cases) {
    const std::string tag = tag_of(c);
    // 8: a lattice of 512 spheres, about the ring shear main job's 643, whose records stay in
    // the core's caches (the force loop then asks for none ahead: force_loop_prefetches).
    iters(benchmark::RegisterBenchmark(("BM_Force/" + tag).c_str(), BM_Force, c))->Arg(8)->Arg(32)->Unit(benchmark::kMicrosecond);
    benchmark::RegisterBenchmark(("BM_Step/" + tag).c_str(), BM_Step, c)->Arg(32)->Unit(benchmark::kMicrosecond);
  }
  // Issue 6's fourth target: MEPA n = 3/2 + EPSD against the plain linear law; each law
  // against a second lattice of itself is the method's control (its ratio must be 1).
  for (const auto& [a, b] : {std::pair{ModelCase{"linear", "none"}, ModelCase{"mepa", "epsd"}},
                             std::pair{ModelCase{"linear", "none"}, ModelCase{"linear", "none"}},
                             std::pair{ModelCase{"mepa", "epsd"}, ModelCase{"mepa", "epsd"}},
                             std::pair{ModelCase{"linear", "none"}, ModelCase{"mepa", "none"}},
                             std::pair{ModelCase{"linear", "none"}, ModelCase{"linear", "epsd"}},
                             std::pair{ModelCase{"linear", "none"}, ModelCase{"mepa", "epsd", 0.0}}}) {
    iters(benchmark::RegisterBenchmark(("BM_ForceAlternate/" + tag_of(a) + "/" + tag_of(b)).c_str(), BM_ForceAlternate,
                                       a, b))
        ->Arg(32)->Unit(benchmark::kMillisecond);
  }
  // The same in a bed where every contact slides: the target's pair and its linear control.
  for (const auto& [a, b] : {std::pair{ModelCase{"linear", "none"}, ModelCase{"mepa", "epsd"}},
                             std::pair{ModelCase{"linear", "none"}, ModelCase{"linear", "none"}}}) {
    iters(benchmark::RegisterBenchmark(("BM_ForceAlternateSliding/" + tag_of(a) + "/" + tag_of(b)).c_str(),
                                       BM_ForceAlternateSliding, a, b))
        ->Arg(32)->Unit(benchmark::kMillisecond);
  }
  // Where the CPU has AVX-512: each law with lanes in four and in eight lanes.
  if (avx512_available())
    for (const auto& c : {ModelCase{"linear", "none"}, ModelCase{"linear", "epsd"}, ModelCase{"hertz_mindlin", "epsd"},
                          ModelCase{"mepa", "none"}, ModelCase{"mepa", "epsd"}})
      iters(benchmark::RegisterBenchmark(("BM_LaneWidths/" + tag_of(c)).c_str(), BM_LaneWidths, c))
          ->Arg(32)->Unit(benchmark::kMillisecond);
  // The force loop's prefetch off and on (force_loop_prefetches' threshold): the linear law
  // and MEPA + EPSD on lattices of 512, 4096 and 32,768 spheres, and the chute's steps.
  for (const auto& c : {ModelCase{"linear", "none"}, ModelCase{"mepa", "epsd"}})
    iters(benchmark::RegisterBenchmark(("BM_PrefetchAlternate/" + tag_of(c)).c_str(), BM_PrefetchAlternate, c))
        ->Arg(8)->Arg(16)->Arg(32)->Unit(benchmark::kMillisecond);
  iters(benchmark::RegisterBenchmark("BM_CasePrefetch", BM_CasePrefetch))->Unit(benchmark::kMillisecond);
  iters(benchmark::RegisterBenchmark("BM_CaseStep", BM_CaseStep))->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond)->UseRealTime();
  benchmark::RegisterBenchmark("BM_CaseScreen", BM_CaseScreen)->Unit(benchmark::kMicrosecond);
  iters(benchmark::RegisterBenchmark("BM_CaseNeighborBuild", BM_CaseNeighborBuild))
      ->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond)->UseRealTime();
  iters(benchmark::RegisterBenchmark("BM_CaseLocalCheck", BM_CaseLocalCheck))
      ->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond)->UseRealTime();
  benchmark::RegisterBenchmark("BM_NeighborBuild", BM_NeighborBuild)->Arg(32)->Unit(benchmark::kMicrosecond);
  benchmark::RegisterBenchmark("BM_NeighborBuildWithHistory", BM_NeighborBuildWithHistory)
      ->Arg(32)->Unit(benchmark::kMicrosecond);
}

}  // namespace

int main(int argc, char** argv) {
  register_all();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
