// The registry's presets that take a rolling model, listed once (COHDEM_ROLLING_LAWS) for
// registry.cpp's table and for the files that instantiate them, one per rolling model
// (registry_none.cpp, registry_epsd.cpp, registry_cdt.cpp, registry_sds.cpp): every law
// compiles the whole force loop, and one file holding all of them was the build's critical
// path (182 s of a 273 s build on two cores); four files of about a quarter each compile
// side by side.
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

/// ContactModelImpl<ContactLaw<N, D, T, R, W>> named `name`. Defined and instantiated for
/// each row of COHDEM_ROLLING_LAWS in registry_<rolling>.cpp (registry_instance.hpp), so
/// that a translation unit including this header compiles no force loop.
template <class N, class D, class T, class R, class W>
std::unique_ptr<ContactModel> make_law(const std::string& name);

}  // namespace cohdem
