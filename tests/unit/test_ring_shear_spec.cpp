// [ring_shear] shear speed from the inertial-number limit: I = gamma_dot d / sqrt(sigma /
// rho_p) with gamma_dot = v / (10 d) (a shear band of 10 mean diameters), so the fastest
// speed at the limit is v = 10 I_max sqrt(sigma_low / rho_p), worked by hand below for the
// copper ore (rho_p = 2481.3 kg/m^3) at the lowest shear point 0.2 x 54.8 kPa.
#include <gtest/gtest.h>

#include <string>

#include "apps/ring_shear_spec.hpp"
#include "core/error.hpp"
#include "io/case_file.hpp"

using namespace cohdem;

namespace {
std::string ring_case(const std::string& speed_keys) {
  return "[simulation]\ndt = 4.5e-7\nduration = 0\n"
         "[[material]]\nname = \"ore\"\ndensity = 2481.3\nyoungs_modulus = 1.19e9\npoisson_ratio = 0.34\n"
         "[contact]\nmodel = \"mepa\"\nk1 = 4.75e8\nk2 = 2.37e9\nkadh = 3.56e8\nn = 1.5\nmu = 0.35\n"
         "[ring_shear]\ncell = \"shear_box\"\nlength = 0.064\nmaterial = \"ore\"\nbase_material = \"ore\"\n"
         "size = { distribution = \"gaussian\", mean = 0.003175, std = 0.0003175, bound = 0.1 }\n"
         "bed_height = 0.03\nsigma_pre = 54.8e3\nfractions = [0.4, 0.2, 0.6]\n" + speed_keys;
}
}  // namespace

TEST(RingShearSpec, ShearSpeedFromInertialNumberLimit) {
  // sqrt(10960 / 2481.3) = 2.101666..., v = 10 x 5e-3 x 2.101666 = 0.1050833 m/s (the lowest
  // fraction is 0.2 although it is not listed first).
  const Case c = load_case_text(ring_case("inertial_number_max = 5e-3\n"), "<spec test>");
  EXPECT_NEAR(c.ring_shear->shear_velocity, 0.1050833, 1e-6);
  EXPECT_NEAR(ring_shear_inertial_number(c.ring_shear->shear_velocity, 10960.0, 2481.3), 5e-3, 1e-12);
}

TEST(RingShearSpec, GivenSpeedIsCheckedAgainstTheLimit) {
  const Case ok = load_case_text(ring_case("shear_velocity = 0.1\ninertial_number_max = 5e-3\n"), "<spec test>");
  EXPECT_DOUBLE_EQ(ok.ring_shear->shear_velocity, 0.1);
  EXPECT_THROW(load_case_text(ring_case("shear_velocity = 0.11\ninertial_number_max = 5e-3\n"), "<spec test>"), InputError);
  const Case none = load_case_text(ring_case(""), "<spec test>");
  EXPECT_DOUBLE_EQ(none.ring_shear->shear_velocity, 0.02);  // documented default without a limit
}
