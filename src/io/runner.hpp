// `cohdem run`: builds the system from a case, audits the time step, runs the time loop and
// writes VTK frames, the CSV time series, a JSON summary and progress lines.
#pragma once
#include <string>

#include "io/case_file.hpp"
#include "sim/timestep_audit.hpp"

namespace cohdem {

struct RunOptions {
  std::string out_dir;   ///< overrides [output] folder when not empty
  bool quiet = false;    ///< no progress lines
  std::string resume;    ///< checkpoint to continue from (same case; output folder reused)
  /// Wall-time budget, s (< 0: none). Past it the run stops at its next checkpoint (the ring
  /// shear tester: the end of the current stage) and returns kExitResumable.
  double max_wall_time = -1;
};

/// Exit status of a run stopped by RunOptions::max_wall_time: resume it with --resume
/// (EX_TEMPFAIL of sysexits.h: a job script may resubmit).
constexpr int kExitResumable = 75;

/// Smallest particle radius of each material (particles present and pour sources).
std::vector<double> min_radius_by_material(const System& s);
/// Audit velocity: the case's, else max(1 m/s, sqrt(2 |g| H), insertion and wall speeds).
double audit_velocity(const Case& c);

/// Runs a case to completion. Throws InputError/RunError; returns the exit status. The case
/// is taken by value: its particle list (up to ~100 bytes a particle, read from
/// [[particle]] tables or [[particles]] files) is released once the system holds the
/// particles, so it does not count in the run's memory; pass an rvalue to avoid the copy.
int run_case(Case c, const RunOptions& opt);

/// Writes one state as particles_TAG.vtu, walls_TAG.vtu and (with `contacts`) contacts_TAG.vtu
/// in `dir`: the same arrays as the frames of `cohdem run`.
void write_state_vtk(const System& s, const std::string& dir, const std::string& tag, bool contacts);

/// `cohdem check`: validates and prints derived quantities; returns the exit status
/// (0 ok, 1 time step past its hard bound).
int check_case(const Case& c);

}  // namespace cohdem
