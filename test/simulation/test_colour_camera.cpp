// The colour camera's effects (colour_camera.h) on a synthetic image with a vertical stripe: a
// camera at rest changes only the noise; a panning head smears the stripe over the exposure and
// slants it by the rolling shutter's row delay, by the amounts its motion gives.
#include "geofusion/simulation/colour_camera.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace geofusion {
namespace {

constexpr int kW = 640, kH = 480;

/// White image, a black stripe over columns [300, 340).
std::vector<std::uint8_t> stripe() {
  std::vector<std::uint8_t> rgb(3 * kW * kH, 220);
  for (int v = 0; v < kH; ++v)
    for (int u = 300; u < 340; ++u)
      for (int c = 0; c < 3; ++c) rgb[3 * (v * kW + u) + c] = 20;
  return rgb;
}

/// Columns of row v darker than mid-grey: first, last, and how many are in between grey levels.
struct RowProfile {
  int first_dark = -1, last_dark = -1, ramp = 0;
};
RowProfile profile(const std::vector<std::uint8_t>& rgb, int v) {
  RowProfile p;
  for (int u = 0; u < kW; ++u) {
    const int g = rgb[3 * (v * kW + u)];
    if (g < 120) {
      if (p.first_dark < 0) p.first_dark = u;
      p.last_dark = u;
    }
    if (g > 40 && g < 200) ++p.ramp;
  }
  return p;
}

PinholeIntrinsics camera() {
  PinholeIntrinsics K;
  K.fx = K.fy = 554.0;
  K.cx = 320.0, K.cy = 240.0;
  return K;
}

ColourNoise geometryOnly() {
  ColourNoise n = ColourNoise::fetchHead();
  n.read_noise_dn = n.shot_noise = n.exposure_walk = 0.0;
  return n;
}

TEST(ColourCamera, AtRestOnlyNoise) {
  ColourCamera camera_model(ColourNoise::fetchHead(), 1);
  std::vector<std::uint8_t> rgb = stripe();
  const std::vector<std::uint8_t> clean = rgb;
  const Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  camera_model.apply(camera(), T, T, 1.0 / 30.0, 1.0, &rgb);
  EXPECT_NEAR(camera_model.lastFlow().norm(), 0.0, 1e-9);
  double diff = 0.0;
  for (std::size_t i = 0; i < rgb.size(); ++i) diff += std::abs(rgb[i] - clean[i]);
  diff /= rgb.size();
  // Read and shot noise (2 + 0.5 sqrt(level) grey levels) and the exposure's first step.
  EXPECT_GT(diff, 1.0);
  EXPECT_LT(diff, 12.0);
  const RowProfile p = profile(rgb, 240);
  EXPECT_EQ(p.first_dark, 300);
  EXPECT_EQ(p.last_dark, 339);
}

TEST(ColourCamera, PanningSmearsAndSlants) {
  const ColourNoise n = geometryOnly();
  ColourCamera camera_model(n, 2);
  std::vector<std::uint8_t> rgb = stripe();
  // The head pans at 60 deg/s about the optical frame's y axis (image x moves).
  const double dt = 1.0 / 30.0, omega = 60.0 * M_PI / 180.0;
  Eigen::Isometry3d before = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d now = Eigen::Isometry3d::Identity();
  now.linear() = Eigen::AngleAxisd(omega * dt, Eigen::Vector3d::UnitY()).toRotationMatrix();
  camera_model.apply(camera(), before, now, dt, 1.0, &rgb);
  const double flow = std::abs(camera_model.lastFlow().x());
  EXPECT_NEAR(flow, 554.0 * omega, 0.05 * 554.0 * omega);  // about 580 px/s
  // Motion blur: the stripe's edges ramp over about flow * exposure (8.7 px) each.
  const RowProfile mid = profile(rgb, 240);
  EXPECT_NEAR(mid.ramp, 2.0 * 0.8 * flow * n.exposure_s, 4.0);  // 10-90 % of each edge
  // Rolling shutter: the last rows see the stripe flow * readout (14.5 px) from the first.
  const RowProfile top = profile(rgb, 10), bottom = profile(rgb, 470);
  const double slant = std::abs((bottom.first_dark - top.first_dark) * 1.0);
  EXPECT_NEAR(slant, flow * n.readout_s * 460.0 / 480.0, 2.5);
}

TEST(ColourCamera, ExposureStaysInItsRange) {
  ColourNoise n = ColourNoise::fetchHead();
  n.exposure_walk = 0.2;  // a restless auto exposure
  ColourCamera camera_model(n, 3);
  const Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  double lo = 2.0, hi = 0.0;
  for (int k = 0; k < 200; ++k) {
    std::vector<std::uint8_t> rgb = stripe();
    camera_model.apply(camera(), T, T, 1.0 / 30.0, 1.0, &rgb);
    lo = std::min(lo, camera_model.gain());
    hi = std::max(hi, camera_model.gain());
  }
  EXPECT_GE(lo, 1.0 - n.exposure_range - 1e-12);
  EXPECT_LE(hi, 1.0 + n.exposure_range + 1e-12);
  EXPECT_GT(hi - lo, n.exposure_range);  // it does move
}

}  // namespace
}  // namespace geofusion
