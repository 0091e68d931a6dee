// Everything one force evaluation reads and writes.
#pragma once
#include <vector>

#include "neighbor/neighbor_list.hpp"
#include "particles/particle_store.hpp"
#include "walls/wall.hpp"

namespace cohdem {

struct ForceContext {
  ParticleStore& p;
  NeighborList& nl;
  const std::vector<Wall>& walls;
  double dt = 0, t = 0;
  // Per wall entry: force on the particle, moment on the wall about the contact point,
  // contact point; valid where nl.whist.live[e].
  std::vector<Vec3>& f_wall;
  std::vector<Vec3>& tw_wall;
  std::vector<Vec3>& c_wall;
  /// Body-force acceleration added to every free particle after its contact forces, m/s^2.
  Vec3 gravity{};
};

}  // namespace cohdem
