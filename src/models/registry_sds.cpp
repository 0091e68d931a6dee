// The laws of registry.cpp's table with SDS rolling resistance (registry_sds.hpp).
#include "models/registry_sds.hpp"

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

// One line per law of the table (a law missing here fails at the link).
template std::unique_ptr<ContactModel> make_sds_law<LinearNormal, LinearRestitutionDamping, LinearTangential, NoTwisting>(const std::string&);
template std::unique_ptr<ContactModel> make_sds_law<HertzNormal, TsujiDamping, MindlinTangential, NoTwisting>(const std::string&);
template std::unique_ptr<ContactModel> make_sds_law<MepaNormal, ViscousDamping, HystTangential<MepaNormal>, NoTwisting>(const std::string&);
template std::unique_ptr<ContactModel> make_sds_law<LudingNormal, ViscousDamping, HystTangential<LudingNormal>, NoTwisting>(const std::string&);
template std::unique_ptr<ContactModel> make_sds_law<EepaNormal, RatioDamping, HystTangential<EepaNormal>, NoTwisting>(const std::string&);
template std::unique_ptr<ContactModel> make_sds_law<JkrNormal, TsujiDamping, MindlinTangential, NoTwisting>(const std::string&);
template std::unique_ptr<ContactModel> make_sds_law<DmtNormal, TsujiDamping, MindlinTangential, NoTwisting>(const std::string&);

}  // namespace cohdem
