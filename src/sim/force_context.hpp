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
  // Per-pair results (force on i, torques on i and j), valid where nl.hist.live[k].
  std::vector<Vec3>& f_pair;
  std::vector<Vec3>& ti_pair;
  std::vector<Vec3>& tj_pair;
  // Per wall entry: force on the particle, moment on the wall about the contact point,
  // contact point; valid where nl.whist.live[e].
  std::vector<Vec3>& f_wall;
  std::vector<Vec3>& tw_wall;
  std::vector<Vec3>& c_wall;
  // Contact radius of each live pair / wall entry (conduction), when not null.
  double* a_pair = nullptr;
  double* a_wall = nullptr;
};

}  // namespace cohdem
