// The definition of make_law (registry_laws.hpp) and COHDEM_INSTANTIATE_ROLLING(R), which
// instantiates it for every row of COHDEM_ROLLING_LAWS with rolling model R: included only
// by registry_<rolling>.cpp, one translation unit per rolling model.
#pragma once
#include "models/damping/ratio.hpp"
#include "models/damping/restitution.hpp"
#include "models/normal/dmt.hpp"
#include "models/normal/hertz.hpp"
#include "models/normal/jkr.hpp"
#include "models/normal/linear.hpp"
#include "models/normal/mepa.hpp"
#include "models/registry_laws.hpp"
#include "models/rolling/rolling.hpp"
#include "models/tangential/spring.hpp"
#include "models/twisting/twisting.hpp"
#include "sim/force_kernel.hpp"

namespace cohdem {

template <class N, class D, class T, class R, class W>
std::unique_ptr<ContactModel> make_law(const std::string& name) {
  return std::make_unique<ContactModelImpl<ContactLaw<N, D, T, R, W>>>(name);
}

}  // namespace cohdem

#define COHDEM_INSTANTIATE_ONE_(name, N, D, T) \
  template std::unique_ptr<ContactModel> make_law<N, D, T, RollingOfThisFile, NoTwisting>(const std::string&);
/// Instantiates make_law<N, D, T, R, NoTwisting> for every preset (inside namespace cohdem).
#define COHDEM_INSTANTIATE_ROLLING(R)                \
  namespace cohdem {                                 \
  using RollingOfThisFile = R;                       \
  COHDEM_ROLLING_LAWS(COHDEM_INSTANTIATE_ONE_)       \
  }
