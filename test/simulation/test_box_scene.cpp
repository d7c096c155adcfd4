#include "geofusion/common/class_palette.h"
#include "geofusion/simulation/box_scene.h"

#include <gtest/gtest.h>

#include <cmath>

namespace geofusion {
namespace {

// Camera looking straight down from height h (optical z = world -z).
Eigen::Isometry3d lookingDown(double x, double y, double h) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(x, y, h);
  return T;
}

TEST(BoxScene, DepthOfTheTableAndOfABoxTopMatchesGeometry) {
  BoxScene scene;
  scene.objects.push_back(BoxObject{"cube", 1, Eigen::Vector3d(0.1, 0.1, 0.1),
                                    Eigen::Isometry3d(Eigen::Translation3d(0, 0, 0.77))});
  PinholeIntrinsics K;
  const RenderedFrame f = scene.render(K, lookingDown(0.0, 0.0, 1.5));
  ASSERT_EQ(f.depth.size(), 640u * 480u);
  auto at = [&f](int u, int v) { return static_cast<std::size_t>(v) * f.width + u; };
  // Principal point hits the top face of the cube: 1.5 - 0.82 = 0.68 m.
  const std::size_t centre = at(320, 240);
  EXPECT_NEAR(f.depth[centre], 0.68, 1e-4);
  EXPECT_EQ(f.instance[centre], 0);
  // A pixel far from the centre sees the table top at 1.5 - 0.72 = 0.78 m (depth is z, not range).
  const std::size_t side = at(40, 240);
  EXPECT_EQ(f.instance[side], RenderedFrame::kTable);
  EXPECT_NEAR(f.depth[side], 0.78, 1e-4);
  // The cube's image width is 0.1 m * fx / 0.68 m.
  const int pixels = visiblePixelCounts(f, 1)[0];
  const double side_px = 0.1 * K.fx / 0.68;
  EXPECT_NEAR(pixels, side_px * side_px, 0.05 * side_px * side_px);
}

TEST(BoxScene, DemoSceneIsVisibleFromTheOrbitAndDetectionsAreNearTruth) {
  const BoxScene scene = BoxScene::demoScene();
  ASSERT_EQ(scene.objects.size(), 6u);
  // Camera 1.0 m from the table centre, 1.35 m high, looking at the table centre.
  const Eigen::Vector3d eye(-1.0, 0.0, 1.35), target(0.0, 0.0, 0.75);
  const Eigen::Vector3d z = (target - eye).normalized();
  const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();
  T_world_cam.linear() << x, y, z;
  T_world_cam.translation() = eye;
  const RenderedFrame f = scene.render(PinholeIntrinsics{}, T_world_cam);
  const auto counts = visiblePixelCounts(f, scene.objects.size());
  int visible = 0;
  for (int c : counts) visible += c > 300;
  EXPECT_GE(visible, 5);

  std::mt19937 rng(7);
  DetectionNoise noise;
  const auto dets = synthesizeDetections(scene, f, T_world_cam, noise, rng);
  EXPECT_EQ(static_cast<int>(dets.size()), visible);
  for (const RawDetection& d : dets) {
    const BoxObject* obj = nullptr;
    for (const auto& o : scene.objects) {
      if (o.class_name == d.class_name) obj = &o;
    }
    ASSERT_NE(obj, nullptr);
    const Eigen::Vector3d world = T_world_cam * d.position_cam;
    EXPECT_LT((world - obj->T_world_obj.translation()).norm(), 6 * noise.translation_sigma_m);
    EXPECT_NEAR(d.orientation_cam.norm(), 1.0, 1e-9);
    EXPECT_TRUE(d.box.valid());
    EXPECT_GE(d.score, noise.min_score);
  }
}

TEST(ClassPalette, StableAndDistinct) {
  const Rgb a = classColor("003_cracker_box");
  const Rgb b = classColor("003_cracker_box");
  const Rgb c = classColor("004_sugar_box");
  EXPECT_EQ(a.r, b.r);
  EXPECT_EQ(a.g, b.g);
  EXPECT_EQ(a.b, b.b);
  EXPECT_GT(std::abs(a.r - c.r) + std::abs(a.g - c.g) + std::abs(a.b - c.b), 0.05f);
  for (float v : {a.r, a.g, a.b}) {
    EXPECT_GE(v, 0.f);
    EXPECT_LE(v, 1.f);
  }
  const Rgb red = hsvToRgb(0.0, 1.0, 1.0);
  EXPECT_FLOAT_EQ(red.r, 1.f);
  EXPECT_FLOAT_EQ(red.g, 0.f);
}

}  // namespace
}  // namespace geofusion
