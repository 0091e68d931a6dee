// The registry's laws with SDS rolling resistance (rolling = "sds"), instantiated in their
// own translation unit, registry_sds.cpp: every law compiles the whole force loop, and apart
// from registry.cpp the build compiles them side by side (registry.cpp alone is the longest
// file of the build).
#pragma once
#include <memory>
#include <string>

#include "models/registry.hpp"

namespace cohdem {

/// ContactModelImpl<ContactLaw<N, D, T, SdsRolling, W>> named `name`; registry_sds.cpp
/// instantiates it for each law of the registry's table that takes a rolling model.
template <class N, class D, class T, class W>
std::unique_ptr<ContactModel> make_sds_law(const std::string& name);

}  // namespace cohdem
