// Shared pieces of the packed-bed protocols (`cohdem bed ...`, docs/packed-beds.md): loading
// the case, cloning a settled bed, advancing with progress lines, trimming, measuring the bed
// in a vertical pipe, and small output helpers.
#pragma once
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "io/case_file.hpp"
#include "sim/system.hpp"

namespace cohdem::beds {

struct BedOptions {
  std::string case_path;
  std::vector<std::string> sets;  ///< --set overrides
  std::string out_dir;            ///< overrides [output] folder
  int threads = 0;
  bool quiet = false;
  bool resume = false;            ///< continue the long stage from its checkpoint in the output folder
};

/// Loads the case (with overrides and the thread count) and names the output folder.
Case load(const BedOptions& o);
std::string out_folder(const BedOptions& o, const Case& c);

/// build_system plus the time-step audit of `cohdem run` (throws on its hard bound).
std::unique_ptr<System> build_checked(const Case& c);

/// A copy of a system's state (particles, walls, lists with contact history, time), ready to
/// step; the copy evolves independently.
std::unique_ptr<System> clone(const Case& c, const System& src);

/// Advances by `duration` s, calling `sample` every `every` steps (0: never); progress lines
/// every few seconds of wall time unless quiet. Throws RunError on a non-finite state.
void advance(System& s, double duration, const std::string& label, bool quiet,
             const std::function<void(System&)>& sample = {}, uint64_t every = 0);
/// The same for `n` steps, calling `after` (when given) after every step, after `sample`.
/// Steps after which nothing reads the particles take the force loop's fused opening
/// (System::step_once(true), bit-identical): not those followed by a sample, a finite-state
/// check or a progress line, nor the last; with `after`, only where `after_reads` (called
/// before the step) says `after` will not read the state after it (no `after_reads`: never).
void advance_steps(System& s, uint64_t n, const std::string& label, bool quiet, const std::function<void(System&)>& sample,
                   uint64_t every, const std::function<void(System&)>& after = {},
                   const std::function<bool(const System&)>& after_reads = {});

/// A protocol's long stage (the fill of a bed, a thermal cycling run: the case's `duration`
/// from its start), resumable. Without --resume, or with --resume but no checkpoint at `ckpt`
/// yet, the system is built from the case; with --resume and a checkpoint, from the
/// checkpoint, which must have been written by the same case file text, --set options and
/// seed (else InputError naming the checkpoint): `resumed`, `complete` (the stage had ended)
/// and the protocol's own `state` saved with it (e.g. its samples so far) are then set.
struct Stage {
  std::unique_ptr<System> s;
  bool resumed = false, complete = false;
  nlohmann::json state;
};
Stage open_stage(const Case& c, const BedOptions& o, const std::filesystem::path& ckpt);
/// Runs the stage to the end of the case's duration (steps counted from t = 0, so a resumed
/// stage ends at the same step, bit for bit as if never stopped), writing an atomic, fsync'ed
/// checkpoint to `ckpt` every [output] checkpoint_interval seconds of wall time and at the end
/// (marked complete), with `state()` when given. `sample` as for advance().
void run_stage(Stage& st, const Case& c, const BedOptions& o, const std::filesystem::path& ckpt, const std::string& label,
               const std::function<void(System&)>& sample = {}, uint64_t every = 0,
               const std::function<nlohmann::json()>& state = {});

/// Index of the wall called `name`; throws InputError naming the case file otherwise.
size_t find_wall(const Case& c, const System& s, const std::string& name, const std::string& option);

/// Mean particle radius, m.
double mean_radius(const System& s);

/// A bed standing on a horizontal base in a vertical pipe (axis along z) of radius R.
struct PipeBed {
  double R = 0;          ///< pipe radius, m
  double z_base = 0;     ///< base height, m
  double phi = 0;        ///< solids fraction of the bulk (2 d above the base to 3 d below the top)
  double rho_bulk = 0;   ///< particle density x phi, kg/m^3
  double mass = 0;       ///< free particles, kg
  double height = 0;     ///< mass-equivalent bed height M / (rho_bulk pi R^2), m
  double top = 0;        ///< 99th percentile of centre heights, m
  size_t count = 0;
};
PipeBed measure_pipe_bed(const System& s, double R, double z_base);

/// Removes the free particles whose centres lie above z; returns how many.
size_t trim_above(System& s, double z);

/// Comma-separated numbers ("0.1,0.2"); throws InputError naming the option.
std::vector<double> parse_list(const std::string& text, const std::string& option);

}  // namespace cohdem::beds
