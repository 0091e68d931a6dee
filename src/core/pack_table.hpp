// Left-packing of the picked lanes of a four-lane group (the AVX2 screening, src/sim/
// screen_avx2.cpp, and the list build's pair search, src/neighbor/search_avx2.cpp): for each
// 4-bit mask of picked lanes, the lanes in ascending order (then lane 0 again), as the
// permutation that moves them to the front of a register.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>

namespace cohdem {

struct PackTable {
  alignas(32) int32_t dbl[16][8];  ///< 64-bit lanes as pairs of 32-bit halves (vpermd / vpermps)
  alignas(16) uint8_t u32[16][16]; ///< 32-bit lanes as bytes (pshufb)
  alignas(16) uint8_t u8[16][16];  ///< 8-bit lanes (pshufb; bytes 4-15 zero)
};

constexpr PackTable make_pack_table() {
  PackTable t{};
  for (int m = 0; m < 16; ++m) {
    int n = 0;
    std::array<int, 4> lanes{0, 0, 0, 0};
    for (int l = 0; l < 4; ++l)
      if (m & (1 << l)) lanes[size_t(n++)] = l;
    for (int o = 0; o < 4; ++o) {
      const int l = lanes[size_t(o)];
      t.dbl[m][2 * o] = 2 * l;
      t.dbl[m][2 * o + 1] = 2 * l + 1;
      for (int b = 0; b < 4; ++b) t.u32[m][4 * o + b] = uint8_t(4 * l + b);
      t.u8[m][o] = uint8_t(l);
    }
    for (int o = 4; o < 16; ++o) t.u8[m][o] = 0x80;
  }
  return t;
}

inline constexpr PackTable kPack = make_pack_table();

}  // namespace cohdem
