// Parameters of a contact model, validated once when a case is loaded.
//
// Every sub-model lists its keys as ParamSpec rows (name, unit, default, valid range, doc).
// A ParamSet holds the values a user gave for one species pair (from the case file's
// [contact] table, a [[contact.pair]] override or `--set`), remembers where each came from,
// and `get` turns a missing/out-of-range value into an InputError naming file, line and key.
#pragma once
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "core/error.hpp"

namespace cohdem {

struct ParamSpec {
  const char* name;
  const char* unit;
  double def;          ///< default value (ignored when required)
  bool required;
  double min;          ///< valid range [min, max] (min_open: (min, max])
  double max;
  bool min_open;
  const char* doc;
};

inline constexpr double kInf = std::numeric_limits<double>::infinity();

/// Shorthand constructors for the spec tables.
constexpr ParamSpec opt(const char* n, const char* u, double def, double lo, double hi, const char* doc,
                        bool lo_open = false) {
  return {n, u, def, false, lo, hi, lo_open, doc};
}
constexpr ParamSpec req(const char* n, const char* u, double lo, double hi, const char* doc,
                        bool lo_open = false) {
  return {n, u, 0.0, true, lo, hi, lo_open, doc};
}

struct ParamOrigin {
  std::string file;
  int line = 0;
  std::string section;  ///< e.g. "contact" or "contact.pair[0]"
};

class ParamSet {
 public:
  void set(const std::string& key, double value, ParamOrigin where = {}) {
    values_[key] = value;
    origin_[key] = std::move(where);
  }
  bool has(const std::string& key) const { return values_.count(key) != 0; }
  const std::map<std::string, double>& values() const { return values_; }
  ParamOrigin origin(const std::string& key) const {
    auto it = origin_.find(key);
    return it == origin_.end() ? ParamOrigin{file_, 0, section_} : it->second;
  }
  /// Where this set as a whole comes from (used when a required key is missing).
  void set_context(std::string file, int line, std::string section) {
    file_ = std::move(file); line_ = line; section_ = std::move(section);
  }

  /// Value for `spec`, or its default; throws InputError when missing or out of range.
  double get(const ParamSpec& spec) const {
    auto it = values_.find(spec.name);
    if (it == values_.end()) {
      if (spec.required)
        throw InputError(file_, line_, section_.empty() ? spec.name : section_ + "." + spec.name,
                         std::string("missing required parameter (") + spec.doc + ", " + spec.unit + ")");
      return spec.def;
    }
    const double v = it->second;
    const bool low_ok = spec.min_open ? v > spec.min : v >= spec.min;
    if (!(low_ok && v <= spec.max)) {
      const auto o = origin(spec.name);
      throw InputError(o.file, o.line, o.section.empty() ? std::string(spec.name) : o.section + "." + spec.name,
                       "value " + num(v) + " out of range: expected " + (spec.min_open ? "(" : "[") +
                           num(spec.min) + ", " + num(spec.max) + "] " + spec.unit + " (" + spec.doc + ")");
    }
    return v;
  }

 private:
  static std::string num(double v) {
    if (v == kInf) return "inf";
    if (v == -kInf) return "-inf";
    char b[32];
    std::snprintf(b, sizeof b, "%g", v);
    return b;
  }
  std::map<std::string, double> values_;
  std::map<std::string, ParamOrigin> origin_;
  std::string file_, section_;
  int line_ = 0;
};

/// Material data of the two bodies in a species pair (walls have a material too).
struct PairMaterial {
  double E_i = 0, nu_i = 0, E_j = 0, nu_j = 0;  ///< Young's modulus Pa, Poisson ratio
  double Estar = 0;  ///< 1/E* = (1-nu_i^2)/E_i + (1-nu_j^2)/E_j
  double Gstar = 0;  ///< 1/G* = (2-nu_i)/G_i + (2-nu_j)/G_j   (Mindlin)
  bool wall = false;  ///< j is a wall

  static PairMaterial make(double Ei, double nui, double Ej, double nuj, bool wall) {
    PairMaterial m;
    m.E_i = Ei; m.nu_i = nui; m.E_j = Ej; m.nu_j = nuj; m.wall = wall;
    m.Estar = 1.0 / ((1 - nui * nui) / Ei + (1 - nuj * nuj) / Ej);
    const double Gi = Ei / (2 * (1 + nui)), Gj = Ej / (2 * (1 + nuj));
    m.Gstar = 1.0 / ((2 - nui) / Gi + (2 - nuj) / Gj);
    return m;
  }
};

}  // namespace cohdem
