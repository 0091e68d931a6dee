// A probe of the machine, not of cohdem: how long data stays in this core's caches while the
// core does something else. It explains a cost seen in whole runs (docs/performance.md,
// twenty-fourth round): the force calls right after a neighbor-list build run slower, and
// so do those after a pause of the same length that touches no memory at all.
//
//   ./build/cohdem_bench --benchmark_filter=CacheAfterPause
//
// BM_CacheAfterPause/<KiB>/<pause us>: a buffer of KiB kibibytes, one 8-byte word per 64-byte
// line linked into a single random cycle, is walked once (every line, each load depending on
// the last, so the walk's time is the lines' latency); between walks (outside the timing) the
// core runs a register-only loop for `pause` microseconds. With no pause the buffer stays as
// warm as the caches allow; where a pause of a few milliseconds doubles the walk, the lines
// were evicted during the pause by something other than this process (on a shared host: the
// other tenants of the L3, or the host running other work on this core).
#include <benchmark/benchmark.h>

#include <chrono>
#include <cstdint>
#include <random>
#include <vector>

namespace {

void BM_CacheAfterPause(benchmark::State& st) {
  const size_t lines = size_t(st.range(0)) * 1024 / 64;
  const auto pause = std::chrono::microseconds(st.range(1));
  // Word 0 of each line holds the index of the next line's word (Sattolo: one cycle).
  std::vector<uint64_t> buf(lines * 8);
  std::vector<uint64_t> order(lines);
  for (size_t i = 0; i < lines; ++i) order[i] = i;
  std::mt19937_64 rng(1);
  for (size_t i = lines - 1; i > 0; --i) std::swap(order[i], order[std::uniform_int_distribution<size_t>(0, i - 1)(rng)]);
  for (size_t i = 0; i < lines; ++i) buf[order[i] * 8] = order[(i + 1) % lines] * 8;
  uint64_t p = 0;
  for (size_t i = 0; i < lines; ++i) p = buf[p];  // warm
  uint64_t x = 88172645463325252ull;
  for (auto _ : st) {
    if (pause.count() > 0) {
      st.PauseTiming();
      const auto t0 = std::chrono::steady_clock::now();
      while (std::chrono::steady_clock::now() - t0 < pause)
        for (int r = 0; r < 64; ++r) { x ^= x << 13; x ^= x >> 7; x ^= x << 17; }
      st.ResumeTiming();
    }
    for (size_t i = 0; i < lines; ++i) p = buf[p];
  }
  benchmark::DoNotOptimize(p);
  benchmark::DoNotOptimize(x);
  st.SetItemsProcessed(int64_t(st.iterations()) * int64_t(lines));
  st.counters["ns_per_line"] =
      benchmark::Counter(double(st.iterations()) * double(lines), benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

BENCHMARK(BM_CacheAfterPause)
    ->ArgsProduct({{1024, 4096}, {0, 250, 1000, 4000}})
    ->ArgNames({"KiB", "pause_us"})
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime();

}  // namespace
