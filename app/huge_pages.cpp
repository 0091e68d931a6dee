// Large allocations on transparent huge pages (Linux): the global operator new is replaced
// so that the whole 2 MiB pages inside every block of 2 MiB or more are marked MADV_HUGEPAGE
// before the block is first touched. Debian's and most distributions' kernels give huge
// pages only to memory so marked (the "madvise" setting of
// /sys/kernel/mm/transparent_hugepage/enabled); with "always" the mark changes nothing, with
// "never" the kernel ignores it.
//
// Why: at 10^6 particles the step's arrays are 4-24 MiB each and the force loop reads the
// partners' records a plane of cells ahead. With 4 KiB pages each such read can also miss
// the TLB; with 2 MiB pages the page walks all but vanish. Measured on the 10^6 gas
// (docs/performance-history.md, sixtieth round): 1.02x on two threads, no change on one, the
// same bits. Small blocks (the 10^4 gas's arrays, the lists of a ring shear cell) are left as
// malloc gives them.
//
// COHDEM_THP=0 in the environment turns it off (for comparisons): no block is marked. Linked
// into the cohdem program, its tests and its benchmarks (CMakeLists.txt), not into the
// library: a program that embeds cohdem keeps its own allocator.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <new>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace {

constexpr std::size_t kHugePage = std::size_t(2) << 20;

bool huge_pages_on() {
  // Read once (getenv allocates nothing, so it is safe inside operator new).
  static const bool on = [] {
    const char* e = std::getenv("COHDEM_THP");
    return !(e != nullptr && e[0] == '0' && e[1] == '\0');
  }();
  return on;
}

void* try_allocate(const std::size_t n) {
  void* p = std::malloc(n == 0 ? 1 : n);
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  if (p != nullptr && n >= kHugePage && huge_pages_on()) {
    // The whole huge pages inside the block (malloc gives large blocks their own mapping,
    // page-aligned, or heap memory: both anonymous). Its first and last partial pages stay
    // small. The block itself is not moved to a 2 MiB boundary: arrays that all started on one
    // would put the same particle of every array in the same cache sets (tried: 0.985x on one
    // thread at 10^6 particles).
    const auto a = reinterpret_cast<std::uintptr_t>(p);
    const std::uintptr_t lo = (a + kHugePage - 1) / kHugePage * kHugePage, hi = (a + n) / kHugePage * kHugePage;
    // A failed advice (a kernel without transparent huge pages) leaves ordinary pages.
    if (hi > lo) (void)madvise(reinterpret_cast<void*>(lo), hi - lo, MADV_HUGEPAGE);
  }
#endif
  return p;
}

void* allocate(const std::size_t n) {
  for (;;) {
    if (void* p = try_allocate(n)) return p;
    const std::new_handler h = std::get_new_handler();
    if (h == nullptr) throw std::bad_alloc();
    h();
  }
}

}  // namespace

// Every block, large or small, comes from malloc and is released with free; the library's
// aligned and nothrow forms call these or free as well.
void* operator new(std::size_t n) { return allocate(n); }
void* operator new[](std::size_t n) { return allocate(n); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
