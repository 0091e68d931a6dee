// The contact network of a state, for ParaView ("stress trees", Walton seed 001): one line per
// live contact, from centre to centre (pairs; periodic partners at their image position) or
// from the centre to the contact point (walls), with the normal force, the force vector, the
// contact radius and, with [thermal], the conductance.
#pragma once
#include "io/vtk.hpp"
#include "sim/system.hpp"

namespace cohdem {

/// Line cells with cell data: kind (0 pair, 1 wall), normal_force (N, repulsive > 0),
/// force (on the first particle, N), contact_radius (m), conductance (W/K; 0 without thermal).
VtuData contact_network_vtu(const System& s);

struct ContactForceStats {
  double max = 0, mean = 0;  ///< normal force over live particle-particle contacts, N
  size_t count = 0;
};
ContactForceStats pair_force_stats(const System& s);

}  // namespace cohdem
