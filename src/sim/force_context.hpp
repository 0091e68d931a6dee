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
  // Per-pair results, valid where nl.hist.live[k]: the force on i (j gets its opposite) and
  // the torque on j; the kernel sums i's side directly (ti_pair is kept for callers that
  // want it but is not written by the bulk kernel).
  std::vector<Vec3>& f_pair;
  std::vector<Vec3>& ti_pair;
  std::vector<Vec3>& tj_pair;
  // Per wall entry: force on the particle, moment on the wall about the contact point,
  // contact point; valid where nl.whist.live[e].
  std::vector<Vec3>& f_wall;
  std::vector<Vec3>& tw_wall;
  std::vector<Vec3>& c_wall;
  /// Body-force acceleration added to every free particle after its contact forces, m/s^2.
  Vec3 gravity{};
  /// Below this many particles the kernel runs on one thread (fork/join costs more than it saves).
  long parallel_min = 0;
  /// Contact radius of each live pair (indexed like nl.jdx) and wall entry, when not null
  /// (conduction, contact network).
  double* a_pair = nullptr;
  double* a_wall = nullptr;
};

}  // namespace cohdem
