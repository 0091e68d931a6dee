#include "io/contact_cmd.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "contact/driver.hpp"
#include "core/error.hpp"
#include "io/case_file.hpp"
#include "io/csv.hpp"
#include "io/plot.hpp"
#include "models/registry.hpp"

namespace cohdem {

namespace fs = std::filesystem;

int run_contact(const ContactCommand& cmd) {
  // 1. Model and parameters.
  std::unique_ptr<ContactModel> model;
  ParamSet ps;
  PairMaterial mat;
  double density = cmd.density;
  if (!cmd.case_path.empty()) {
    const Case c = load_case_file(cmd.case_path);
    const int n = int(c.materials.size());
    int idx[2] = {0, 0};
    if (!cmd.materials.empty()) {
      if (cmd.materials.size() != 2) throw InputError("--materials", 0, "materials", "expected two material names, e.g. --materials ore,steel");
      for (int q = 0; q < 2; ++q) {
        idx[q] = -1;
        for (int i = 0; i < n; ++i)
          if (c.materials[i].name == cmd.materials[q]) idx[q] = i;
        if (idx[q] < 0) throw InputError(cmd.case_path, 0, "materials", "no material '" + cmd.materials[q] + "' in the case");
      }
    }
    model = make_contact_model(c.model, c.rolling, c.file);
    ps = c.pair_params[size_t(idx[0]) * n + idx[1]];
    const Material &a = c.materials[idx[0]], &b = c.materials[idx[1]];
    if (a.E > 0 && b.E > 0) mat = PairMaterial::make(a.E, a.nu, b.E, b.nu, cmd.wall);
    density = a.density > 0 ? a.density : density;
  } else {
    if (cmd.model.empty()) throw InputError("--model", 0, "model", "give --model NAME (or --case CASE.toml)");
    model = make_contact_model(cmd.model, cmd.rolling, "--model");
    if (cmd.E > 0) mat = PairMaterial::make(cmd.E, cmd.nu, cmd.E, cmd.nu, cmd.wall);
    if (!(cmd.nu > -1 && cmd.nu < 0.5)) throw InputError("--nu", 0, "nu", "Poisson ratio must be in (-1, 0.5)");
  }
  const auto specs = model->specs();
  for (const auto& kv : cmd.params) {
    const auto eq = kv.find('=');
    if (eq == std::string::npos) throw InputError("--set", 0, kv, "expected name=value, e.g. --set k1=4.75e8");
    const std::string k = kv.substr(0, eq), v = kv.substr(eq + 1);
    if (std::none_of(specs.begin(), specs.end(), [&](const ParamSpec& s) { return k == s.name; })) {
      std::string names;
      for (const auto& s : specs) names += (names.empty() ? "" : ", ") + std::string(s.name);
      throw InputError("--set", 0, k, "not a parameter of contact model '" + model->name() + "'; its parameters are: " + names);
    }
    char* end = nullptr;
    const double x = std::strtod(v.c_str(), &end);
    if (end == v.c_str() || *end != '\0' || !std::isfinite(x)) throw InputError("--set", 0, k, "expected a number, got '" + v + "'");
    ps.set(k, x, {"--set", 0, ""});
  }
  ps.set_context("--set", 0, "");
  model->set_params(1, {ps}, {mat});

  // 2. Path.
  if (cmd.path.empty()) throw InputError("--path", 0, "path", "give --path PATH.csv with columns delta, xi, theta, phi (any subset)");
  const CsvTable t = CsvTable::read(cmd.path);
  static const std::vector<std::string> known = {"delta", "xi", "theta", "phi"};
  for (const auto& name : t.names())
    if (std::find(known.begin(), known.end(), name) == known.end())
      throw InputError(cmd.path, 1, name, "unknown column; expected any of: delta, xi, theta, phi");
  if (t.num_rows() == 0) throw InputError(cmd.path, 1, "", "the path has a header but no rows");
  PathTable path;
  if (t.has("delta")) path.delta = t.column("delta");
  if (t.has("xi")) path.xi = t.column("xi");
  if (t.has("theta")) path.theta = t.column("theta");
  if (t.has("phi")) path.phi = t.column("phi");

  // 3. Drive.
  DriverSetup setup;
  if (!(cmd.ri > 0)) throw InputError("--ri", 0, "ri", "radius of body i must be > 0 m");
  setup.ri = cmd.ri;
  setup.rj = cmd.wall ? 0.0 : (cmd.rj > 0 ? cmd.rj : cmd.ri);
  setup.density = density;
  setup.quasi_static = !(cmd.dt > 0);
  if (cmd.dt > 0) setup.dt = cmd.dt;
  const auto rows = drive_contact(*model, 0, 0, setup, path);
  const auto cols = driver_columns(*model);

  // 4. Write.
  fs::create_directories(cmd.out);
  {
    CsvWriter w(fs::path(cmd.out) / "response.csv", cols);
    for (const auto& r : rows) w.row(r);
  }
  auto column = [&](const std::string& name) {
    const size_t c = size_t(std::find(cols.begin(), cols.end(), name) - cols.begin());
    std::vector<double> v;
    for (const auto& r : rows) v.push_back(r[c]);
    return v;
  };
  if (cmd.plot) {
    std::vector<PlotSpec> panels;
    const std::string title = model->name() + (cmd.rolling != "none" ? " + " + cmd.rolling : "");
    panels.push_back({title + ": normal force", "overlap delta (m)", "fn (N, repulsion > 0)",
                      {{"fn", column("delta"), column("fn"), "linespoints"}}});
    if (t.has("xi")) panels.push_back({"tangential", "xi (m)", "ft (N)", {{"ft", column("xi"), column("ft"), "linespoints"}}});
    if (t.has("theta"))
      panels.push_back({"bending / rolling", "theta (rad)", "mb (N m)", {{"mb", column("theta"), column("mb"), "linespoints"}}});
    if (t.has("phi")) panels.push_back({"twisting", "phi (rad)", "mt (N m)", {{"mt", column("phi"), column("mt"), "linespoints"}}});
    for (auto& p : panels) { p.width = 700; p.height = 500; }
    plot_png_panels(fs::path(cmd.out) / "response.png", panels, panels.size() > 1 ? 2 : 1);
  }
  spdlog::info("{} rows: {}/response.csv{}", rows.size(), cmd.out, cmd.plot ? ", " + cmd.out + "/response.png" : "");
  return 0;
}

}  // namespace cohdem
