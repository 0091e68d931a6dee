#include "particles/particle_store.hpp"

#include <algorithm>

namespace cohdem {

namespace {
template <class T>
void apply_perm(std::vector<T>& a, const std::vector<uint32_t>& perm, std::vector<T>& tmp) {
  tmp.resize(a.size());
  for (size_t k = 0; k < perm.size(); ++k) tmp[k] = a[perm[k]];
  a.swap(tmp);
}
template <class T>
void compact(std::vector<T>& a, const std::vector<uint8_t>& remove) {
  size_t w = 0;
  for (size_t r = 0; r < a.size(); ++r)
    if (!remove[r]) a[w++] = a[r];
  a.resize(w);
}
}  // namespace

void ParticleStore::enable_thermal(const double T0) {
  const size_t n = size();
  if (radius0.size() != n) {  // those it has are kept (a checkpoint's, a case table's)
    const size_t have = std::min(radius0.size(), n);
    radius0.resize(n);
    for (size_t i = have; i < n; ++i) radius0[i] = radius[i];
  }
  if (temperature.size() != n) temperature.resize(n, T0);
  if (heat_flow.size() != n) heat_flow.resize(n, 0.0);
  thermal_ = true;
}

void ParticleStore::disable_thermal() {
  thermal_ = false;
  for (auto* a : {&radius0, &temperature, &heat_flow}) std::vector<double>().swap(*a);
}

void ParticleStore::permute(const std::vector<uint32_t>& perm) {
  std::vector<uint64_t> tu;
  std::vector<int32_t> ti;
  std::vector<uint8_t> tb;
  std::vector<double> td;
  std::vector<Vec3> tv;
  apply_perm(id, perm, tu);
  apply_perm(species, perm, ti);
  for (auto* a : body_array()) apply_perm(*a, perm, ti);
  apply_perm(flag, perm, tb);
  for (auto* a : {&radius, &mass, &inertia}) apply_perm(*a, perm, td);
  for (auto* a : thermal_arrays()) apply_perm(*a, perm, td);
  for (auto* a : {&x, &v, &omega, &force, &torque}) apply_perm(*a, perm, tv);
}

void ParticleStore::resize(size_t n) {
  id.resize(n); species.resize(n); flag.resize(n);
  for (auto* a : body_array()) a->resize(n, -1);
  for (auto* a : {&radius, &mass, &inertia}) a->resize(n);
  for (auto* a : thermal_arrays()) a->resize(n);
  for (auto* a : {&x, &v, &omega, &force, &torque}) a->resize(n);
}

void ParticleStore::reserve(size_t n) {
  id.reserve(n); species.reserve(n); flag.reserve(n);
  for (auto* a : body_array()) a->reserve(n);
  for (auto* a : {&radius, &mass, &inertia}) a->reserve(n);
  for (auto* a : thermal_arrays()) a->reserve(n);
  for (auto* a : {&x, &v, &omega, &force, &torque}) a->reserve(n);
}

void ParticleStore::shrink_to_fit() {
  id.shrink_to_fit(); species.shrink_to_fit(); flag.shrink_to_fit(); body.shrink_to_fit();
  for (auto* a : {&radius, &mass, &inertia}) a->shrink_to_fit();
  for (auto* a : thermal_arrays()) a->shrink_to_fit();
  for (auto* a : {&x, &v, &omega, &force, &torque}) a->shrink_to_fit();
}

void ParticleStore::erase_if_flagged(const std::vector<uint8_t>& remove) {
  compact(id, remove); compact(species, remove); compact(flag, remove);
  for (auto* a : body_array()) compact(*a, remove);
  for (auto* a : {&radius, &mass, &inertia}) compact(*a, remove);
  for (auto* a : thermal_arrays()) compact(*a, remove);
  for (auto* a : {&x, &v, &omega, &force, &torque}) compact(*a, remove);
}

}  // namespace cohdem
