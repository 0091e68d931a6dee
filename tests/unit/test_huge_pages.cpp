// app/huge_pages.cpp replaces the global operator new of the program, its tests and its
// benchmarks: the whole 2 MiB pages inside a block of 2 MiB or more are marked for
// transparent huge pages (MADV_HUGEPAGE) before it is touched; COHDEM_THP=0 turns that off.
// Checked here through what the kernel reports for the block's mapping (/proc/self/smaps),
// not through timings.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace {

constexpr uintptr_t kHugePage = uintptr_t(2) << 20;

bool thp_disabled() {
  const char* e = std::getenv("COHDEM_THP");
  return e != nullptr && std::string(e) == "0";
}

/// The smaps block of the mapping holding address a ("" where /proc/self/smaps is missing).
std::string smaps_of(const uintptr_t a) {
  std::ifstream in("/proc/self/smaps");
  std::string line, block;
  bool inside = false;
  while (std::getline(in, line)) {
    // A mapping's first line: "lo-hi perms offset dev inode path", hex addresses.
    uintptr_t lo = 0, hi = 0;
    char dash = 0;
    std::istringstream head(line);
    if (head >> std::hex >> lo >> dash >> hi && dash == '-' && line.find(':') > line.find(' ')) {
      if (inside) return block;
      inside = a >= lo && a < hi;
      block.clear();
    }
    if (inside) block += line + "\n";
  }
  return inside ? block : "";
}

/// The value of a "Key:  value" line of an smaps block, or -1 where the kernel does not give it.
long smaps_field(const std::string& block, const std::string& key) {
  const size_t at = block.find("\n" + key + ":");
  if (at == std::string::npos) return -1;
  return std::strtol(block.c_str() + at + key.size() + 2, nullptr, 10);
}

}  // namespace

TEST(HugePages, LargeBlocksAreMarkedForThem) {
#if !defined(__linux__)
  GTEST_SKIP() << "transparent huge pages are a Linux feature";
#endif
  if (thp_disabled()) GTEST_SKIP() << "COHDEM_THP=0";
  std::ifstream mode_file("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string mode;
  std::getline(mode_file, mode);
  if (mode.empty() || mode.find("[never]") != std::string::npos)
    GTEST_SKIP() << "this kernel gives no transparent huge pages (" << mode << ")";
  // 6 MiB of doubles (a 10^6-particle run's arrays are 4-24 MiB each), and a block just
  // under 2 MiB, which is left alone.
  std::vector<double> big(6u << 17, 1.0), small((2u << 17) - 1024, 1.0);
  const uintptr_t a = reinterpret_cast<uintptr_t>(big.data());
  const uintptr_t inside = (a + kHugePage - 1) / kHugePage * kHugePage;  // its first whole huge page
  ASSERT_LE(inside + kHugePage, a + big.size() * sizeof(double));
  const std::string block = smaps_of(inside);
  if (block.empty()) GTEST_SKIP() << "no /proc/self/smaps";
  const long eligible = smaps_field(block, "THPeligible");
  if (eligible < 0) GTEST_SKIP() << "this kernel does not say which mappings are eligible";
  // With the "madvise" setting only a marked mapping is eligible; with "always" every one.
  EXPECT_EQ(eligible, 1) << "the huge pages inside a 6 MiB block are not marked (" << mode << ")\n" << block;
  if (mode.find("[madvise]") != std::string::npos) {
    const uintptr_t s0 = reinterpret_cast<uintptr_t>(small.data());
    const std::string sb = smaps_of((s0 + kHugePage - 1) / kHugePage * kHugePage);
    if (!sb.empty()) EXPECT_EQ(smaps_field(sb, "THPeligible"), 0) << "a block under 2 MiB was marked\n" << sb;
  }
}

TEST(HugePages, SmallBlocksAndReleasesWorkAsBefore) {
  // Small and large blocks (the large ones marked), allocated and released in mixed order
  // (every block is released with free): each keeps its own contents, so no two blocks
  // overlap and none was released while in use.
  std::vector<std::vector<uint64_t>> keep;
  std::vector<int> tag;
  auto fill = [](std::vector<uint64_t>& v, const int r) {
    for (size_t q = 0; q < v.size(); ++q) v[q] = uint64_t(r) * 1000003u + q;
  };
  for (int r = 0; r < 40; ++r) {
    const size_t n = (r % 4 == 0) ? (size_t(5) << 18) + size_t(r) : size_t(17 * r + 1);
    keep.emplace_back(n);
    tag.push_back(r);
    fill(keep.back(), r);
    if (r % 3 == 2) {
      keep.erase(keep.begin());
      tag.erase(tag.begin());
    }
  }
  size_t bad = 0;
  for (size_t b = 0; b < keep.size(); ++b)
    for (size_t q = 0; q < keep[b].size(); ++q) bad += keep[b][q] != uint64_t(tag[b]) * 1000003u + q;
  EXPECT_EQ(bad, 0u);
  EXPECT_EQ(keep.size(), 27u);
  auto* arr = new double[(5u << 17)];
  arr[0] = 1.0;
  arr[(5u << 17) - 1] = 2.0;
  EXPECT_EQ(arr[0] + arr[(5u << 17) - 1], 3.0);
  delete[] arr;
}
