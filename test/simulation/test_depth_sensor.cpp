// The depth camera models (depth_sensor.h) on a synthetic view: a wall 1.2 m away and a box
// 0.7 m away in front of it, seen by a 640 x 480 camera. Each model's signature properties: its
// random error against distance, the side its shadow falls on, flying pixels at edges, holes on
// materials, the misregistration; and the earlier model unchanged.
#include "geofusion/simulation/depth_sensor.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace geofusion {
namespace {

struct View {
  PinholeIntrinsics K;
  std::vector<float> depth;
  std::vector<std::uint16_t> instance;
  float at(int u, int v) const { return depth[static_cast<std::size_t>(v) * K.width + u]; }
};

/// The wall at `wall_m`, the box (instance 1) over columns [box_u0, box_u1) and rows 140-340.
View makeView(float wall_m = 1.2f, float box_m = 0.7f, int box_u0 = 250, int box_u1 = 390) {
  View v;
  v.K.fx = v.K.fy = 570.0;
  v.K.cx = 320.0, v.K.cy = 240.0;
  v.depth.assign(640 * 480, wall_m);
  v.instance.assign(640 * 480, 0);
  for (int r = 140; r < 340; ++r) {
    for (int c = box_u0; c < box_u1; ++c) {
      v.depth[static_cast<std::size_t>(r) * 640 + c] = box_m;
      v.instance[static_cast<std::size_t>(r) * 640 + c] = 1;
    }
  }
  return v;
}

double rmsResidual(const std::vector<float>& noisy, const std::vector<float>& clean, int r0, int r1,
                   int c0, int c1) {
  double sum = 0.0;
  int n = 0;
  for (int r = r0; r < r1; ++r) {
    for (int c = c0; c < c1; ++c) {
      const std::size_t i = static_cast<std::size_t>(r) * 640 + c;
      if (!(noisy[i] > 0.f)) continue;
      sum += (noisy[i] - clean[i]) * (noisy[i] - clean[i]);
      ++n;
    }
  }
  return n > 0 ? std::sqrt(sum / n) : std::nan("");
}

double holeShare(const std::vector<float>& d, int r0, int r1, int c0, int c1) {
  int holes = 0, n = 0;
  for (int r = r0; r < r1; ++r) {
    for (int c = c0; c < c1; ++c) {
      ++n;
      holes += !(d[static_cast<std::size_t>(r) * 640 + c] > 0.f);
    }
  }
  return static_cast<double>(holes) / n;
}

TEST(DepthSensor, StructuredLightErrorGrowsWithTheSquareOfDistance) {
  DepthNoise n = DepthNoise::structuredLight();
  n.disparity_step_px = 0.0;  // the random part alone
  std::mt19937 rng(3);
  const View near = makeView(0.6f, 0.5f), far = makeView(1.2f, 1.0f);
  std::vector<float> a = near.depth, b = far.depth;
  applyDepthNoise(near.K, n, rng, &a);
  applyDepthNoise(far.K, n, rng, &b);
  // The wall's centre-left, away from the box: sigma_z = z^2 sigma_d / (f b).
  const double sa = rmsResidual(a, near.depth, 20, 460, 20, 200);
  const double sb = rmsResidual(b, far.depth, 20, 460, 20, 200);
  const double expected_far = 1.2 * 1.2 * n.disparity_sigma_px / (n.focal_px * n.baseline_m);
  EXPECT_NEAR(sb / sa, 4.0, 0.4);
  EXPECT_NEAR(sb, expected_far, 0.15 * expected_far);
  // With the disparity steps: readings sit on the steps of fb / d.
  std::vector<float> q = far.depth;
  applyDepthNoise(far.K, DepthNoise::structuredLight(), rng, &q);
  EXPECT_GT(rmsResidual(q, far.depth, 20, 460, 20, 200), sb * 0.9);
}

TEST(DepthSensor, ShadowFallsOnTheEmittersFarSide) {
  std::mt19937 rng(4);
  const View v = makeView();
  DepthNoise n = DepthNoise::structuredLight();
  n.edge_dropout = 0.0;  // the shadow alone
  n.edge_flying = 0.0;
  std::vector<float> d = v.depth;
  applyDepthNoise(v.K, n, rng, &d);
  // Projector on the left in the registered image (shadow_baseline_m < 0): right of the box.
  // Width: f b (1/z_box - 1/z_wall) = 570 * 0.03 * (1/0.7 - 1/1.2) = 10 px.
  const double right = holeShare(d, 150, 330, 391, 399), left = holeShare(d, 150, 330, 240, 248);
  EXPECT_GT(right, 0.95);
  EXPECT_LT(left, 0.05);
  EXPECT_LT(holeShare(d, 150, 330, 404, 420), 0.05);  // beyond the shadow's width
  // Active stereo: the second camera at +x, the band left of the box.
  DepthNoise s = DepthNoise::activeStereo();
  s.edge_dropout = 0.0;
  s.edge_flying = 0.0;
  s.misregistration_x_px = 0;
  std::vector<float> e = v.depth;
  applyDepthNoise(v.K, s, rng, &e);
  EXPECT_GT(holeShare(e, 150, 330, 238, 248), 0.95);
  EXPECT_LT(holeShare(e, 150, 330, 391, 399), 0.05);
}

TEST(DepthSensor, TimeOfFlightHasFlyingPixelsAndNoShadow) {
  std::mt19937 rng(5);
  const View v = makeView();
  std::vector<float> d = v.depth;
  DepthNoise n = DepthNoise::timeOfFlight();
  n.misregistration_x_px = 0;
  applyDepthNoise(v.K, n, rng, &d);
  int flying = 0, band = 0;
  for (int r = 150; r < 330; ++r) {
    for (int c : {248, 249, 250, 251, 388, 389, 390, 391}) {
      const float z = d[static_cast<std::size_t>(r) * 640 + c];
      if (!(z > 0.f)) continue;
      ++band;
      flying += z > 0.72f && z < 1.18f;  // between the box and the wall
    }
  }
  EXPECT_GT(flying, band / 5);
  EXPECT_LT(holeShare(d, 150, 330, 394, 404), 0.05);  // no shadow
  EXPECT_LT(holeShare(d, 150, 330, 236, 246), 0.05);
}

TEST(DepthSensor, MaterialsLoseTheirDepthAndMisregistrationShifts) {
  std::mt19937 rng(6);
  const View v = makeView();
  const std::vector<SurfaceMaterial> materials{SurfaceMaterial::kDiffuse,
                                               SurfaceMaterial::kTransparent};
  DepthNoise n = DepthNoise::structuredLight();
  std::vector<float> d = v.depth;
  applyDepthNoise(v.K, n, rng, &d, &v.instance, &materials);
  const double box = holeShare(d, 160, 320, 270, 370);
  EXPECT_NEAR(box, n.transparent_dropout, 0.08);
  EXPECT_LT(holeShare(d, 20, 120, 20, 200), 0.01);  // the diffuse wall keeps its depth
  // Misregistration: the box edge moves by the offset.
  n.misregistration_x_px = 2;
  n.edge_dropout = n.edge_flying = 0.0;
  n.shadow = false;
  std::vector<float> s = v.depth;
  applyDepthNoise(v.K, n, rng, &s);
  EXPECT_GT(s[240 * 640 + 251], 1.0f);  // still the wall
  EXPECT_LT(s[240 * 640 + 252], 0.8f);  // the box, 2 px right of where it was
}

TEST(DepthSensor, PresetsByNameAndTheEarlierModelUnchanged) {
  for (const std::string& name : DepthNoise::names()) {
    DepthNoise n;
    ASSERT_TRUE(DepthNoise::byName(name, &n)) << name;
    EXPECT_EQ(n.name, name);
  }
  DepthNoise fetch;
  EXPECT_TRUE(DepthNoise::byName("fetch_head", &fetch));
  EXPECT_EQ(fetch.kind, DepthSensorKind::kStructuredLight);
  EXPECT_FALSE(DepthNoise::byName("kinect_v9", &fetch));
  // The earlier model's description (the cache key of the generated suites) is as it was.
  EXPECT_EQ(DepthNoise::nguyen2012().describe(), "0.0012 0.0019 0.001 0.02 0.5 78 0.8 4");
  EXPECT_NE(DepthNoise::structuredLight().describe().find("structured_light"), std::string::npos);
}

}  // namespace
}  // namespace geofusion
