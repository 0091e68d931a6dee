// Atomic binary checkpoints of a running system, and restart from them bit for bit.
//
// A checkpoint may be written at the end of any step. It holds the particles, the walls'
// moving state, pour progress, the random generator, every live contact's history, the
// forces of the last step, and the state the neighbor list was last built from; a restart
// rebuilds exactly the same lists from that state, installs the history and continues with
// the saved forces, so the continued run is bitwise equal to an uninterrupted one
// (tests/unit/test_checkpoint.cpp). An application (the ring shear tester) may store its own
// state beside the system's, in the same atomic file.
#pragma once
#include <filesystem>
#include <string>

#include "sim/system.hpp"

namespace cohdem {

/// Writes the checkpoint atomically and durably (temp file, fsync, rename, fsync of the
/// directory: after a kill or a power cut the path holds the previous checkpoint or the
/// complete new one), with an application's own state (opaque bytes) when given.
void write_checkpoint(const std::filesystem::path& path, const System& s, const std::string& app_state = {});

/// Restores a checkpoint into `s`, which must be built from the same case (materials, model,
/// walls, pours) without particles. Throws InputError if the file is not a checkpoint of the
/// same model, or is truncated. Returns the application state stored with it (empty if none).
std::string read_checkpoint(const std::filesystem::path& path, System& s);

}  // namespace cohdem
