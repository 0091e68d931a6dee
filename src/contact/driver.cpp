#include "contact/driver.hpp"

#include <cmath>
#include <cstddef>
#include <limits>

#include "core/error.hpp"

namespace cohdem {

size_t PathTable::rows() const {
  size_t n = 0;
  for (const auto* c : {&delta, &xi, &theta, &phi}) {
    if (c->empty()) continue;
    if (n != 0 && c->size() != n)
      throw InputError("", 0, "path", "path columns differ in length (" + std::to_string(n) + " and " +
                                          std::to_string(c->size()) + " rows)");
    n = c->size();
  }
  return n;
}

std::vector<std::string> driver_columns(const ContactModel& model) {
  std::vector<std::string> c = {"delta", "xi", "theta", "phi", "fn", "ft", "mb", "mt", "a", "contact"};
  for (auto& s : model.state_names()) c.push_back(s);
  return c;
}

std::vector<std::vector<double>> drive_contact(const ContactModel& model, int si, int sj, const DriverSetup& setup,
                                               const PathTable& path) {
  if (!(setup.ri > 0)) throw InputError("", 0, "ri", "radius of body i must be > 0");
  if (!(setup.rj >= 0)) throw InputError("", 0, "rj", "radius of body j must be >= 0 (0: wall)");
  const double tstep = setup.quasi_static ? kQuasiStaticTime : setup.dt;
  if (!(tstep > 0)) throw InputError("", 0, "dt", "time step must be > 0");
  const size_t nrow = path.rows();
  auto col = [](const std::vector<double>& c, size_t k) { return c.empty() ? 0.0 : c[k]; };

  const Vec3 n{0, 0, 1}, t{1, 0, 0}, b{0, 1, 0};
  constexpr double inf = std::numeric_limits<double>::infinity();
  const bool wall = setup.rj == 0;
  PairGeom g;
  g.n = n;
  g.ri = setup.ri;
  g.rj = setup.rj;
  g.mi = 4.0 / 3.0 * M_PI * setup.ri * setup.ri * setup.ri * setup.density;
  g.Ii = 0.4 * g.mi * setup.ri * setup.ri;
  g.mj = wall ? inf : 4.0 / 3.0 * M_PI * setup.rj * setup.rj * setup.rj * setup.density;
  g.Ij = wall ? inf : 0.4 * g.mj * setup.rj * setup.rj;
  g.rstar = wall ? setup.ri : setup.ri * setup.rj / (setup.ri + setup.rj);
  g.mstar = wall ? g.mi : g.mi * g.mj / (g.mi + g.mj);
  g.dt = tstep;

  const std::vector<std::string> names = model.state_names();
  std::vector<std::byte> state(model.state_size(), std::byte{0});
  std::vector<double> sv(names.size());
  std::vector<std::vector<double>> out;
  out.reserve(nrow);
  double d0 = col(path.delta, 0), x0 = 0, th0 = 0, ph0 = 0;
  for (size_t k = 0; k < nrow; ++k) {
    const double d = col(path.delta, k), x = col(path.xi, k), th = col(path.theta, k), ph = col(path.phi, k);
    g.delta = d;
    g.vn = -(d - d0) / tstep;
    g.vt = t * ((x - x0) / tstep);
    g.wrel = b * ((th - th0) / tstep) + n * ((ph - ph0) / tstep);
    d0 = d; x0 = x; th0 = th; ph0 = ph;
    PairForce f;
    const bool alive = model.evaluate(si, sj, g, state.data(), f);
    if (!alive) f = PairForce{};
    if (!sv.empty()) model.state_values(si, sj, state.data(), sv.data());
    std::vector<double> row = {d, x, th, ph, f.fn, -dot(f.ft, t), -dot(f.mr, b), -f.mt, f.a, alive ? 1.0 : 0.0};
    row.insert(row.end(), sv.begin(), sv.end());
    out.push_back(std::move(row));
  }
  return out;
}

}  // namespace cohdem
