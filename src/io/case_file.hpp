// Case files (TOML, SI units) and their strict validation. Every error names the file, the
// line and the key; unknown keys are errors. docs/case-file.md is the reference.
#pragma once
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <optional>

#include "apps/ring_shear_spec.hpp"
#include "models/params.hpp"
#include "particles/insertion.hpp"
#include "sim/system.hpp"
#include "thermal/thermal.hpp"

namespace cohdem {

struct OutputSettings {
  std::string folder = "out";
  double frame_interval = 0;    ///< s of simulated time between VTK frames (0: first and last only)
  double series_interval = 0;   ///< s between CSV rows (0: every 100 steps)
  std::vector<std::string> probes;  ///< extra CSV columns (see docs/case-file.md)
  double progress_interval = 5; ///< wall-clock s between progress lines
  bool vtk = true;
  double checkpoint_interval = 600;  ///< wall-clock s between checkpoints (0: only at the end)
  bool contacts = false;        ///< also write the contact network (contacts_*.vtu)
};

struct InsertStep {
  InsertSpec spec;
  bool pour = false;
  double rate = 0, start = 0, interval = 0;
  int line = 0;       ///< where the [[insert]] is, for errors
  std::string key;    ///< "insert[k]"
};

struct ExplicitParticle {
  int material = 0;
  double radius = 0;
  Vec3 x, v, omega;
  bool frozen = false;
  int attach_wall = -1;
  double temperature = 0;       ///< K (0: thermal.initial_temperature)
};

struct Case {
  std::string file;             ///< path or "<embedded:NAME>"
  std::string name;
  SimConfig cfg;
  double duration = 0;          ///< s
  int dt_line = 0;              ///< line of simulation.dt, for audit errors
  uint64_t seed = 1;
  double audit_velocity = 0;    ///< m/s for the Hertz collision-time audit (0: derived)
  std::vector<Material> materials;
  std::string model = "linear", rolling = "none";
  std::vector<ParamSet> pair_params;  ///< n*n
  std::vector<Wall> walls;
  std::vector<InsertStep> inserts;
  std::vector<ExplicitParticle> particles;
  size_t particle_tables = 0;   ///< how many of them came from [[particle]] tables
  OutputSettings output;
  std::optional<RingShearSpec> ring_shear;  ///< [ring_shear]: run the ring shear tester
  ThermalSettings thermal;      ///< [thermal], wall temperatures, [[heat_source]]

  uint64_t steps() const;
};

/// Parses and validates. `overrides` are "dotted.key=value" strings from --set; a value is
/// read as TOML (numbers, strings in quotes or bare words, arrays).
Case load_case_file(const std::string& path, const std::vector<std::string>& overrides = {});
Case load_case_text(const std::string& text, const std::string& name,
                    const std::vector<std::string>& overrides = {});

/// Builds the system: materials, model, walls, explicit particles and fills (pours are
/// registered to run during the time loop).
/// With fill = false, fills and explicit particles are skipped (a checkpoint supplies them).
std::unique_ptr<System> build_system(const Case& c, bool fill = true);

}  // namespace cohdem
