// Strict reading of one TOML table: every key must be read (unknown keys are errors), and
// every error names the file, the line and the dotted key. Used by the case-file parser and
// by the apps that add their own tables ([ring_shear], ...).
#pragma once
#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/vec3.hpp"
#include "models/params.hpp"

namespace cohdem {

inline int line_of(const toml::node& n) { return int(n.source().begin.line); }

class Section {
 public:
  Section(const toml::table& t, std::string path, const std::string& file)
      : t_(t), path_(std::move(path)), file_(file) {}

  const std::string& path() const { return path_; }
  int line() const { return line_of(t_); }
  bool has(const std::string& k) const { return t_.contains(k); }
  std::string key(const std::string& k) const { return path_.empty() ? k : path_ + "." + k; }
  [[noreturn]] void fail(const std::string& k, const std::string& what) const {
    const toml::node* n = t_.get(k);
    throw InputError(file_, n ? line_of(*n) : line(), key(k), what);
  }

  double num(const std::string& k, std::optional<double> def, double lo = -kInf, double hi = kInf,
             bool lo_open = false, const char* unit = "") {
    used_.insert(k);
    const toml::node* n = t_.get(k);
    if (!n) {
      if (!def) fail(k, std::string("missing required key (a number") + (*unit ? std::string(", ") + unit : "") + ")");
      return *def;
    }
    double v;
    if (auto d = n->value_exact<double>()) v = *d;
    else if (auto i = n->value_exact<int64_t>()) v = double(*i);
    else fail(k, std::string("expected a number, got ") + type_name(*n));
    if (!std::isfinite(v)) fail(k, "expected a finite number");
    const bool ok_lo = lo_open ? v > lo : v >= lo;
    if (!ok_lo || v > hi) {
      std::ostringstream s;
      s << "value " << v << " out of range: expected " << (lo_open ? "> " : ">= ") << lo;
      if (hi < kInf) s << " and <= " << hi;
      if (*unit) s << " " << unit;
      fail(k, s.str());
    }
    return v;
  }
  int64_t integer(const std::string& k, std::optional<int64_t> def, int64_t lo = 0) {
    used_.insert(k);
    const toml::node* n = t_.get(k);
    if (!n) {
      if (!def) fail(k, "missing required key (an integer)");
      return *def;
    }
    auto i = n->value_exact<int64_t>();
    if (!i) fail(k, std::string("expected an integer, got ") + type_name(*n));
    if (*i < lo) fail(k, "value " + std::to_string(*i) + " out of range: expected >= " + std::to_string(lo));
    return *i;
  }
  std::string str(const std::string& k, std::optional<std::string> def,
                  const std::vector<std::string>& choices = {}) {
    used_.insert(k);
    const toml::node* n = t_.get(k);
    if (!n) {
      if (!def) fail(k, "missing required key (a string)");
      return *def;
    }
    auto s = n->value_exact<std::string>();
    if (!s) fail(k, std::string("expected a string, got ") + type_name(*n));
    if (!choices.empty() && std::find(choices.begin(), choices.end(), *s) == choices.end())
      fail(k, "unknown value '" + *s + "'; expected one of: " + join(choices));
    return *s;
  }
  bool boolean(const std::string& k, std::optional<bool> def) {
    used_.insert(k);
    const toml::node* n = t_.get(k);
    if (!n) {
      if (!def) fail(k, "missing required key (true or false)");
      return *def;
    }
    auto b = n->value_exact<bool>();
    if (!b) fail(k, std::string("expected true or false, got ") + type_name(*n));
    return *b;
  }
  std::vector<double> numbers(const std::string& k, std::optional<std::vector<double>> def, size_t count = 0) {
    used_.insert(k);
    const toml::node* n = t_.get(k);
    if (!n) {
      if (!def) fail(k, "missing required key (an array of numbers)");
      return *def;
    }
    const toml::array* a = n->as_array();
    if (!a) fail(k, std::string("expected an array of numbers, got ") + type_name(*n));
    std::vector<double> v;
    for (const auto& e : *a) {
      if (auto d = e.value_exact<double>()) v.push_back(*d);
      else if (auto i = e.value_exact<int64_t>()) v.push_back(double(*i));
      else fail(k, "expected an array of numbers");
      if (!std::isfinite(v.back())) fail(k, "expected finite numbers");
    }
    if (count && v.size() != count) fail(k, "expected " + std::to_string(count) + " numbers, got " + std::to_string(v.size()));
    return v;
  }
  Vec3 vec3(const std::string& k, std::optional<Vec3> def) {
    std::optional<std::vector<double>> d;
    if (def) d = std::vector<double>{def->x, def->y, def->z};
    auto v = numbers(k, d, 3);
    return {v[0], v[1], v[2]};
  }
  std::vector<std::string> strings(const std::string& k, std::optional<std::vector<std::string>> def) {
    used_.insert(k);
    const toml::node* n = t_.get(k);
    if (!n) {
      if (!def) fail(k, "missing required key (an array of strings)");
      return *def;
    }
    const toml::array* a = n->as_array();
    if (!a) fail(k, std::string("expected an array of strings, got ") + type_name(*n));
    std::vector<std::string> v;
    for (const auto& e : *a) {
      auto s = e.value_exact<std::string>();
      if (!s) fail(k, "expected an array of strings");
      v.push_back(*s);
    }
    return v;
  }
  std::optional<Section> table(const std::string& k, bool required = false) {
    used_.insert(k);
    const toml::node* n = t_.get(k);
    if (!n) {
      if (required) fail(k, "missing required table");
      return std::nullopt;
    }
    if (!n->is_table()) fail(k, std::string("expected a table, got ") + type_name(*n));
    return Section(*n->as_table(), key(k), file_);
  }
  std::vector<Section> tables(const std::string& k) {
    used_.insert(k);
    std::vector<Section> v;
    const toml::node* n = t_.get(k);
    if (!n) return v;
    const toml::array* a = n->as_array();
    if (!a) fail(k, std::string("expected an array of tables ([[") + k + "]]), got " + type_name(*n));
    int idx = 0;
    for (const auto& e : *a) {
      if (!e.is_table()) fail(k, "expected an array of tables");
      v.emplace_back(*e.as_table(), key(k) + "[" + std::to_string(idx++) + "]", file_);
    }
    return v;
  }
  /// Marks a key as consumed by someone else (e.g. contact parameters).
  void use(const std::string& k) { used_.insert(k); }
  std::vector<std::string> keys() const {
    std::vector<std::string> v;
    for (auto&& [k, n] : t_) v.emplace_back(k.str());
    return v;
  }
  const toml::node* node(const std::string& k) const { return t_.get(k); }
  /// Errors on the first key that was never read.
  void finish(const std::vector<std::string>& allowed_hint = {}) const {
    for (auto&& [k, n] : t_) {
      if (used_.count(std::string(k.str()))) continue;
      std::vector<std::string> exp(allowed_hint);
      if (exp.empty()) exp.assign(used_.begin(), used_.end());
      throw InputError(file_, line_of(n), key(std::string(k.str())),
                       "unknown key; expected one of: " + join(exp));
    }
  }
  static std::string join(const std::vector<std::string>& v) {
    std::string s;
    for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
    return s;
  }
  static const char* type_name(const toml::node& n) {
    switch (n.type()) {
      case toml::node_type::string: return "a string";
      case toml::node_type::integer: return "an integer";
      case toml::node_type::floating_point: return "a number";
      case toml::node_type::boolean: return "a boolean";
      case toml::node_type::array: return "an array";
      case toml::node_type::table: return "a table";
      default: return "a date/time";
    }
  }

 private:
  const toml::table& t_;
  std::string path_;
  const std::string& file_;
  std::set<std::string> used_;
};

}  // namespace cohdem
