// The virtual ring shear tester (Schulze RST-01 type; procedure of ASTM D6773): builds the
// cell, fills and settles the sample with reduced adhesion, consolidates under a
// servo-controlled lid, pre-shears to steady state, and shears to failure at lower normal
// stresses, re-pre-shearing before each point; then evaluates the yield locus (Mohr circles,
// sigma_1, sigma_c, ffc, phi_e) and writes CSV, JSON, PNG and a text summary.
#pragma once
#include "io/case_file.hpp"
#include "io/runner.hpp"

namespace cohdem {

/// Runs the [ring_shear] procedure of a case. Returns the exit status.
int run_ring_shear(const Case& c, const RunOptions& opt);

}  // namespace cohdem
