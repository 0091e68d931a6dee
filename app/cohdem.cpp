// cohdem: command-line interface (CLI11).
//   cohdem run [CASE] [--set key=value]... [--out DIR] [--threads N] [--quiet]
//   cohdem check CASE [--set key=value]...
//   cohdem contact --model NAME --set k=v... --ri R [--rj R | --wall] --path PATH.csv [--out DIR]
//   cohdem models
// Exit status: 0 success, 1 time-step audit failed (check), 2 bad input, 3 run failure.
#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include <cstdio>
#include <string>
#include <vector>

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
  contact->add_option("--rolling", cc.rolling, "rolling model (without --case): none, epsd, cdt");
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

  CLI11_PARSE(app, argc, argv);
  spdlog::set_pattern("[%H:%M:%S] %^%l%$ %v");
  try {
    if (run->parsed()) {
      if (threads > 0) sets.push_back("simulation.threads=" + std::to_string(threads));
      const Case c = load(case_path, sets);
      RunOptions o;
      o.out_dir = out_dir;
      o.quiet = quiet;
      o.resume = resume;
      return run_case(c, o);
    }
    if (check->parsed()) return check_case(load(case_path, sets));
    if (contact->parsed()) {
      if (!materials.empty()) {
        const auto comma = materials.find(',');
        cc.materials = {materials.substr(0, comma), comma == std::string::npos ? "" : materials.substr(comma + 1)};
      }
      return run_contact(cc);
    }
    if (models->parsed()) {
      for (const auto& name : contact_model_names()) {
        auto m = make_contact_model(name, "none");  // rolling keys: see the last line
        std::printf("%s\n", name.c_str());
        for (const auto& s : m->specs())
          std::printf("  %-16s %-10s %s%s\n", s.name, s.unit, s.doc, s.required ? " (required)" : "");
      }
      std::printf("rolling: none, epsd (adds mu_r, eta_r), cdt (adds mu_r); walton: none (its bending moment "
                  "fills the rolling slot)\n");
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
