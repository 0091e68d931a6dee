// The series probes that read contact forces (max_contact_force, mean_contact_force): a case
// that asks for them must record the pair forces on any number of threads (before the fix a
// one- or two-thread run of examples/beds/janssen.toml stopped at its first series row with
// a contact: "pair forces were not recorded").
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>
#include <unistd.h>
#include <vector>

#include "io/case_file.hpp"
#include "io/runner.hpp"

using namespace cohdem;

namespace {

// A sphere (r = 5 mm, glass 2500 kg/m^3) resting on a frozen one under gravity, linear
// spring kn = 1e4 N/m with e = 0.1: the contact's oscillation (period 2 pi sqrt(m/kn) = 2.3
// ms) decays at zeta omega = 1.6e3 /s, so after 0.05 s (e^-80) the pair force is the
// weight m g to rounding. Started touching at the static overlap m g / kn.
std::string case_text(const std::string& probes) {
  const double r = 0.005, m = 2500.0 * 4.0 / 3.0 * std::numbers::pi * r * r * r, g = 9.81;
  const double z = 2 * r - m * g / 1e4;
  std::ostringstream t;
  t.precision(17);
  t << "[simulation]\ndt = 1e-5\nduration = 0.05\ngravity = [0, 0, -9.81]\nthreads = 1\n"
    << "[[material]]\nname = \"glass\"\ndensity = 2500\n"
    << "[contact]\nmodel = \"linear\"\nkn = 1e4\ne = 0.1\nmu = 0.5\n"
    << "[[particle]]\nmaterial = \"glass\"\nradius = " << r << "\nposition = [0, 0, 0]\nfrozen = true\n"
    << "[[particle]]\nmaterial = \"glass\"\nradius = " << r << "\nposition = [0, 0, " << z << "]\n"
    << "[output]\nvtk = false\nprobes = [" << probes << "]\n";
  return t.str();
}

// The last row of series.csv, by column name.
double last_value(const std::filesystem::path& csv, const std::string& column) {
  std::ifstream f(csv);
  std::string header, line, last;
  std::getline(f, header);
  while (std::getline(f, line))
    if (!line.empty()) last = line;
  std::vector<std::string> names, values;
  for (std::stringstream h(header); std::getline(h, line, ',');) names.push_back(line);
  for (std::stringstream v(last); std::getline(v, line, ',');) values.push_back(line);
  for (size_t k = 0; k < names.size() && k < values.size(); ++k)
    if (names[k] == column) return std::stod(values[k]);
  ADD_FAILURE() << column << " not in " << csv;
  return NAN;
}

}  // namespace

TEST(Probes, ContactForceProbesRecordThePairForces) {
  for (const char* p : {"\"max_contact_force\"", "\"mean_contact_force\""})
    EXPECT_TRUE(load_case_text(case_text(p), "<probes>").cfg.record_contacts) << p;
  EXPECT_FALSE(load_case_text(case_text("\"max_overlap\""), "<probes>").cfg.record_contacts);
}

TEST(Probes, ContactForceOfASphereRestingOnAnotherIsItsWeight) {
  const Case c = load_case_text(case_text("\"max_contact_force\", \"mean_contact_force\""), "<probes>");
  const auto out = std::filesystem::temp_directory_path() / ("cohdem_probes_" + std::to_string(::getpid()));
  RunOptions o;
  o.out_dir = out.string();
  o.quiet = true;
  ASSERT_EQ(run_case(c, o), 0);
  const double r = 0.005, w = 2500.0 * 4.0 / 3.0 * std::numbers::pi * r * r * r * 9.81;
  // Settled to e^-80 of the initial disturbance: 1e-9 relative covers the rounding of a few
  // thousand steps.
  EXPECT_NEAR(last_value(out / "series.csv", "max_contact_force"), w, 1e-9 * w);
  EXPECT_NEAR(last_value(out / "series.csv", "mean_contact_force"), w, 1e-9 * w);
  std::filesystem::remove_all(out);
}
