// Single-contact driver: moves one contact along a prescribed path and records the forces
// and moments of a contact model, for model plots (`cohdem contact`) and closed-form tests.
//
// Frame: fixed normal n = e_z (from j to i), tangent t = e_x, bending axis b = n x t = e_y.
// Path columns (rows are states of the contact, missing columns are zero):
//   delta  normal overlap, m (> 0 in contact, < 0 apart)
//   xi     tangential displacement of i relative to j along t, m
//   theta  rotation of i relative to j about b (bending/rolling angle), rad
//   phi    rotation of i relative to j about n (twist angle), rad
// xi, theta and phi are accumulated from the start of the path (zero before row 0); row k
// feeds the model the increments row k - row k-1 as rates over one time step:
//   vn = -(delta_k - delta_k-1)/dt,  vt = (xi_k - xi_k-1)/dt t,
//   wrel = (theta_k - theta_k-1)/dt b + (phi_k - phi_k-1)/dt n.
// The springs integrate increments only while the contact lives; a contact that ends resets
// its history (as in a simulation). The state buffer persists between rows.
//
// Rates: by default the path is quasi-static: each row is taken to last kQuasiStaticTime, so
// every increment is exact while all rates (and with them viscous damping and any other
// velocity-dependent term) vanish. With quasi_static = false each row lasts `dt` and the
// damping acts with the masses given by `density`.
//
// Result columns (driver_columns): delta, xi, theta, phi (the path), fn (normal force on i,
// repulsion positive, damping included), ft, mb, mt (the contact's resistance to the imposed
// xi, theta, phi: minus the force/moment on i along t, b, n, so elastic slopes are positive),
// a (contact radius, m), contact (1 while the contact lives), then the law's state columns
// (ContactModel::state_names, e.g. MEPA dmax, dp, branch). No file I/O here.
#pragma once
#include <string>
#include <vector>

#include "models/registry.hpp"

namespace cohdem {

struct DriverSetup {
  double ri = 1e-3;          ///< radius of body i, m
  double rj = 1e-3;          ///< radius of body j, m; 0: j is a wall (R* = ri)
  double density = 2500.0;   ///< kg/m^3: masses and inertia (rate-dependent terms only)
  double dt = 1e-6;          ///< duration of one row, s (used when !quasi_static)
  bool quasi_static = true;  ///< rates -> 0: no damping, increments exact
};

/// Duration of one row of a quasi-static path, s: rates ~ increment / 1e30.
inline constexpr double kQuasiStaticTime = 1e30;

struct PathTable {
  std::vector<double> delta, xi, theta, phi;  ///< equal lengths, or empty (= zero)
  /// Number of rows; throws InputError if the non-empty columns differ in length.
  size_t rows() const;
};

/// Column names of drive_contact's rows (for a CSV header).
std::vector<std::string> driver_columns(const ContactModel& model);

/// Drives one contact of species pair (si, sj) of `model` (parameters already set) along
/// `path`; returns one row per path row, columns as driver_columns(model).
std::vector<std::vector<double>> drive_contact(const ContactModel& model, int si, int sj, const DriverSetup& setup,
                                               const PathTable& path);

}  // namespace cohdem
