// `cohdem contact`: drives one contact along a prescribed path and writes its response
// (CSV) and the force-displacement / moment-angle loops (PNG). The contract is documented in
// docs/contact-driver.md and kept stable.
#pragma once
#include <string>
#include <vector>

namespace cohdem {

struct ContactCommand {
  std::string case_path;                ///< take model, rolling, parameters, E, nu from a case
  std::vector<std::string> materials;   ///< the material pair in that case (default: first, first)
  std::string model, rolling = "none";  ///< without a case
  std::vector<std::string> params;      ///< name=value, override/complete the parameters
  double ri = 0, rj = 0;                ///< radii, m (rj = 0 with `wall`)
  bool wall = false;
  double E = 0, nu = 0.25, density = 2500;  ///< without a case: both bodies' material
  std::string path;                     ///< CSV with any of: delta, xi, theta, phi
  std::string out = "out/contact";      ///< folder for response.csv and response.png
  double dt = 0;                        ///< > 0: rows last dt (damping acts); 0: quasi-static
  bool plot = true;
};

/// Returns the exit status; throws InputError for bad input.
int run_contact(const ContactCommand& cmd);

}  // namespace cohdem
