// The one place where contact-law presets are registered: one row per preset.
#include "models/registry.hpp"

#include <functional>
#include <map>

#include "models/damping/restitution.hpp"
#include "models/normal/hertz.hpp"
#include "models/normal/linear.hpp"
#include "models/rolling/rolling.hpp"
#include "models/tangential/spring.hpp"
#include "models/twisting/twisting.hpp"
#include "sim/force_kernel.hpp"

namespace cohdem {

namespace {

using Factory = std::function<std::unique_ptr<ContactModel>(const std::string& rolling)>;

/// Instantiates a law for each rolling choice (the rolling model is a compile-time slot).
template <class N, class D, class T, class W = NoTwisting>
Factory with_rolling(const std::string& name) {
  return [name](const std::string& rolling) -> std::unique_ptr<ContactModel> {
    if (rolling == "none") return std::make_unique<ContactModelImpl<ContactLaw<N, D, T, NoRolling, W>>>(name);
    if (rolling == "epsd") return std::make_unique<ContactModelImpl<ContactLaw<N, D, T, EpsdRolling, W>>>(name);
    if (rolling == "cdt") return std::make_unique<ContactModelImpl<ContactLaw<N, D, T, CdtRolling, W>>>(name);
    return nullptr;
  };
}

const std::map<std::string, Factory>& table() {
  static const std::map<std::string, Factory> t = {
      // name            normal        damping                   tangential
      {"linear", with_rolling<LinearNormal, LinearRestitutionDamping, LinearTangential>("linear")},
      {"hertz_mindlin", with_rolling<HertzNormal, TsujiDamping, MindlinTangential>("hertz_mindlin")},
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

std::vector<std::string> rolling_model_names() { return {"none", "epsd", "cdt"}; }

std::unique_ptr<ContactModel> make_contact_model(const std::string& model, const std::string& rolling,
                                                 const std::string& file, int line) {
  auto it = table().find(model);
  if (it == table().end())
    throw InputError(file, line, "contact.model",
                     "unknown contact model '" + model + "'; expected one of: " + join(contact_model_names()));
  auto m = it->second(rolling);
  if (!m)
    throw InputError(file, line, "contact.rolling",
                     "unknown rolling model '" + rolling + "'; expected one of: " + join(rolling_model_names()));
  return m;
}

}  // namespace cohdem
