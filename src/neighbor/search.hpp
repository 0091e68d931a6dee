// The list build's pair search, four candidates at a time (src/neighbor/neighbor_list.cpp,
// step 4): `search_avx2` tests one particle against the candidate ranges of its half
// stencil, reading the candidates' positions and radii from copies in cell order (one
// contiguous run per range, instead of one particle's scattered records per candidate).
// It computes what the portable loop computes, in the same order and without fused
// multiply-adds (xs = x_a - shift, d = xs - x_b, d2 = (dx dx + dy dy) + dz dz,
// rc = r_a' + r_b, a pair when d2 < rc^2 and not both bodies fixed), and writes the same keys
// and images in the same order, so the lists are the same bit for bit
// (tests/unit/test_neighbor.cpp). Compiled for AVX2 alone and called only where the CPU has
// it (and `COHDEM_SIMD` is not 0: the switch the force loop's screening follows).
#pragma once
#include <cstddef>
#include <cstdint>

#include "core/vec3.hpp"

namespace cohdem {

/// The candidates in cell order (index t of the build's cell list): position, radius and
/// the particle's own index, each array with kSearchPad entries past the last particle, which
/// the last group of a range may read (they are never picked; their index is a valid one).
/// The particles' flags (by particle index) are read only for a fixed particle's candidates.
struct SearchInput {
  const double* x;
  const double* y;
  const double* z;
  const double* r;
  const uint32_t* index;
  const uint8_t* flag;  ///< ParticleStore::flag
  const Vec3* shift;    ///< image translations by image code (NeighborList::shift)
};
inline constexpr size_t kSearchPad = 4;

/// Particle a (at xa, with ra = r_a + skin + reach; fixed_a: not kFree) against the
/// candidates [q0[r], q1[r]) of each range r < nr, seen under image img[r]: each pair found
/// is appended at k as a key (lower index << 32 | higher) and the image of the higher seen
/// from the lower, in candidate order. Writes up to three entries past the last one it keeps
/// (room for them is the caller's). Returns the new count.
size_t search_avx2(const SearchInput& s, uint32_t a, const Vec3& xa, double ra, bool fixed_a, int nr,
                   const uint32_t* q0, const uint32_t* q1, const uint8_t* img, uint64_t* key, uint8_t* image,
                   size_t k);

}  // namespace cohdem
