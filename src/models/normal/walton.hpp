// Walton's plastic-cohesive normal model (seed 001, "Normal force model (linearized form)").
//
//   loading (new maximum)    F_R = K'_R alpha,          K'_R = sf 2 pi Y (2 R*) (walton/common.hpp)
//   unloading / reloading    F_R = max(0, K2 (alpha - alpha_p)),  alpha_p = alpha_max - F_Rmax / K2
//   attraction               -Fc, Fc = Fc0 + cf F_Rmax   (build-up with the largest load)
//   total                    f = F_R - Fc
// State: alpha_max, alpha_p and Fc of the contact (recomputed only when alpha_max grows).
//
// OPEN points, decided (docs/contact-models.md):
//  - K2: `K2` > 0 sets it (N/m). K2 = 0 (default) takes the slope of a Hertzian unloading
//    curve from F_Rmax for a sphere flattened to `flat` times its radius (R_f = flat R*,
//    default 2 as the paper suggests): initial slope 2 E* (3 F_Rmax R_f / (4 E*))^(1/3)
//    (k2_slope = 0, default) or the average slope, 2/3 of it (k2_slope = 1). K2 depends on
//    F_Rmax, so it is fixed per loading history. K2 is never below K'_R: at small loads
//    (below yield) the Hertz estimate is softer than the plastic line, and the contact then
//    unloads along the loading line (elastic, no dissipation).
//  - Attraction range: the attraction is constant while the contact lives; the contact forms
//    at touch (alpha > 0: snap-in to -Fc, zero-range cohesion as in JKR) and breaks when
//    alpha <= -gap_c (default 0: at zero overlap). reach() = gap_c.
//  - Friction base (Walton tangential: mu F_R): F_R = f + Fc, the repulsion (no damping).
//  - NormalOut::kn = K2 (the stiffest slope), a = sqrt(2 R* alpha) (truncation geometry),
//    f_adh = Fc (read by the bending and twisting limits).
#pragma once
#include <algorithm>
#include <array>
#include <cmath>

#include "models/normal/base.hpp"
#include "models/walton/common.hpp"

namespace cohdem {

struct WaltonNormal : NormalBase {
  struct Params { double Y, sf, Fc0, cf, K2, flat, gap_c, Estar; bool k2_avg; };
  struct State {
    double amax = 0;  ///< largest overlap, m (0: no contact yet)
    double ap = 0;    ///< plastic overlap where the repulsion vanishes, m
    double fc = 0;    ///< current pull-off force Fc0 + cf F_Rmax, N
  };
  static void flip(State&) {}  ///< overlaps and pull-off force: the same seen from either particle
  static constexpr std::array specs = {
      kWaltonY, kWaltonSf,
      req("Fc0", "N", 0, kInf, "pull-off force of a fresh contact"),
      opt("cf", "-", 0.0, 0, kInf, "build-up: Fc = Fc0 + cf F_Rmax"),
      opt("K2", "N/m", 0.0, 0, kInf, "elastic unloading stiffness (0: Hertz unloading of a flattened sphere)"),
      opt("flat", "-", 2.0, 0, kInf, "flattening: unloading radius R_f = flat R* (K2 = 0)", true),
      opt("k2_slope", "0/1", 0, 0, 1, "Hertz unloading slope: 0 initial, 1 average (= 2/3 initial)"),
      opt("gap_c", "m", 0.0, 0, kInf, "separation beyond touching at which the contact breaks")};
  static Params make(const ParamSet& p, const PairMaterial& m) {
    return {p.get(specs[0]), p.get(specs[1]), p.get(specs[2]), p.get(specs[3]), p.get(specs[4]),
            p.get(specs[5]), p.get(specs[7]), m.Estar, p.get(specs[6]) != 0};
  }
  static constexpr std::array<const char*, 3> state_columns = {"amax", "ap", "Fc"};
  static void state_values(const Params&, const State& s, double* out) {
    out[0] = s.amax; out[1] = s.ap; out[2] = s.fc;
  }
  static double reach(const Params& p, double) { return p.gap_c; }

  /// Unloading stiffness after a largest repulsion F_Rmax.
  static double k2_of(const Params& p, double fr_max, double rstar, double kr) {
    double k2 = p.K2;
    if (k2 <= 0) {
      k2 = 2.0 * p.Estar * std::cbrt(3.0 * fr_max * p.flat * rstar / (4.0 * p.Estar));
      if (p.k2_avg) k2 *= 2.0 / 3.0;
    }
    return std::max(k2, kr);
  }

  COHDEM_INLINE static void apply(const Params& p, const PairGeom& g, State& s, NormalOut& o) {
    const double d = g.delta;
    if (s.amax <= 0 ? !(d > 0) : d <= -p.gap_c) { o.alive = false; return; }
    o.alive = true;
    const double kr = walton_kr(p.Y, p.sf, g.rstar);
    if (d > s.amax) {  // plastic loading: new maximum
      const double fr_max = kr * d;
      s.amax = d;
      s.ap = d - fr_max / k2_of(p, fr_max, g.rstar, kr);
      s.fc = p.Fc0 + p.cf * fr_max;
    }
    const double k2 = kr * s.amax / (s.amax - s.ap);
    const double fr = d > s.ap ? k2 * (d - s.ap) : 0.0;
    o.f_el = fr - s.fc;
    o.f_adh = s.fc;
    o.kn = k2;
    o.a = std::sqrt(2.0 * g.rstar * std::max(d, 0.0));
  }
  template <class P>
  COHDEM_INLINE static double coulomb_base(const P&, const NormalOut& o, double) {
    return std::max(o.f_el + o.f_adh, 0.0);
  }
};

}  // namespace cohdem
