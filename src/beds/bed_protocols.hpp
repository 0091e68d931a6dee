// The packed-bed validation protocols behind `cohdem bed ...` (docs/packed-beds.md). Each takes
// a case file (examples/beds/*.toml) that describes the bed, runs it in stages that a case file
// cannot express (several seeds, clones of one settled bed, trimming, wall motions), evaluates it
// with src/analysis and writes CSV tables, a JSON summary and PNG plots in the output folder.
// Each returns the exit status (0 ok; InputError/RunError propagate as for `cohdem run`).
#pragma once
#include <string>
#include <vector>

#include "beds/bed_common.hpp"
#include "beds/bed_stress.hpp"

namespace cohdem::beds {

/// Packing between two parallel plane walls (periodic in the other horizontal direction):
/// for each seed, run the case (pour and settle), then the solids-fraction profile against
/// the distance from the walls and the mean fraction in a horizontal band.
struct PackingOptions {
  std::vector<int> seeds{1};
  int bins_per_diameter = 10;
  double band_margin = 3;   ///< band: this many diameters above the floor and below the top
};
int run_packing(const BedOptions& o, const PackingOptions& p);

/// Janssen: fill the pipe (the case's duration), then for each bed height clone the settled bed,
/// trim it, settle, move the pipe wall up (silo) or down (piston) and average the pedestal force.
struct JanssenOptions {
  std::string pipe = "pipe", base = "pedestal";
  std::vector<double> heights;   ///< bed heights, m (empty: `count` heights up to 90% of the fill)
  int count = 7;
  double speed = 0.01;           ///< pipe speed, m/s
  double travel_up = 1.5e-3, travel_down = 3e-3;  ///< m
  double settle = 0.02;          ///< s after trimming
  std::string direction = "both";  ///< up, down or both
  double slice = 2;              ///< stress slices, particle diameters
};
int run_janssen(const BedOptions& o, const JanssenOptions& j);

/// One pipe motion on a clone of a settled bed (the building block of janssen and vibrate):
/// trim to `height` above the base, settle for `settle` s, move the pipe at `velocity` (m/s,
/// signed: + up) by `travel` (m), averaging the pedestal load over the second half. With
/// `stresses`, also the slice stresses (slices of `slice` diameters) averaged the same way, and
/// the final state as VTK (`label`) in `vtk_dir`.
struct PipeMotion {
  double height = 0;     ///< mass-equivalent, with the bulk density given
  double force = 0, force_sd = 0;  ///< pedestal load, N
  double weight = 0;     ///< bed weight, N
  size_t particles = 0;
  double solids_fraction = 0;
  double max_overlap = 0;  ///< largest pair overlap / smaller radius at the end
  SliceStresses stress;
};
PipeMotion move_pipe(const Case& c, const System& filled, size_t pipe, size_t base, double height, double velocity,
                     double travel, double settle, double rho_bulk, bool stresses, double slice,
                     const std::string& label, bool quiet, const std::string& vtk_dir);

/// Throws InputError unless `pipe` is a cylinder (particles inside, axis along z) and `base` a
/// plane with normal +z.
void check_pipe(const Case& c, const System& s, size_t pipe, size_t base);

/// The common start of the pipe protocols: loads the case, finds and checks the pipe and base
/// walls, creates the output folder, runs the fill (the case's duration) and measures the bed.
struct PipeFill {
  Case c;
  std::unique_ptr<System> s;
  size_t pipe = 0, base = 0;
  std::string out;
  double R = 0, z0 = 0, g = 0;  ///< pipe radius, base height (m), |gravity| (m/s^2)
  double d = 0;                 ///< mean particle diameter, m
  PipeBed bed;                  ///< the filled bed
};
PipeFill fill_pipe(const BedOptions& o, const std::string& pipe, const std::string& base);

/// Vibration: fill, then shake a clone (pipe and base oscillate vertically), compare the solids
/// fraction and the piston (wall-down) force of both beds trimmed to the same height.
struct VibrateOptions {
  std::string pipe = "pipe", base = "pedestal";
  double amplitude = 5e-4, frequency = 30, cycles = 30;
  double settle = 0.05;
  double height = 0;            ///< m (0: 90% of the shorter bed)
  double speed = 0.01, travel = 3e-3;
};
int run_vibrate(const BedOptions& o, const VibrateOptions& v);

/// Thermal cycling of a bed under a spring-loaded lid: run the case and report per cycle the
/// peak contact force, pipe-wall stress, base and lid stress and the lid travel.
struct ThermalCycleOptions {
  std::string pipe = "pipe", base = "base", lid = "lid";
  double start = 0, period = 0;  ///< first cycle start and cycle length, s (period required)
  double sample = 1e-3;          ///< s between samples
};
int run_thermal_cycle(const BedOptions& o, const ThermalCycleOptions& t);

}  // namespace cohdem::beds
