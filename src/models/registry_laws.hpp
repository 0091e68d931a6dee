// The registry's presets that take a rolling model, listed once (COHDEM_ROLLING_LAWS) for
// registry.cpp's table and for registry_sds.cpp, which instantiates their SDS forms in a
// translation unit of their own: every law compiles the whole force loop, and apart from
// registry.cpp (the longest file of the build) the build compiles them side by side.
#pragma once
#include <memory>
#include <string>

#include "models/registry.hpp"

/// X(name, normal, damping, tangential) for each preset with a rolling slot (Walton, whose
/// bending fills it, is registry.cpp's own row). The adhesive and elasto-plastic laws' headers
/// say why their damping and tangential partners were chosen (docs/contact-models.md).
#define COHDEM_ROLLING_LAWS(X)                                                      \
  X("linear", LinearNormal, LinearRestitutionDamping, LinearTangential)             \
  X("hertz_mindlin", HertzNormal, TsujiDamping, MindlinTangential)                  \
  X("mepa", MepaNormal, ViscousDamping, HystTangential<MepaNormal>)                 \
  X("luding", LudingNormal, ViscousDamping, HystTangential<LudingNormal>)           \
  X("eepa", EepaNormal, RatioDamping, HystTangential<EepaNormal>)                   \
  X("jkr", JkrNormal, TsujiDamping, MindlinTangential)                              \
  X("dmt", DmtNormal, TsujiDamping, MindlinTangential)

namespace cohdem {

/// ContactModelImpl<ContactLaw<N, D, T, SdsRolling, W>> named `name`; registry_sds.cpp
/// instantiates it for each row of COHDEM_ROLLING_LAWS.
template <class N, class D, class T, class W>
std::unique_ptr<ContactModel> make_sds_law(const std::string& name);

}  // namespace cohdem
