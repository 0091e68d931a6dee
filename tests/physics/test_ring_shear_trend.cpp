// Virtual ring shear tester end to end on a tiny periodic shear box: a cohesionless MEPA bulk
// solid has a cohesion intercept near zero, and raising the adhesive stiffness kadh raises the
// cohesion and lowers the flow function ffc (issue 4's trend check).
//
// Why this cell runs in seconds, and what that costs:
// - 8 x 8 mean diameters (50 mm), about 4 d high between the glued rough layers: 255 free
//   and ~90 glued particles;
// - the copper ore stiffnesses softened 100 times at the paper's consolidation stress
//   (54.8 kPa): MEPA forces are linear in k at a fixed overlap, so this only makes overlaps
//   100^(2/3) = 22 times larger (about 2% of the radius) and lets dt grow 100^(1/3) = 4.6
//   times; gamma_n is lowered 10 times to keep the damping ratio (ratio ~ gamma / sqrt(k m));
// - shear at 0.15 m/s: inertial number ~1e-2 at the consolidation stress.
// Levels: kadh = 0, 0.25 k1 and 0.75 k1 (0.75 k1 is the 5% ore's ratio kadh/k1). A contact
// unloaded from a load F reaches a tensile force of F kadh (k2 - k1) / (k1 (k2 + kadh)):
// 0, 0.19 F and 0.52 F.
//
// What a cell this small measures robustly. Its shear stress swings by +-50% during a
// pre-shear (stick-slip of 255 particles), so a round-off change (another compiler, a
// reordered sum) gives another realization of the test. The scatter over realizations was
// measured with four fillings (seeds 3-6) of each level (kPa; sigma_pre = 54.8 kPa):
//   level         c (3-point fit)    ffc          tau at 0.25 sigma_pre   mean tau of the 3 points
//   kadh = 0      -6.9 .. +4.9       7.0 .. inf   4.7 .. 9.6              15.7 .. 19.1
//   0.25 k1       -5.5 .. +3.5       6.7 .. inf   9.7 .. 15.4             21.6 .. 25.4
//   0.75 k1       +5.3 .. +30.4      1.2 .. 4.2   21.9 .. 36.9            32.1 .. 39.6
// (the 0.75 k1 row includes a fifth realization: seed 3 before a round-off change, c = 30.4).
// The fitted cohesion scatters by +-6 kPa, so the trend is asserted on the height of the
// locus (mean normalized tau of the three shear points) and on tau at the lowest normal
// stress, which separate the levels by more than their scatter; the cohesion and ffc only
// on the side the scatter cannot cross.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <future>
#include <nlohmann/json.hpp>
#include <string>

#include "io/case_file.hpp"
#include "io/runner.hpp"

using namespace cohdem;

namespace {

std::string case_text(double kadh) {
  const std::string mepa = "k1 = 4.75e6\nk2 = 2.37e7\nkadh = " + std::to_string(kadh) +
                           "\nn = 1.5\nmu_r = 0.3\ngamma_n = 0.5\n";
  return "[simulation]\ndt = 4e-6\nduration = 0\ngravity = [0, 0, -9.81]\nseed = 3\nthreads = 1\naudit_velocity = 0.5\n"
         "[[material]]\nname = \"ore\"\ndensity = 2481.3\nyoungs_modulus = 1.19e9\npoisson_ratio = 0.34\n"
         "[[material]]\nname = \"steel\"\nyoungs_modulus = 2e9\npoisson_ratio = 0.3\n"
         "[contact]\nmodel = \"mepa\"\nrolling = \"epsd\"\nmu = 0.35\n" + mepa +
         "[[contact.pair]]\nmaterials = [\"ore\", \"steel\"]\nmu = 0.7\nmu_r = 0.3\n"
         "[ring_shear]\ncell = \"shear_box\"\nlength = 0.05\nwidth = 0.05\nmaterial = \"ore\"\nbase_material = \"steel\"\n"
         "size = { distribution = \"gaussian\", mean = 0.003175, std = 0.0003175, bound = 0.1 }\n"
         "bed_height = 0.025\nsettle_time = 0.1\nsigma_pre = 54.8e3\nfractions = [0.25, 0.5, 0.75]\n"
         "shear_velocity = 0.15\napproach_speed = 0.3\nconsolidate_time = 0.01\nfirst_preshear_distance = 0.0127\n"
         "preshear_distance = 0.0064\nshear_distance = 0.0064\nrelax_time = 0.005\nsample_interval = 2e-5\n"
         "[output]\nvtk = false\n";
}

struct Outcome {
  double c = NAN, ffc = NAN, phi = NAN;
  double tau_low = NAN;   ///< normalized tau of the shear point at the lowest normal stress, Pa
  double tau_mean = NAN;  ///< mean normalized tau of the shear points (height of the locus), Pa
};

Outcome run(double kadh) {
  const Case c = load_case_text(case_text(kadh), "<ring shear trend test>");
  const auto out = std::filesystem::temp_directory_path() / ("cohdem_ring_shear_trend_" + std::to_string(kadh) + "_" + std::to_string(::getpid()));
  RunOptions o;
  o.out_dir = out.string();
  o.quiet = true;
  EXPECT_EQ(run_case(c, o), 0);
  std::ifstream f(out / "summary.json");
  const auto j = nlohmann::json::parse(f);
  std::filesystem::remove_all(out);
  Outcome r;
  const auto& yl = j["yield_locus"];
  EXPECT_FALSE(yl.contains("error")) << "kadh " << kadh << ": " << yl.dump();
  if (yl.contains("error")) return r;
  r.c = yl["cohesion"].get<double>();
  r.ffc = yl["ffc"].is_string() ? INFINITY : yl["ffc"].is_null() ? NAN : yl["ffc"].get<double>();  // null: no steady-state circle
  r.phi = yl["phi_lin_deg"].get<double>();
  const auto& pts = j["shear_points"];
  EXPECT_EQ(pts.size(), 3u) << "kadh " << kadh;
  double sum = 0, sig_low = INFINITY;
  for (const auto& q : pts) {
    const double sig = q["sigma"].get<double>(), tau = q["tau_normalized"].get<double>();
    sum += tau;
    if (sig < sig_low) { sig_low = sig; r.tau_low = tau; }
  }
  r.tau_mean = pts.empty() ? NAN : sum / double(pts.size());
  // Momentum balance of the periodic sample along the shear direction: the lid's and the
  // base's shear forces differ by the rate of change of the sample's momentum. Over the last
  // quarter of a pre-shear (T >= 0.0064 m / 4 / 0.15 m/s = 10.7 ms) that averages to at most
  // m v / (T A) = 0.093 kg x 0.15 m/s / (10.7 ms x 0.0025 m^2) = 0.52 kPa (the whole sample
  // brought to the lid's speed), about 2% of the pre-shear tau; the averages are of samples
  // every 5 steps of a fluctuating net force, which adds noise: tolerance 5% + 0.52 kPa.
  const auto& pre = j["pre_shear"];
  for (size_t q = 0; q < pre["tau_each"].size(); ++q) {
    const double lid = pre["tau_each"][q].get<double>(), base = pre["tau_base_each"][q].get<double>();
    EXPECT_NEAR(base, lid, 0.05 * lid + 520) << "kadh " << kadh << ", pre-shear " << q + 1 << ": base and lid shear stresses";
  }
  std::printf("[validation] ring shear trend: kadh = %.3g N/m^1.5: phi_lin = %.1f deg, c = %.2f kPa, ffc = %.2f, "
              "tau at the lowest sigma %.2f kPa, mean tau %.2f kPa\n", kadh, r.phi, r.c / 1e3, r.ffc, r.tau_low / 1e3,
              r.tau_mean / 1e3);
  return r;
}

}  // namespace

TEST(RingShearTrend, CohesionlessHasNoInterceptAndAdhesionRaisesCohesionLowersFfc) {
  const double sigma_pre = 54.8e3, k1 = 4.75e6;
  // Three independent runs side by side (one thread each).
  auto a = std::async(std::launch::async, run, 0.0), b = std::async(std::launch::async, run, 0.25 * k1),
       w = std::async(std::launch::async, run, 0.75 * k1);
  const Outcome dry = a.get(), mid = b.get(), wet = w.get();
  // Adhesion raises the whole yield locus: its height grows with kadh at each step (measured
  // gaps between levels 2.5 and 6.7 kPa at the least, worst pairing of fillings: asserted
  // > 0 and > 0.05 sigma_pre = 2.7 kPa), and at the lowest normal stress the strong level
  // shears at far more than the cohesionless one (gap >= 12.3 kPa measured: asserted
  // > 0.15 sigma_pre = 8.2 kPa).
  EXPECT_GT(mid.tau_mean, dry.tau_mean);
  EXPECT_GT(wet.tau_mean, mid.tau_mean + 0.05 * sigma_pre);
  EXPECT_GT(wet.tau_low, dry.tau_low + 0.15 * sigma_pre);
  // kadh = 0: the cohesion intercept is zero within the scatter of the fit (|c| <= 6.9 kPa
  // measured: asserted < 0.15 sigma_pre = 8.2 kPa).
  EXPECT_LT(std::abs(dry.c), 0.15 * sigma_pre);
  // 0.75 k1: cohesive, on the side the scatter never crossed (c >= 5.3 kPa, ffc <= 4.2).
  EXPECT_GT(wet.c, 0.0);
  EXPECT_LT(wet.ffc, 6.0);
  EXPECT_LT(wet.ffc, dry.ffc);
  // The cohesionless friction angle of spheres with mu = 0.35 and rolling resistance
  // (sphere packings with rolling resistance reach 30-40 degrees; measured 27.5-38.6 over
  // the four fillings): 25 to 45 degrees.
  EXPECT_GT(dry.phi, 25.0);
  EXPECT_LT(dry.phi, 45.0);
}
