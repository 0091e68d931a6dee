// Helpers to build small systems in tests without a case file.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "models/registry.hpp"
#include "sim/system.hpp"

namespace cohdem::testing {

/// A system with the given materials, model and one parameter set used for every pair.
inline std::unique_ptr<System> make_system(std::vector<Material> mats, const std::string& model,
                                           const std::string& rolling, const ParamSet& params, double dt,
                                           Vec3 gravity = {0, 0, 0}, double skin = 1e-3) {
  auto s = std::make_unique<System>();
  s->materials = std::move(mats);
  s->cfg.dt = dt;
  s->cfg.gravity = gravity;
  s->cfg.skin = skin;
  const size_t n = s->materials.size();
  std::vector<ParamSet> sets(n * n, params);
  s->set_model(make_contact_model(model, rolling), sets);
  return s;
}

inline ParamSet params(std::initializer_list<std::pair<const char*, double>> kv) {
  ParamSet p;
  for (auto& [k, v] : kv) p.set(k, v);
  return p;
}

inline Wall plane(const Vec3& point, const Vec3& normal, int material) {
  Wall w;
  w.name = "plane";
  w.shape = WallShape::Plane;
  w.point = point;
  w.normal = normalized(normal);
  w.material = material;
  return w;
}

}  // namespace cohdem::testing
