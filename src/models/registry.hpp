// The contact-model registry: a preset name ("linear", "hertz_mindlin", "mepa", ...) and a
// rolling choice ("none", "epsd", "cdt", "sds") select one compiled ContactLaw. The choice is made
// once per run, never per pair. To add a model: write its sub-model header(s), then add one
// row to COHDEM_ROLLING_LAWS (registry_laws.hpp), or to registry.cpp's table for a law whose
// rolling slot is its own (Walton). A rolling model: its header, a registry_<name>.cpp like
// registry_epsd.cpp, and its line in registry.cpp's with_rolling.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "models/pair.hpp"
#include "models/params.hpp"

namespace cohdem {

struct ForceContext;  // sim/force_context.hpp: particles, pair list, walls of one step

class ContactModel {
 public:
  virtual ~ContactModel() = default;
  virtual const std::string& name() const = 0;
  /// Every parameter key the law reads (union of its sub-models).
  virtual std::vector<ParamSpec> specs() const = 0;
  /// Bytes of history per contact (the law's State).
  virtual size_t state_size() const = 0;
  /// Builds the parameter table for `n` materials (species then wall materials):
  /// sets[i*n+j] and mats[i*n+j] describe the pair (i, j). Throws InputError on bad values.
  virtual void set_params(int n, const std::vector<ParamSet>& sets, const std::vector<PairMaterial>& mats) = 0;
  /// Largest tensile gap (m) at which a live contact of pair (i, j) can still act.
  virtual double reach(int i, int j, double rstar) const = 0;
  /// Tangent stiffness scale for the time-step audit: normal force and stiffness at overlap
  /// `delta` (used by `cohdem check`).
  virtual NormalOut normal_at(int i, int j, const PairGeom& g) const = 0;
  /// One contact, for the single-contact driver and tests; `state` points to state_size()
  /// bytes (zeroed for a new contact). Returns false when there is no contact.
  virtual bool evaluate(int i, int j, const PairGeom& g, void* state, PairForce& out) const = 0;
  /// The function that rewrites one contact's history (state_size() bytes) as seen from the
  /// other particle, the history of pair (j, i) from that of (i, j): a plain function, for
  /// the neighbor list, which knows no models.
  using FlipFn = void (*)(void* state);
  virtual FlipFn flipper() const = 0;
  void flip_state(void* state) const { flipper()(state); }
  /// Names of the per-contact state columns the law exposes (e.g. MEPA: dmax, dp, branch).
  virtual std::vector<std::string> state_names() const = 0;
  /// Values of those columns for one contact of pair (i, j); `out` has state_names().size().
  virtual void state_values(int i, int j, const void* state, double* out) const = 0;
  /// The bulk force loop over all pairs and wall contacts of one step.
  virtual void compute(ForceContext& ctx) const = 0;
};

/// Creates a model by preset and rolling name; throws InputError naming `key` otherwise.
std::unique_ptr<ContactModel> make_contact_model(const std::string& model, const std::string& rolling,
                                                 const std::string& file = "", int line = 0);
/// Preset names, for help texts and error messages.
std::vector<std::string> contact_model_names();
std::vector<std::string> rolling_model_names();

}  // namespace cohdem
