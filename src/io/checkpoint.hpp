// Atomic binary checkpoints of a running system, and restart from them bit for bit.
//
// A checkpoint is written at the end of a step in which the neighbor list was rebuilt, so a
// restart rebuilds exactly the same list from the saved positions, installs the saved
// contact history and continues with the saved forces: the continued run is bitwise equal to
// an uninterrupted one (tests/unit/test_checkpoint.cpp). The file holds the particles, the
// walls' moving state, pour progress, the random generator and every live contact's history.
#pragma once
#include <filesystem>
#include <string>

#include "sim/system.hpp"

namespace cohdem {

/// Writes the checkpoint atomically (temp file + rename).
void write_checkpoint(const std::filesystem::path& path, const System& s);

/// Restores a checkpoint into `s`, which must be built from the same case (materials, model,
/// walls, pours) without particles. Throws InputError if the file is not a checkpoint of the
/// same model, or is truncated.
void read_checkpoint(const std::filesystem::path& path, System& s);

}  // namespace cohdem
