// Probes of the machine, not of cohdem. They explain costs seen in whole runs
// (docs/performance-history.md, twenty-fourth and twenty-fifth rounds), and give a reading of a
// machine before a benchmark session.
//
//   ./build/cohdem_bench --benchmark_filter='CacheAfterPause|CoreToCore|RemoteLines|OmpSync|Streams|FirstTouch'
//
// How long data stays in this core's caches while the core does something else: the force
// calls right after a neighbor-list build run slower, and so do those after a pause of the
// same length that touches no memory at all.
//
// BM_CacheAfterPause/<KiB>/<pause us>: a buffer of KiB kibibytes, one 8-byte word per 64-byte
// line linked into a single random cycle, is walked once (every line, each load depending on
// the last, so the walk's time is the lines' latency); between walks (outside the timing) the
// core runs a register-only loop for `pause` microseconds. With no pause the buffer stays as
// warm as the caches allow; where a pause of a few milliseconds doubles the walk, the lines
// were evicted during the pause by something other than this process (on a shared host: the
// other tenants of the L3, or the host running other work on this core).
//
// BM_CoreToCore: one cache line passed back and forth between two threads pinned to two
// different CPUs (the first two this process may run on), each waiting for the other's
// store before making its own; the time per round trip is twice the latency of moving a
// written line from one core to the other. Every handing of data between threads pays it:
// OpenMP's fork, join and barriers, and any line that one thread writes and the other reads
// (in the force loop, the particles at a block boundary).
//
// BM_Streams/streams:<K>/layout:<0|1|2>: how many sequential streams one core keeps
// prefetched. Each step of the loop updates element i of K streams (a record of three
// doubles: reads two, writes the third), the way the force loop's finish walks a particle's
// position, velocity, spin, force, torque, ... arrays side by side. Layout 0: K separate
// arrays, each starting 1088 bytes (17 lines) further into its page than the one before (no
// two streams share an L1 set at the same element); layout 1: one array of K-record
// structures (the same bytes, one stream); layout 2: K separate arrays all at the same offset
// within their pages (what large vectors get from mmap: cohdem's particle arrays at 10^6
// particles). 2^19 elements a stream (12 MiB, beyond the caches). The rate in bytes per second
// counts the records' bytes once. On the twenty-sixth round's Zen 4 VM (thirty-second round in
// docs/performance.md): layout 1 holds 19-26 GB/s at any K; layout 0 16-18 GB/s up to 16
// streams and 9-11 from 18; layout 2 falls to 5-8 GB/s from 12 streams. Whole runs of cohdem
// did not follow (the same section): five fewer streams, or the arrays staggered, left the
// 10^6 gas where it was.
//
// BM_OmpSync/threads:2/kind:<0|1>: what OpenMP's synchronisation costs on two threads, per
// operation: kind 0 an empty parallel region (fork and join, what the force loop pays once
// per call), kind 1 a barrier inside one region (what a team kept across steps would pay
// instead).
//
// BM_FirstTouch/KiB:<K>/huge:<0|1>: what the first write to fresh memory costs. Each iteration
// maps K KiB of new anonymous memory (aligned to 2 MiB), with huge:1 advised MADV_HUGEPAGE,
// and writes one byte in every 4 KiB page (timed), then unmaps it (not timed). The counter
// is the time per 4 KiB page (with huge pages, per 4 KiB of the huge pages' memory; a block
// under 2 MiB, as the 1024 KiB one, holds no huge page whatever the advice). It
// is what an array pays the first time the time loop writes it (an array grown in the loop,
// a buffer first used at the first list build that carries contacts): on the seventy-third
// round's Zen 5 VM 10-11 us a 4 KiB page, 2.6 ms a MiB, and 0.2 us with huge pages (0.11 ms
// a 2 MiB page), where a page fault on an ordinary host costs well under 1 us
// (docs/performance-history.md, seventy-third round). Linux only (elsewhere: skipped).
#include <benchmark/benchmark.h>
#include <omp.h>
#include <pthread.h>
#include <sched.h>

#if defined(__linux__)
#include <sys/mman.h>
#endif

#include <atomic>
#include <chrono>
#include <cstdint>
#include <random>
#include <string>
#include <thread>
#include <utility>
#include <vector>

namespace {

/// `lines` 64-byte lines of eight words whose word 0 holds the index of the next line's
/// word 0 along one random cycle through all of them (Sattolo), so that a walk p = buf[p]
/// from 0 visits every line once, each load's address taken from the one before.
std::vector<uint64_t> line_cycle(const size_t lines, const uint64_t seed) {
  std::vector<uint64_t> buf(lines * 8);
  std::vector<uint64_t> order(lines);
  for (size_t i = 0; i < lines; ++i) order[i] = i;
  std::mt19937_64 rng(seed);
  for (size_t i = lines - 1; i > 0; --i) std::swap(order[i], order[std::uniform_int_distribution<size_t>(0, i - 1)(rng)]);
  for (size_t i = 0; i < lines; ++i) buf[order[i] * 8] = order[(i + 1) % lines] * 8;
  return buf;
}

void BM_CacheAfterPause(benchmark::State& st) {
  const size_t lines = size_t(st.range(0)) * 1024 / 64;
  const auto pause = std::chrono::microseconds(st.range(1));
  std::vector<uint64_t> buf = line_cycle(lines, 1);
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

/// The first two CPUs this process may run on, or -1 where it has fewer than two.
std::pair<int, int> two_cpus() {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof set, &set) != 0) return {-1, -1};
  int found[2] = {-1, -1}, k = 0;
  for (int c = 0; c < CPU_SETSIZE && k < 2; ++c)
    if (CPU_ISSET(c, &set)) found[k++] = c;
  return {found[0], found[1]};
}

bool pin_to(const int cpu) {
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(cpu, &set);
  return pthread_setaffinity_np(pthread_self(), sizeof set, &set) == 0;
}

void BM_CoreToCore(benchmark::State& st) {
  const auto [c0, c1] = two_cpus();
  if (c1 < 0) {
    st.SkipWithError("needs two CPUs");
    return;
  }
  // Two lines, each written by one thread only: the ping and the pong.
  struct alignas(64) Line { std::atomic<uint64_t> v{0}; };
  static Line ping, pong;
  ping.v.store(0);
  pong.v.store(0);
  std::atomic<bool> stop{false};
  std::thread other([&, c1 = c1] {
    pin_to(c1);
    uint64_t seen = 0;
    while (true) {
      const uint64_t p = ping.v.load(std::memory_order_acquire);
      if (p != seen) {
        seen = p;
        pong.v.store(p, std::memory_order_release);
      } else if (stop.load(std::memory_order_relaxed)) {
        break;
      }
    }
  });
  cpu_set_t before;
  pthread_getaffinity_np(pthread_self(), sizeof before, &before);
  pin_to(c0);
  uint64_t i = 0;
  constexpr int kTrips = 1000;
  for (auto _ : st) {
    for (int r = 0; r < kTrips; ++r) {
      ping.v.store(++i, std::memory_order_release);
      while (pong.v.load(std::memory_order_acquire) != i) {
      }
    }
  }
  stop.store(true);  // seen by the other thread once it has answered the last ping
  other.join();
  pthread_setaffinity_np(pthread_self(), sizeof before, &before);
  st.counters["time_per_round_trip"] = benchmark::Counter(double(st.iterations()) * kTrips,
                                                        benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  st.SetLabel("CPUs " + std::to_string(c0) + " and " + std::to_string(c1));
}

BENCHMARK(BM_CoreToCore)->Unit(benchmark::kMicrosecond)->UseRealTime();

// BM_RemoteLines: what a line written by the other core costs when it is read, where the
// reads cannot overlap. The other thread (second CPU) writes one word in each of 4000 lines
// (256 KiB, within any L2); then this thread (first CPU) walks them once along a random
// cycle, each load's address taken from the one before, timed (ns_per_line); and hands them
// back. What the force loop pays for the particles at a block boundary, which both cores
// touch every step, follows it. On the forty-third round's Zen 3 VM it took one of two values
// that the host switched between every few tens of seconds, 18-24 ns and 65-80 ns ("the
// host's placement of the two vCPUs"; docs/performance-history.md, forty-third and forty-fourth rounds:
// the chute's block-boundary finishing 21-25 against 46-50 us a step); bench/scaling.py
// --placement reads it before and after each two-thread run.
void BM_RemoteLines(benchmark::State& st) {
  const auto [c0, c1] = two_cpus();
  if (c1 < 0) {
    st.SkipWithError("needs two CPUs");
    return;
  }
  constexpr size_t kLines = 4000;
  // Word 0 of each line: the cycle's next line; word 1: what the other thread writes (the
  // line is then in its cache, modified).
  std::vector<uint64_t> buf = line_cycle(kLines, 2);
  std::atomic<int> turn{0};  // 1: the other thread writes; 0: this one walks; -1: stop
  std::thread other([&, c1 = c1] {
    pin_to(c1);
    for (;;) {
      int t;
      while ((t = turn.load(std::memory_order_acquire)) == 0) {
      }
      if (t < 0) break;
      for (size_t l = 0; l < kLines; ++l) buf[l * 8 + 1] += 1;
      turn.store(0, std::memory_order_release);
    }
  });
  cpu_set_t before;
  pthread_getaffinity_np(pthread_self(), sizeof before, &before);
  pin_to(c0);
  uint64_t p = 0;
  for (auto _ : st) {
    st.PauseTiming();
    turn.store(1, std::memory_order_release);
    while (turn.load(std::memory_order_acquire) != 0) {
    }
    st.ResumeTiming();
    for (size_t l = 0; l < kLines; ++l) p = buf[p];
  }
  turn.store(-1, std::memory_order_release);
  other.join();
  pthread_setaffinity_np(pthread_self(), sizeof before, &before);
  benchmark::DoNotOptimize(p);
  st.counters["ns_per_line"] = benchmark::Counter(double(st.iterations()) * double(kLines),
                                                  benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  st.SetLabel("CPUs " + std::to_string(c0) + " and " + std::to_string(c1));
}

BENCHMARK(BM_RemoteLines)->Unit(benchmark::kMicrosecond)->UseRealTime();

void BM_OmpSync(benchmark::State& st) {
  const int nt = int(st.range(0));
  const bool barrier = st.range(1) == 1;
  constexpr int kOps = 1000;
  for (auto _ : st) {
    if (barrier) {
#pragma omp parallel num_threads(nt)
      for (int r = 0; r < kOps; ++r) {
#pragma omp barrier
      }
    } else {
      for (int r = 0; r < kOps; ++r) {
#pragma omp parallel num_threads(nt)
        benchmark::ClobberMemory();
      }
    }
  }
  st.counters["time_per_op"] =
      benchmark::Counter(double(st.iterations()) * kOps, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

void BM_Streams(benchmark::State& st) {
  const size_t k_streams = size_t(st.range(0));
  const int layout = int(st.range(1));
  constexpr size_t kN = size_t(1) << 19;           // elements a stream
  constexpr size_t kRec = 3;                       // doubles a record
  constexpr size_t kArray = kN * kRec;             // doubles an array (a whole number of pages)
  constexpr size_t kStagger = 1088 / sizeof(double);  // 17 lines
  const size_t gap = layout == 0 ? kStagger : 0;
  std::vector<double> buf(k_streams * (kArray + gap) + 8);
  // 64-byte aligned start; arrays k at k * (kArray + gap) (layout 1 uses the buffer as one array).
  double* const base = reinterpret_cast<double*>((reinterpret_cast<uintptr_t>(buf.data()) + 63) & ~uintptr_t(63));
  std::vector<double*> arr(k_streams);
  for (size_t k = 0; k < k_streams; ++k) arr[k] = base + k * (kArray + gap);
  for (size_t q = 0; q < k_streams * kArray; ++q) base[q] = 1e-9 * double(q % 1000);
  double total = 0;
  for (auto _ : st) {
    if (layout == 1) {
      for (size_t i = 0; i < kN; ++i) {
        double s = 0;
        double* const p = base + i * kRec * k_streams;
        for (size_t k = 0; k < k_streams; ++k) {
          s += p[kRec * k] * p[kRec * k + 1];
          p[kRec * k + 2] = s;
        }
      }
    } else {
      double* const* const a = arr.data();
      for (size_t i = 0; i < kN; ++i) {
        double s = 0;
        for (size_t k = 0; k < k_streams; ++k) {
          double* const p = a[k] + kRec * i;
          s += p[0] * p[1];
          p[2] = s;
        }
      }
    }
    benchmark::ClobberMemory();
    total += base[2];
  }
  benchmark::DoNotOptimize(total);
  st.SetBytesProcessed(int64_t(st.iterations()) * int64_t(kN * kRec * sizeof(double) * k_streams));
  st.counters["ns_per_element"] =
      benchmark::Counter(double(st.iterations()) * double(kN), benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

void BM_FirstTouch(benchmark::State& st) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  constexpr size_t kPage = 4096, kHuge = size_t(2) << 20;
  const size_t bytes = size_t(st.range(0)) * 1024;
  const bool huge = st.range(1) == 1;
  for (auto _ : st) {
    st.PauseTiming();
    // Room for a 2 MiB boundary inside, so that huge pages can back all of `bytes`.
    void* const m = mmap(nullptr, bytes + kHuge, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (m == MAP_FAILED) {
      st.SkipWithError("mmap failed");
      return;
    }
    char* const p = reinterpret_cast<char*>((reinterpret_cast<uintptr_t>(m) + kHuge - 1) & ~uintptr_t(kHuge - 1));
    if (huge) (void)madvise(p, bytes, MADV_HUGEPAGE);
    st.ResumeTiming();
    for (size_t o = 0; o < bytes; o += kPage) p[o] = 1;
    benchmark::ClobberMemory();
    st.PauseTiming();
    munmap(m, bytes + kHuge);
    st.ResumeTiming();
  }
  st.counters["per_4KiB_page"] = benchmark::Counter(double(st.iterations()) * double(bytes / kPage),
                                                    benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
#else
  st.SkipWithError("Linux only");
#endif
}

BENCHMARK(BM_FirstTouch)
    ->ArgsProduct({{1024, 16384}, {0, 1}})
    ->ArgNames({"KiB", "huge"})
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime();

BENCHMARK(BM_Streams)
    ->ArgsProduct({{4, 8, 12, 16, 18, 20, 24}, {0, 1, 2}})
    ->ArgNames({"streams", "layout"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

BENCHMARK(BM_OmpSync)
    ->ArgsProduct({{2}, {0, 1}})
    ->ArgNames({"threads", "kind"})
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime();

}  // namespace
