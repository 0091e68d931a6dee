// ContactModelImpl<Law>: the type-erased face of one compiled ContactLaw. compute() is
// defined in sim/force_kernel.hpp (it needs the particle and pair-list types).
#pragma once
#include <cstring>
#include <string>
#include <vector>

#include "models/contact_law.hpp"
#include "models/registry.hpp"
#include "sim/lanes.hpp"

namespace cohdem {

template <class Law>
class ContactModelImpl final : public ContactModel {
 public:
  using Params = typename Law::Params;
  using State = typename Law::State;
  static_assert(std::is_trivially_copyable_v<State>, "contact history must be plain data");

  explicit ContactModelImpl(std::string name) : name_(std::move(name)) {}
  const std::string& name() const override { return name_; }
  std::vector<ParamSpec> specs() const override { return Law::specs(); }
  size_t state_size() const override { return sizeof(State); }
  void set_params(int n, const std::vector<ParamSet>& sets, const std::vector<PairMaterial>& mats) override {
    n_ = n;
    params_.clear();
    params_.reserve(size_t(n) * n);
    for (int k = 0; k < n * n; ++k) params_.push_back(Law::make(sets[k], mats[k]));
    // The lanes' reading of the pairs' parameters (sim/lanes.hpp), once per parameter set;
    // empty, so the scalar law runs, when the law has no lanes or a pair's settings are not
    // theirs.
    lanes_.clear();
    if constexpr (LaneLaw<Law>::kHave) {
      for (const Params& q : params_) {
        if (!LaneLaw<Law>::usable(q)) {
          lanes_.clear();
          break;
        }
        lanes_.push_back(lane_params(q));
      }
    }
  }
  double reach(int i, int j, double rstar) const override { return Law::reach(p(i, j), rstar); }
  NormalOut normal_at(int i, int j, const PairGeom& g) const override {
    typename Law::Normal::State s{};
    NormalOut no;
    Law::Normal::apply(p(i, j).normal, g, s, no);
    return no;
  }
  bool evaluate(int i, int j, const PairGeom& g, void* state, PairForce& out) const override {
    State s;
    std::memcpy(&s, state, sizeof(State));
    const bool alive = Law::evaluate(p(i, j), g, s, out);
    std::memcpy(state, &s, sizeof(State));
    return alive;
  }
  FlipFn flipper() const override { return &flip_history; }
  static void flip_history(void* state) {
    State s;
    std::memcpy(&s, state, sizeof(State));
    Law::flip(s);
    std::memcpy(state, &s, sizeof(State));
  }
  std::vector<std::string> state_names() const override { return Law::state_names(); }
  void state_values(int i, int j, const void* state, double* out) const override {
    State s;
    std::memcpy(&s, state, sizeof(State));
    Law::state_values(p(i, j), s, out);
  }
  void compute(ForceContext& ctx) const override;

  const Params& p(int i, int j) const { return params_[size_t(i) * n_ + j]; }
  int n() const { return n_; }

 private:
  /// The wall contacts of particle i, added to F and T in wall-entry order (the force loop's
  /// pass 2; out of line, sim/force_kernel.hpp).
  __attribute__((noinline)) void wall_contacts(ForceContext& c, long i, Vec3& F, Vec3& T) const;
  std::string name_;
  int n_ = 0;
  std::vector<Params> params_;
  std::vector<typename LaneLaw<Law>::Params> lanes_;
};

}  // namespace cohdem
