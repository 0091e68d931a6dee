// The presets of COHDEM_ROLLING_LAWS with SDS rolling resistance (registry_laws.hpp).
#include "models/registry_laws.hpp"

#include "models/damping/ratio.hpp"
#include "models/damping/restitution.hpp"
#include "models/normal/dmt.hpp"
#include "models/normal/hertz.hpp"
#include "models/normal/jkr.hpp"
#include "models/normal/linear.hpp"
#include "models/normal/mepa.hpp"
#include "models/rolling/rolling.hpp"
#include "models/tangential/spring.hpp"
#include "models/twisting/twisting.hpp"
#include "sim/force_kernel.hpp"

namespace cohdem {

template <class N, class D, class T, class W>
std::unique_ptr<ContactModel> make_sds_law(const std::string& name) {
  return std::make_unique<ContactModelImpl<ContactLaw<N, D, T, SdsRolling, W>>>(name);
}

#define COHDEM_SDS_LAW(name, N, D, T) \
  template std::unique_ptr<ContactModel> make_sds_law<N, D, T, NoTwisting>(const std::string&);
COHDEM_ROLLING_LAWS(COHDEM_SDS_LAW)
#undef COHDEM_SDS_LAW

}  // namespace cohdem
