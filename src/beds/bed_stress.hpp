// Coarse-grained stresses in horizontal slices of a bed in a vertical pipe (axis along z), for
// the Janssen checks: the vertical stress, the mean horizontal stress, and the normal and shear
// stresses on the pipe wall, each against height (docs/packed-beds.md).
//
// Slice average of the contact stress (Irving-Kirkwood line form; e.g. Weinhart et al. 2012):
//   sigma_ab = 1/V sum_c f_a l_b w_c,
// f the force on the particle, l its branch vector (pair: x_i - x_j; wall: x_i - contact point),
// w_c the fraction of the branch segment inside the slice (the whole contact when the branch is
// horizontal and its height is inside). Compression positive. Wall stresses from the contacts on
// the pipe wall whose contact points lie in the slice, over the wall area 2 pi R dz: normal
// (pushing the wall outward, positive) and shear (the vertical force of the wall on the bed,
// upward positive).
#pragma once
#include <vector>

#include "sim/system.hpp"

namespace cohdem::beds {

struct SliceStresses {
  std::vector<double> edges;       ///< slice bounds in z, m
  std::vector<double> sigma_v;     ///< sigma_zz, Pa
  std::vector<double> sigma_h;     ///< (sigma_xx + sigma_yy)/2, Pa
  std::vector<double> wall_normal; ///< Pa
  std::vector<double> wall_shear;  ///< Pa, upward on the bed positive
  std::vector<double> fraction;    ///< solids fraction
  double centre(size_t i) const { return 0.5 * (edges[i] + edges[i + 1]); }
  /// Element-wise sum (for averaging over samples).
  void accumulate(const SliceStresses& o, double weight);
  void scale(double f);
};

/// Slices of equal height between z_lo and z_hi in the pipe (wall index `pipe`, a cylinder
/// with its axis along z) of cross-section pi R^2.
SliceStresses slice_stresses(const System& s, size_t pipe, double z_lo, double z_hi, int nbins);

}  // namespace cohdem::beds
