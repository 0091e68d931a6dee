// The one place where contact-law presets are registered: one row per preset.
#include "models/registry.hpp"

#include <algorithm>
#include <functional>
#include <map>

#include "models/damping/ratio.hpp"
#include "models/damping/restitution.hpp"
#include "models/normal/dmt.hpp"
#include "models/normal/hertz.hpp"
#include "models/normal/jkr.hpp"
#include "models/normal/linear.hpp"
#include "models/normal/mepa.hpp"
#include "models/normal/walton.hpp"
#include "models/registry_laws.hpp"
#include "models/rolling/rolling.hpp"
#include "models/tangential/spring.hpp"
#include "models/twisting/twisting.hpp"
#include "models/walton/bending.hpp"
#include "models/walton/tangential.hpp"
#include "sim/force_kernel.hpp"

namespace cohdem {

namespace {

using Factory = std::function<std::unique_ptr<ContactModel>(const std::string& rolling)>;

/// A law whose rolling slot is fixed (Walton: bending); accepts only rolling = "none".
template <class N, class D, class T, class R, class W>
Factory fixed_rolling(const std::string& name) {
  return [name](const std::string& rolling) -> std::unique_ptr<ContactModel> {
    if (rolling == "none") return std::make_unique<ContactModelImpl<ContactLaw<N, D, T, R, W>>>(name);
    return nullptr;
  };
}

/// Instantiates a law for each rolling choice (the rolling model is a compile-time slot).
template <class N, class D, class T, class W = NoTwisting>
Factory with_rolling(const std::string& name) {
  return [name](const std::string& rolling) -> std::unique_ptr<ContactModel> {
    // Each compiled in registry_<rolling>.cpp (registry_laws.hpp).
    if (rolling == "none") return make_law<N, D, T, NoRolling, W>(name);
    if (rolling == "epsd") return make_law<N, D, T, EpsdRolling, W>(name);
    if (rolling == "cdt") return make_law<N, D, T, CdtRolling, W>(name);
    if (rolling == "sds") return make_law<N, D, T, SdsRolling, W>(name);
    return nullptr;
  };
}

const std::map<std::string, Factory>& table() {
  static const std::map<std::string, Factory> t = {
#define COHDEM_TABLE_ROW(name, N, D, T) {name, with_rolling<N, D, T>(name)},
      COHDEM_ROLLING_LAWS(COHDEM_TABLE_ROW)
#undef COHDEM_TABLE_ROW
      // Walton: bending in the rolling slot, twisting in the twisting slot.
      {"walton", fixed_rolling<WaltonNormal, RatioDamping, WaltonTangential, WaltonBending, WaltonTwisting>("walton")},
  };
  return t;
}

std::string join(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}

}  // namespace

std::vector<std::string> contact_model_names() {
  std::vector<std::string> v;
  for (const auto& [k, f] : table()) v.push_back(k);
  return v;
}

std::vector<std::string> rolling_model_names() { return {"none", "epsd", "cdt", "sds"}; }

std::unique_ptr<ContactModel> make_contact_model(const std::string& model, const std::string& rolling,
                                                 const std::string& file, int line) {
  auto it = table().find(model);
  if (it == table().end())
    throw InputError(file, line, "contact.model",
                     "unknown contact model '" + model + "'; expected one of: " + join(contact_model_names()));
  auto m = it->second(rolling);
  if (!m) {
    const auto names = rolling_model_names();
    if (std::find(names.begin(), names.end(), rolling) != names.end())
      throw InputError(file, line, "contact.rolling",
                       "rolling model '" + rolling + "' cannot be used with contact model '" + model +
                           "', whose rolling slot is part of the model (walton: bending moment); expected: none");
    throw InputError(file, line, "contact.rolling",
                     "unknown rolling model '" + rolling + "'; expected one of: " + join(rolling_model_names()));
  }
  return m;
}

}  // namespace cohdem
