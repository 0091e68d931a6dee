// Helpers for single-contact tests: a configured model for one species pair, path building
// for the driver, and loop integrals.
#pragma once
#include <array>
#include <cmath>
#include <initializer_list>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "contact/driver.hpp"
#include "models/registry.hpp"

namespace cohdem::testing {

inline ParamSet pset(std::initializer_list<std::pair<const char*, double>> kv) {
  ParamSet p;
  for (auto& [k, v] : kv) p.set(k, v);
  return p;
}

/// A preset with one material pair (E, nu on both sides) and the given parameters.
inline std::unique_ptr<ContactModel> one_pair_model(const std::string& name, const std::string& rolling,
                                                    const ParamSet& ps, double E = 1e9, double nu = 0.3,
                                                    bool wall = false) {
  auto m = make_contact_model(name, rolling);
  m->set_params(1, {ps}, {PairMaterial::make(E, nu, E, nu, wall)});
  return m;
}

/// Builds a driver path piecewise: each call moves one column linearly to `target` in
/// `steps` rows (the last row hits the target exactly); the other columns hold.
class PathBuilder {
 public:
  enum Col { Delta = 0, Xi = 1, Theta = 2, Phi = 3 };
  PathBuilder& go(Col c, double target, int steps) {
    const double from = cur_[c];
    for (int k = 1; k <= steps; ++k) {
      cur_[c] = k == steps ? target : from + (target - from) * double(k) / steps;
      push();
    }
    return *this;
  }
  PathBuilder& to(double delta, int steps) { return go(Delta, delta, steps); }
  /// One row at overlap `delta` (a jump: the hysteretic laws are rate-independent).
  PathBuilder& at(double delta) {
    cur_[Delta] = delta;
    push();
    return *this;
  }
  size_t size() const { return p_.delta.size(); }
  const PathTable& table() const { return p_; }

 private:
  void push() {
    p_.delta.push_back(cur_[0]);
    p_.xi.push_back(cur_[1]);
    p_.theta.push_back(cur_[2]);
    p_.phi.push_back(cur_[3]);
  }
  std::array<double, 4> cur_{0, 0, 0, 0};
  PathTable p_;
};

using Rows = std::vector<std::vector<double>>;

/// Index of a driver column by name (-1 if absent).
inline int column(const ContactModel& m, const std::string& name) {
  const auto c = driver_columns(m);
  for (size_t k = 0; k < c.size(); ++k)
    if (c[k] == name) return int(k);
  return -1;
}

/// Work done on the contact, sum of y dx by the trapezoid rule over rows [from, to]:
/// for a closed loop (the path returns to its start) this is the energy dissipated.
inline double path_work(const Rows& r, int cx, int cy, size_t from, size_t to) {
  double w = 0;
  for (size_t k = from + 1; k <= to; ++k) w += 0.5 * (r[k][cy] + r[k - 1][cy]) * (r[k][cx] - r[k - 1][cx]);
  return w;
}

}  // namespace cohdem::testing
