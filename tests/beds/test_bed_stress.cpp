// Slice stresses (src/beds/bed_stress.hpp) on a column whose contact forces are known.
#include <gtest/gtest.h>

#include "beds/bed_stress.hpp"
#include "physics/fixture.hpp"

using namespace cohdem;
using namespace cohdem::testing;

// N spheres stacked on a base inside a wide pipe (no wall contact). A slice between two
// neighbouring centres holds exactly one branch, the contact carrying the weight of the spheres
// above it, so sigma_v there is that weight over the pipe section; and a slice from the base to
// the top centre integrates sum f l over all contacts.
TEST(BedStress, ColumnCarriesTheWeightAbove) {
  const int N = 5;
  const double r = 1e-3, R = 5e-3, g = 9.81;
  auto s = make_system({{"glass", 2500, 0, 0}}, "linear", "none", params({{"kn", 1e6}, {"e", 0.3}, {"mu", 0.5}}), 2e-6,
                       {0, 0, -g});
  s->cfg.threads = 1;
  s->cfg.record_contacts = true;  // slice_stresses reads the pair forces
  s->walls.push_back(plane({0, 0, 0}, {0, 0, 1}, 0));
  Wall pipe;
  pipe.name = "pipe";
  pipe.shape = WallShape::Cylinder;
  pipe.radius = R;
  s->walls.push_back(pipe);
  for (int k = 0; k < N; ++k) s->add_particle(0, r, {0, 0, r + 2 * r * k});
  s->prepare();
  s->run(20000);
  const double m = s->particles.mass[0], A = M_PI * R * R;
  // Slices of height 2r between the centres (overlaps ~1e-10 m: centres at r + 2 r k).
  const auto sl = beds::slice_stresses(*s, 1, r, r + 2 * r * (N - 1), N - 1);
  for (int b = 0; b < N - 1; ++b) {
    EXPECT_NEAR(sl.sigma_v[b], (N - 1 - b) * m * g / A, 1e-6 * N * m * g / A) << "slice " << b;
    EXPECT_NEAR(sl.sigma_h[b], 0.0, 1e-9);
    EXPECT_EQ(sl.wall_normal[b], 0.0);
  }
  // One slice over everything, base contact included: sigma_v A H = sum f l.
  const double H = r + 2 * r * (N - 1);
  const auto all = beds::slice_stresses(*s, 1, 0, H, 1);
  double sum_fl = N * m * g * r;  // base contact: force N m g, branch r
  for (int k = 1; k < N; ++k) sum_fl += (N - k) * m * g * 2 * r;
  EXPECT_NEAR(all.sigma_v[0] * A * H, sum_fl, 1e-6 * sum_fl);
}

// A sphere pressed against the pipe wall by a horizontal force: wall normal stress = that force
// over the wall area of its slice; no shear without vertical load.
TEST(BedStress, WallNormalStress) {
  const double r = 1e-3, R = 5e-3;
  auto s = make_system({{"glass", 2500, 0, 0}}, "linear", "none", params({{"kn", 1e5}, {"e", 0.3}, {"mu", 0.5}}), 2e-6);
  s->cfg.threads = 1;
  Wall pipe;
  pipe.name = "pipe";
  pipe.shape = WallShape::Cylinder;
  pipe.radius = R;
  s->walls.push_back(pipe);
  const double delta = 1e-6;
  s->add_particle(0, r, {R - r + delta, 0, 0.5 * r});
  s->prepare();  // forces at the initial state: no step taken
  const auto sl = beds::slice_stresses(*s, 0, 0, 2 * r, 2);
  const double F = 1e5 * delta, dz = r;
  EXPECT_NEAR(sl.wall_normal[0], F / (2 * M_PI * R * dz), 1e-9 * F / (R * dz));
  EXPECT_EQ(sl.wall_normal[1], 0.0);
  EXPECT_NEAR(sl.wall_shear[0], 0.0, 1e-12);
  // The horizontal branch (centre to contact point at the same height) lies in slice 0:
  // sigma_xx = F (r - delta) / V, sigma_h = sigma_xx / 2.
  EXPECT_NEAR(sl.sigma_h[0], 0.5 * F * (r - delta) / (M_PI * R * R * dz), 1e-9 * F / (R * R * dz));
}
