// Shared pieces of the packed-bed protocols (`cohdem bed ...`, docs/packed-beds.md): loading
// the case, cloning a settled bed, advancing with progress lines, trimming, measuring the bed
// in a vertical pipe, and small output helpers.
#pragma once
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "io/case_file.hpp"
#include "sim/system.hpp"

namespace cohdem::beds {

struct BedOptions {
  std::string case_path;
  std::vector<std::string> sets;  ///< --set overrides
  std::string out_dir;            ///< overrides [output] folder
  int threads = 0;
  bool quiet = false;
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
