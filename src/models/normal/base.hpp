// Defaults shared by normal sub-models (static helpers, no virtual calls).
#pragma once
#include <algorithm>

#include "models/pair.hpp"
#include "models/params.hpp"

namespace cohdem {

struct NormalBase {
  struct State {};
  /// How far past touching (negative overlap, m) the model can still act on a live contact.
  template <class P>
  static double reach(const P&, double /*rstar*/) { return 0.0; }
  /// Normal force that bounds friction, rolling and twisting (Coulomb-type limits).
  template <class P>
  COHDEM_INLINE static double coulomb_base(const P&, const NormalOut&, double fn_total) {
    return std::max(fn_total, 0.0);
  }
};

}  // namespace cohdem
