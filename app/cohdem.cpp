// cohdem: command-line interface (CLI11).
//   cohdem run [CASE] [--set key=value]... [--out DIR] [--threads N] [--quiet]
//   cohdem check CASE [--set key=value]...
//   cohdem contact --model NAME --set k=v... --ri R [--rj R | --wall] --path PATH.csv [--out DIR]
//   cohdem models
//   cohdem bed packing|janssen|vibrate|thermal-cycle CASE [--set key=value]... [options]
// Exit status: 0 success, 1 time-step audit failed (check), 2 bad input, 3 run failure.
#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include <cstdio>
#include <string>
#include <vector>

#include "beds/bed_protocols.hpp"
#include "core/error.hpp"
#include "io/case_file.hpp"
#include "io/contact_cmd.hpp"
#include "io/runner.hpp"
#include "models/registry.hpp"

namespace cohdem {
const char* embedded_default_case_name();
const char* embedded_default_case();
}  // namespace cohdem

using namespace cohdem;

namespace {
Case load(const std::string& path, const std::vector<std::string>& sets) {
  if (path.empty()) return load_case_text(embedded_default_case(), embedded_default_case_name(), sets);
  return load_case_file(path, sets);
}
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"cohdem: discrete element method for cohesive bulk solids and packed beds"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "cohdem 0.1.0");

  std::string case_path, out_dir;
  std::vector<std::string> sets;
  int threads = 0;
  bool quiet = false;

  auto* run = app.add_subcommand("run", "run a case (the embedded default case when none is given)");
  run->add_option("case", case_path, "case file (TOML)");
  run->add_option("--set", sets, "override a case-file key, e.g. --set simulation.duration=0.1")->take_all();
  run->add_option("--out", out_dir, "output folder (overrides [output] folder)");
  run->add_option("--threads", threads, "OpenMP threads (overrides simulation.threads)")->check(CLI::NonNegativeNumber);
  run->add_flag("--quiet", quiet, "no progress lines");
  std::string resume;
  run->add_option("--resume", resume, "continue from a checkpoint (OUT/checkpoint.bin) of the same case")
      ->check(CLI::ExistingFile);
  double max_wall_time = -1;
  run->add_option("--max-wall-time", max_wall_time,
                  "stop at the first checkpoint after this many seconds of wall time (a ring shear test: at the end of "
                  "the current stage), exit status 75; continue with --resume")
      ->check(CLI::NonNegativeNumber);

  auto* check = app.add_subcommand("check", "validate a case and print derived quantities without running");
  check->add_option("case", case_path, "case file (TOML); the embedded default when omitted");
  check->add_option("--set", sets, "override a case-file key")->take_all();

  auto* models = app.add_subcommand("models", "list contact models and their parameters");

  ContactCommand cc;
  std::string materials;
  auto* contact = app.add_subcommand("contact", "drive one contact along a path (CSV) and write its response (CSV, PNG)");
  contact->add_option("--case", cc.case_path, "take model, parameters and materials from a case file");
  contact->add_option("--materials", materials, "material pair in that case, e.g. ore,steel (default: the first twice)");
  contact->add_option("--model", cc.model, "contact model (without --case)");
  contact->add_option("--rolling", cc.rolling, "rolling model (without --case): none, epsd, cdt, sds");
  contact->add_option("--set", cc.params, "model parameter, e.g. --set k1=4.75e8")->take_all();
  contact->add_option("--ri", cc.ri, "radius of body i, m")->required();
  contact->add_option("--rj", cc.rj, "radius of body j, m (default: ri)");
  contact->add_flag("--wall", cc.wall, "body j is a wall");
  contact->add_option("--E", cc.E, "Young's modulus of both bodies, Pa (without --case; models that need E*)");
  contact->add_option("--nu", cc.nu, "Poisson ratio of both bodies (without --case)");
  contact->add_option("--density", cc.density, "particle density, kg/m^3 (rate-dependent terms only)");
  contact->add_option("--path", cc.path, "CSV with a header and any of the columns delta, xi, theta, phi")->required();
  contact->add_option("--out", cc.out, "output folder for response.csv and response.png");
  contact->add_option("--dt", cc.dt, "duration of one path row, s (> 0 turns damping on; default quasi-static)");
  contact->add_flag("--no-plot", [&](int64_t) { cc.plot = false; }, "write the CSV only");

  // Packed-bed protocols (docs/packed-beds.md).
  beds::BedOptions bo;
  auto* bed = app.add_subcommand("bed", "packed-bed validation protocols (docs/packed-beds.md)");
  bed->require_subcommand(1);
  auto common = [&](CLI::App* a) {
    a->add_option("case", bo.case_path, "case file (TOML), e.g. examples/beds/janssen.toml")->required();
    a->add_option("--set", bo.sets, "override a case-file key")->take_all();
    a->add_option("--out", bo.out_dir, "output folder (overrides [output] folder)");
    a->add_option("--threads", bo.threads, "OpenMP threads")->check(CLI::NonNegativeNumber);
    a->add_flag("--quiet", bo.quiet, "no progress lines");
    a->add_flag("--resume", bo.resume,
                "continue from the checkpoint of the long stage (fill, thermal cycling) in the output folder, "
                "written every [output] checkpoint_interval s (same case and --set options)");
  };
  beds::PackingOptions po;
  std::string seeds = "1";
  auto* packing = bed->add_subcommand("packing", "solids fraction and its profile between two walls, over seeds");
  common(packing);
  packing->add_option("--seeds", seeds, "comma-separated random seeds (default 1)");
  packing->add_option("--bins-per-diameter", po.bins_per_diameter, "profile bins per particle diameter")->check(CLI::PositiveNumber);
  packing->add_option("--band-margin", po.band_margin, "band for the mean: diameters above the floor and below the top");
  beds::JanssenOptions jo;
  std::string heights;
  auto* janssen = bed->add_subcommand("janssen", "pedestal force against bed height, pipe wall moving up and/or down");
  common(janssen);
  janssen->add_option("--pipe", jo.pipe, "name of the pipe wall (cylinder, axis z)");
  janssen->add_option("--base", jo.base, "name of the pedestal wall (plane, normal +z)");
  janssen->add_option("--heights", heights, "comma-separated bed heights, m (default: --count up to 90% of the fill)");
  janssen->add_option("--count", jo.count, "number of bed heights")->check(CLI::PositiveNumber);
  janssen->add_option("--speed", jo.speed, "pipe speed, m/s")->check(CLI::PositiveNumber);
  janssen->add_option("--travel-up", jo.travel_up, "pipe travel, wall up, m")->check(CLI::PositiveNumber);
  janssen->add_option("--travel-down", jo.travel_down, "pipe travel, wall down, m")->check(CLI::PositiveNumber);
  janssen->add_option("--settle", jo.settle, "settling time after trimming, s")->check(CLI::NonNegativeNumber);
  janssen->add_option("--direction", jo.direction, "up, down or both")->check(CLI::IsMember({"up", "down", "both"}));
  janssen->add_option("--slice", jo.slice, "stress slice height, particle diameters")->check(CLI::PositiveNumber);
  beds::VibrateOptions vo;
  auto* vibrate = bed->add_subcommand("vibrate", "densify by vertical shaking; solids fraction and piston force before/after");
  common(vibrate);
  vibrate->add_option("--pipe", vo.pipe, "name of the pipe wall");
  vibrate->add_option("--base", vo.base, "name of the pedestal wall");
  vibrate->add_option("--amplitude", vo.amplitude, "shaking amplitude, m")->check(CLI::PositiveNumber);
  vibrate->add_option("--frequency", vo.frequency, "shaking frequency, Hz")->check(CLI::PositiveNumber);
  vibrate->add_option("--cycles", vo.cycles, "shaking cycles")->check(CLI::PositiveNumber);
  vibrate->add_option("--settle", vo.settle, "settling time after shaking, s")->check(CLI::NonNegativeNumber);
  vibrate->add_option("--height", vo.height, "bed height for the piston test, m (default: 90% of the shorter bed)");
  vibrate->add_option("--speed", vo.speed, "pipe speed in the piston test, m/s")->check(CLI::PositiveNumber);
  vibrate->add_option("--travel", vo.travel, "pipe travel in the piston test, m")->check(CLI::PositiveNumber);
  beds::ThermalCycleOptions to;
  auto* cycle = bed->add_subcommand("thermal-cycle", "thermal cycling under a spring-loaded lid: peaks per cycle");
  common(cycle);
  cycle->add_option("--pipe", to.pipe, "name of the pipe wall");
  cycle->add_option("--base", to.base, "name of the base wall");
  cycle->add_option("--lid", to.lid, "name of the lid wall (spring control)");
  cycle->add_option("--start", to.start, "start of the first cycle, s")->check(CLI::NonNegativeNumber);
  cycle->add_option("--period", to.period, "cycle length, s")->required()->check(CLI::PositiveNumber);
  cycle->add_option("--sample", to.sample, "s between samples")->check(CLI::PositiveNumber);

  CLI11_PARSE(app, argc, argv);
  spdlog::set_pattern("[%H:%M:%S] %^%l%$ %v");
  if (const char* lv = std::getenv("COHDEM_LOG")) spdlog::set_level(spdlog::level::from_str(lv));
  try {
    if (run->parsed()) {
      if (threads > 0) sets.push_back("simulation.threads=" + std::to_string(threads));
      Case c = load(case_path, sets);
      RunOptions o;
      o.out_dir = out_dir;
      o.quiet = quiet;
      o.resume = resume;
      o.max_wall_time = max_wall_time;
      return run_case(std::move(c), o);
    }
    if (check->parsed()) return check_case(load(case_path, sets));
    if (contact->parsed()) {
      if (!materials.empty()) {
        const auto comma = materials.find(',');
        cc.materials = {materials.substr(0, comma), comma == std::string::npos ? "" : materials.substr(comma + 1)};
      }
      return run_contact(cc);
    }
    if (bed->parsed()) {
      if (packing->parsed()) {
        po.seeds.clear();
        for (double v : beds::parse_list(seeds, "--seeds")) po.seeds.push_back(int(v));
        return beds::run_packing(bo, po);
      }
      if (janssen->parsed()) {
        if (!heights.empty()) jo.heights = beds::parse_list(heights, "--heights");
        return beds::run_janssen(bo, jo);
      }
      if (vibrate->parsed()) return beds::run_vibrate(bo, vo);
      if (cycle->parsed()) return beds::run_thermal_cycle(bo, to);
    }
    if (models->parsed()) {
      for (const auto& name : contact_model_names()) {
        auto m = make_contact_model(name, "none");  // rolling keys: see the last line
        std::printf("%s\n", name.c_str());
        for (const auto& s : m->specs())
          std::printf("  %-16s %-10s %s%s\n", s.name, s.unit, s.doc, s.required ? " (required)" : "");
      }
      std::printf("rolling: none, epsd (adds mu_r, eta_r), cdt (adds mu_r), sds (adds k_r N/m, gamma_r kg/s, "
                  "mu_r); walton: none (its bending moment fills the rolling slot)\n");
      return 0;
    }
  } catch (const InputError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  } catch (const RunError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 3;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 3;
  }
  return 0;
}
