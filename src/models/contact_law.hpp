// A contact law chains five orthogonal sub-models (normal, damping, tangential, rolling or
// bending, twisting), each a stateless struct with plain-data Params and State and one
// static apply (see docs/contact-models.md and ../shared/DESIGN.md). The force loop is
// compiled once per law, so everything below inlines: no virtual calls per pair.
#pragma once
#include <string>
#include <type_traits>
#include <vector>

#include "models/pair.hpp"
#include "models/params.hpp"

namespace cohdem {

template <class N, class D, class T, class R, class W>
struct ContactLaw {
  using Normal = N;
  using Damping = D;
  using Tangential = T;
  using Rolling = R;
  using Twisting = W;
  // A tangential model that keeps no record of its stiffness (LinearTangential) needs a
  // normal law whose stiffness is fixed within a contact.
  static_assert(!requires { T::kNeedsFixedStiffness; } || requires { N::kFixedStiffness; },
                "this tangential model needs a normal law of fixed stiffness");
  // Mindlin's tangential damping takes sqrt(kt/kn) = sqrt(4 G*/E*) per material pair, which
  // holds for normal laws with kn = 2 E* a.
  static_assert(!requires { T::kNeedsHertzianStiffness; } || requires { N::kHertzianStiffness; },
                "this tangential model needs a normal law with kn = 2 E* a");

  struct Params {
    typename N::Params normal;
    typename D::Params damping;
    typename T::Params tangential;
    typename R::Params rolling;
    typename W::Params twisting;
  };
  /// History of one contact, seen from the particle that holds the pair's row (i). Empty
  /// sub-states take no room.
  struct State {
    [[no_unique_address]] typename N::State normal;
    [[no_unique_address]] typename D::State damping;
    [[no_unique_address]] typename T::State tangential;
    [[no_unique_address]] typename R::State rolling;
    [[no_unique_address]] typename W::State twisting;
  };

  /// The history as seen from the other particle, i and j exchanged (the neighbor list does
  /// this when a re-sort reverses which of the two holds the pair's row). Every sub-model with
  /// a history says how it reads from the other side (`static void flip(State&)`: a force or
  /// moment on i changes sign, overlaps and other scalars of the pair do not); one without
  /// flip() must keep none, checked here.
  static void flip(State& s) {
    auto one = [](auto* tag, auto& ss) {
      using X = std::remove_pointer_t<decltype(tag)>;
      if constexpr (requires { X::flip(ss); })
        X::flip(ss);
      else
        static_assert(std::is_empty_v<std::remove_reference_t<decltype(ss)>>,
                      "a sub-model with a history must say how it reads from the other particle (flip)");
    };
    one((N*)nullptr, s.normal);
    one((D*)nullptr, s.damping);
    one((T*)nullptr, s.tangential);
    one((R*)nullptr, s.rolling);
    one((W*)nullptr, s.twisting);
  }

  static std::vector<ParamSpec> specs() {
    std::vector<ParamSpec> v;
    auto add = [&](const auto& a) {
      for (const auto& s : a) {
        bool dup = false;
        for (const auto& e : v) dup = dup || std::string(e.name) == s.name;
        if (!dup) v.push_back(s);
      }
    };
    add(N::specs); add(D::specs); add(T::specs); add(R::specs); add(W::specs);
    return v;
  }

  static Params make(const ParamSet& p, const PairMaterial& m) {
    return {N::make(p, m), D::make(p, m), T::make(p, m), R::make(p, m), W::make(p, m)};
  }

  /// Named per-contact state columns (for the single-contact driver and contact output).
  /// A sub-model exposes columns with `static constexpr std::array<const char*, K>
  /// state_columns` and `static void state_values(const Params&, const State&, double* out)`.
  static std::vector<std::string> state_names() {
    std::vector<std::string> v;
    auto add = [&](auto* tag) {
      using X = std::remove_pointer_t<decltype(tag)>;
      if constexpr (requires { X::state_columns; })
        for (const char* c : X::state_columns) v.emplace_back(c);
    };
    add((N*)nullptr); add((D*)nullptr); add((T*)nullptr); add((R*)nullptr); add((W*)nullptr);
    return v;
  }
  static void state_values(const Params& p, const State& s, double* out) {
    auto put = [&](auto* tag, const auto& sp, const auto& ss) {
      using X = std::remove_pointer_t<decltype(tag)>;
      if constexpr (requires { X::state_columns; }) {
        X::state_values(sp, ss, out);
        out += X::state_columns.size();
      }
    };
    put((N*)nullptr, p.normal, s.normal);
    put((D*)nullptr, p.damping, s.damping);
    put((T*)nullptr, p.tangential, s.tangential);
    put((R*)nullptr, p.rolling, s.rolling);
    put((W*)nullptr, p.twisting, s.twisting);
  }

  /// Largest tensile separation (m, >= 0) at which a live contact still acts.
  static double reach(const Params& p, double rstar) { return N::reach(p.normal, rstar); }

  /// Evaluates one contact. Returns false (and resets the history) when there is none.
  COHDEM_INLINE static bool evaluate(const Params& p, const PairGeom& g, State& s, PairForce& out) {
    NormalOut no;
    N::apply(p.normal, g, s.normal, no);
    if (!no.alive) {
      s = State{};
      return false;
    }
    double gamma_n = 0;
    const double fd = D::apply(p.damping, g, no, gamma_n);
    const double fn = no.f_el + fd;
    const double fc = N::coulomb_base(p.normal, no, fn);
    const Vec3 ft = T::apply(p.tangential, g, no, gamma_n, fc, s.tangential);
    const Vec3 mr = R::apply(p.rolling, g, no, fc, s.rolling);
    const double mt = W::apply(p.twisting, g, no, fc, s.twisting);

    // Lever arms from each centre to the contact point: the middle of the overlap for two
    // spheres, the wall surface for a wall (rj == 0).
    const double li = g.rj > 0 ? g.ri - 0.5 * g.delta : g.ri - g.delta;
    const double lj = g.rj > 0 ? g.rj - 0.5 * g.delta : 0.0;
    const Vec3 nxft = cross(g.n, ft);
    const Vec3 mtw = g.n * mt;
    out.f = g.n * fn + ft;
    // ti = -li n x ft + mr + mtw, tj = -lj n x ft - mr - mtw, summed in that order. A
    // sub-model that never gives a moment (kNone) has its zero terms left out: adding +0 or
    // -0 can change only the sign of a zero, which the sums the torques go into (started at
    // +0) do not keep.
    out.ti = nxft * (-li);
    out.tj = nxft * (-lj);
    if constexpr (!requires { R::kNone; }) {
      out.ti += mr;
      out.tj -= mr;
    }
    if constexpr (!requires { W::kNone; }) {
      out.ti += mtw;
      out.tj -= mtw;
    }
    out.fn = fn;
    out.fn_el = no.f_el;
    out.ft = ft;
    out.mr = mr;
    out.mt = mt;
    out.a = no.a;
    return true;
  }
};

}  // namespace cohdem
