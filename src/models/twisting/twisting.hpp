// Twisting sub-models (moment about the normal). NoTwisting is the default; Walton's
// twisting spring lives with his model (models/walton).
#pragma once
#include <array>

#include "models/pair.hpp"
#include "models/params.hpp"

namespace cohdem {

struct NoTwisting {
  struct Params {};
  struct State {};
  static constexpr bool kNone = true;  // no moment: ContactLaw leaves its (zero) terms out
  static constexpr std::array<ParamSpec, 0> specs{};
  static Params make(const ParamSet&, const PairMaterial&) { return {}; }
  /// Returns the twisting moment on i about n (N m).
  COHDEM_INLINE static double apply(const Params&, const PairGeom&, const NormalOut&, double, State&) {
    return 0.0;
  }
};

}  // namespace cohdem
