// OSMesa renderer: metric depth, pixel alignment, instance ids, regions, colour, bad input.
#include "geofusion/model/object_model.h"
#include "geofusion/render/renderer.h"
#include "geofusion/simulation/box_scene.h"

#include "test_data.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>

namespace geofusion {
namespace {

// One renderer for the whole test program: one context, as the package uses it.
OffscreenRenderer& sharedRenderer() {
  static OffscreenRenderer renderer;
  return renderer;
}

Eigen::Isometry3d pose(const Eigen::Vector3d& t,
                       const Eigen::AngleAxisd& r = Eigen::AngleAxisd(0,
                                                                      Eigen::Vector3d::UnitZ())) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = r.toRotationMatrix();
  T.translation() = t;
  return T;
}

TEST(Renderer, ContextIsCreated) {
  ASSERT_TRUE(sharedRenderer().ok()) << sharedRenderer().error();
}

TEST(Renderer, FrontoParallelPlaneReadsBackItsDistanceWithin1mm) {
  OffscreenRenderer& r = sharedRenderer();
  const PinholeIntrinsics K;
  // A 4 m x 4 m x 1 cm slab whose front face is at z = 0.8 m fills the view.
  const MeshHandle slab = r.addMesh(makeBox(Eigen::Vector3d(4.0, 4.0, 0.01)));
  ASSERT_GE(slab, 0) << r.error();
  for (double z : {0.4, 0.8, 1.5, 3.0}) {
    RenderItem item;
    item.mesh = slab;
    item.T_cam_model = pose(Eigen::Vector3d(0, 0, z + 0.005));
    RenderedImages out;
    ASSERT_TRUE(r.render(K, {item}, &out)) << r.error();
    ASSERT_EQ(out.depth.size(), static_cast<std::size_t>(K.width * K.height));
    double worst = 0.0;
    for (float d : out.depth) worst = std::max(worst, std::abs(d - z));
    EXPECT_LT(worst, 1e-3) << "plane at " << z << " m";
  }
}

TEST(Renderer, TiltedPlaneMatchesRayIntersectionAtEveryPixel) {
  OffscreenRenderer& r = sharedRenderer();
  const PinholeIntrinsics K;
  const MeshHandle slab = r.addMesh(makeBox(Eigen::Vector3d(4.0, 4.0, 0.01)));
  // Front face: plane through (0.1, -0.05, 1.0) with normal n, tilted 35 degrees.
  const Eigen::AngleAxisd tilt(35.0 * M_PI / 180.0, Eigen::Vector3d(1, 1, 0).normalized());
  const Eigen::Vector3d n = tilt * -Eigen::Vector3d::UnitZ();  // towards the camera
  const Eigen::Vector3d p0(0.1, -0.05, 1.0);
  RenderItem item;
  item.mesh = slab;
  item.T_cam_model = pose(p0 - 0.005 * n, tilt);
  RenderedImages out;
  ASSERT_TRUE(r.render(K, {item}, &out)) << r.error();
  double worst = 0.0;
  int drawn = 0;
  for (int v = 0; v < K.height; ++v) {
    for (int u = 0; u < K.width; ++u) {
      const Eigen::Vector3d ray((u - K.cx) / K.fx, (v - K.cy) / K.fy, 1.0);
      const double z = n.dot(p0) / n.dot(ray);  // depth along the optical axis
      const float d = out.depthAt(u, v);
      if (d <= 0.f) continue;
      ++drawn;
      worst = std::max(worst, std::abs(d - z));
    }
  }
  EXPECT_EQ(drawn, K.width * K.height);
  EXPECT_LT(worst, 1e-3);
}

TEST(Renderer, BoxSilhouetteAndDepthAgreeWithAnalyticRayCasting) {
  // The same box seen by the analytic ray caster of box_scene and by OSMesa: depth agrees where
  // both see it, the silhouettes differ at most on the boundary pixels.
  OffscreenRenderer& r = sharedRenderer();
  const PinholeIntrinsics K;
  BoxScene scene;
  scene.table_height_m = -10.0;  // out of sight; the floor plane z = 0 contains the camera
  BoxObject box;
  box.size = Eigen::Vector3d(0.164, 0.213, 0.072);
  box.T_world_obj = pose(Eigen::Vector3d(0.03, -0.02, 0.9),
                         Eigen::AngleAxisd(0.6, Eigen::Vector3d(0.3, 1.0, 0.2).normalized()));
  scene.objects.push_back(box);
  const RenderedFrame analytic = scene.render(K, Eigen::Isometry3d::Identity());

  RenderItem item;
  item.mesh = r.addMesh(makeBox(box.size));
  item.T_cam_model = box.T_world_obj;
  item.instance_id = 9;
  RenderedImages out;
  ASSERT_TRUE(r.render(K, {item}, &out)) << r.error();

  int both = 0, only_one = 0, analytic_pixels = 0;
  double worst = 0.0;
  for (int i = 0; i < K.width * K.height; ++i) {
    const bool a = analytic.instance[i] == 0, b = out.instance[i] == 9;
    EXPECT_EQ(b, out.depth[i] > 0.f);
    analytic_pixels += a;
    if (a && b) {
      ++both;
      worst = std::max(worst, static_cast<double>(std::abs(analytic.depth[i] - out.depth[i])));
    } else if (a != b) {
      ++only_one;
    }
  }
  ASSERT_GT(analytic_pixels, 5000);
  EXPECT_LT(worst, 1e-3);
  // Perimeter of the silhouette is a few hundred pixels; disagreement only along it.
  EXPECT_LT(only_one, 0.03 * analytic_pixels) << only_one << " of " << analytic_pixels;
}

TEST(Renderer, NearerObjectWinsAndSixteenBitIdsSurvive) {
  OffscreenRenderer& r = sharedRenderer();
  const PinholeIntrinsics K;
  const MeshHandle cube = r.addMesh(makeBox(Eigen::Vector3d(0.1, 0.1, 0.1)));
  RenderItem back, front;
  back.mesh = front.mesh = cube;
  back.T_cam_model = pose(Eigen::Vector3d(0.0, 0.0, 1.0));
  back.instance_id = 7;
  front.T_cam_model = pose(Eigen::Vector3d(0.05, 0.0, 0.7));
  front.instance_id = 300;  // needs the high byte
  RenderedImages out;
  ASSERT_TRUE(r.render(K, {front, back}, &out)) << r.error();
  // Centre pixel: the back cube's face only (front cube starts 0.05 - 0.05 = 0 m right of axis
  // at 0.7 m, i.e. at u = cx). Left of centre: back cube; right: front cube.
  const int v = 240;
  EXPECT_EQ(out.instanceAt(300, v), 7);
  EXPECT_NEAR(out.depthAt(300, v), 0.95, 1e-3);
  EXPECT_EQ(out.instanceAt(340, v), 300);
  EXPECT_NEAR(out.depthAt(340, v), 0.65, 1e-3);
  EXPECT_EQ(out.instanceAt(5, 5), 0);
  EXPECT_EQ(out.depthAt(5, 5), 0.f);
  std::set<std::uint16_t> ids(out.instance.begin(), out.instance.end());
  EXPECT_EQ(ids, (std::set<std::uint16_t>{0, 7, 300}));
}

TEST(Renderer, RegionRenderEqualsCropOfFullRender) {
  OffscreenRenderer& r = sharedRenderer();
  const PinholeIntrinsics K;
  RenderItem item;
  item.mesh = r.addMesh(makeCylinder(0.0335, 0.102));
  item.T_cam_model = pose(Eigen::Vector3d(-0.12, 0.07, 0.85),
                          Eigen::AngleAxisd(1.1, Eigen::Vector3d(1, 0.2, 0).normalized()));
  const PixelBox region = r.projectedRegion(K, item.mesh, item.T_cam_model);
  ASSERT_TRUE(region.valid());
  EXPECT_LT(region.area(), K.width * K.height / 20);
  RenderedImages full, part;
  ASSERT_TRUE(r.render(K, {item}, &full));
  ASSERT_TRUE(r.render(K, {item}, &part, region));
  ASSERT_EQ(part.depth.size(), static_cast<std::size_t>(region.area()));
  int drawn_full = 0, drawn_part = 0, mismatched = 0;
  double worst = 0.0;
  for (int v = 0; v < K.height; ++v) {
    for (int u = 0; u < K.width; ++u) {
      const float a = full.depthAt(u, v), b = part.depthAt(u, v);
      drawn_full += a > 0.f;
      drawn_part += b > 0.f;
      if ((a > 0.f) != (b > 0.f)) ++mismatched;
      if (a > 0.f && b > 0.f) worst = std::max(worst, static_cast<double>(std::abs(a - b)));
    }
  }
  EXPECT_GT(drawn_full, 1000);
  EXPECT_EQ(drawn_part, drawn_full);  // the region holds the whole object
  EXPECT_EQ(mismatched, 0);
  EXPECT_LT(worst, 2e-4);
}

TEST(Renderer, ProjectedRegionHandlesOutsideAndBehind) {
  OffscreenRenderer& r = sharedRenderer();
  const PinholeIntrinsics K;
  const MeshHandle cube = r.addMesh(makeBox(Eigen::Vector3d(0.1, 0.1, 0.1)));
  EXPECT_FALSE(r.projectedRegion(K, cube, pose(Eigen::Vector3d(0, 0, -1.0))).valid());
  EXPECT_FALSE(r.projectedRegion(K, cube, pose(Eigen::Vector3d(5.0, 0, 1.0))).valid());
  const PixelBox straddle = r.projectedRegion(K, cube, pose(Eigen::Vector3d(0, 0, 0.0)));
  EXPECT_EQ(straddle.area(), K.width * K.height);
  EXPECT_FALSE(r.projectedRegion(K, 12345, pose(Eigen::Vector3d(0, 0, 1.0))).valid());
}

TEST(Renderer, ColourPassUsesItemColourAndLeavesBackgroundBlack) {
  OffscreenRenderer& r = sharedRenderer();
  const PinholeIntrinsics K;
  RenderItem item;
  item.mesh = r.addMesh(makeBox(Eigen::Vector3d(0.2, 0.2, 0.2)));
  item.T_cam_model = pose(Eigen::Vector3d(0, 0, 1.0));
  item.color = Eigen::Vector3f(1.0f, 0.0f, 0.0f);
  RenderedImages out;
  ASSERT_TRUE(
      r.render(K, {item}, &out, PixelBox{}, OffscreenRenderer::kColor | OffscreenRenderer::kDepth));
  ASSERT_EQ(out.rgb.size(), static_cast<std::size_t>(K.width * K.height * 3));
  EXPECT_TRUE(out.instance.empty());
  const std::size_t centre = (240u * K.width + 320u) * 3u;
  EXPECT_GT(out.rgb[centre], 200);  // lit face towards the head light: bright red
  EXPECT_LT(out.rgb[centre + 1], 10);
  EXPECT_LT(out.rgb[centre + 2], 10);
  EXPECT_EQ(out.rgb[0] + out.rgb[1] + out.rgb[2], 0);
  EXPECT_NEAR(out.depthAt(320, 240), 0.9, 1e-3);
}

TEST(Renderer, YcbTextureShowsUp) {
  if (!test::haveYcb()) GTEST_SKIP() << "YCB-Video models not found at " << test::ycbDir();
  TriangleMesh mesh;
  std::string error;
  ASSERT_TRUE(loadMesh(test::ycbDir() + "/003_cracker_box/textured.obj", &mesh, &error)) << error;
  ASSERT_FALSE(mesh.texture_path.empty());
  OffscreenRenderer& r = sharedRenderer();
  const PinholeIntrinsics K;
  RenderItem item;
  item.mesh = r.addMesh(mesh);
  ASSERT_GE(item.mesh, 0) << r.error();
  item.T_cam_model =
      pose(Eigen::Vector3d(0, 0, 0.6), Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY()));
  RenderedImages out;
  ASSERT_TRUE(r.render(K, {item}, &out, PixelBox{},
                       OffscreenRenderer::kColor | OffscreenRenderer::kInstance));
  // A printed cardboard box: many distinct colours inside the silhouette, mostly not grey.
  std::set<int> colours;
  int saturated = 0, inside = 0;
  for (int i = 0; i < K.width * K.height; ++i) {
    if (out.instance[i] == 0) continue;
    ++inside;
    const int R = out.rgb[3 * i], G = out.rgb[3 * i + 1], B = out.rgb[3 * i + 2];
    colours.insert((R / 16) * 256 + (G / 16) * 16 + B / 16);
    saturated += std::max({R, G, B}) - std::min({R, G, B}) > 60;
  }
  ASSERT_GT(inside, 10000);
  EXPECT_GT(colours.size(), 50u);
  EXPECT_GT(saturated, inside / 4);  // the cracker box is mostly red and yellow print
}

TEST(Renderer, ClosedMeshesSkipBackFacesOthersAreTwoSided) {
  OffscreenRenderer& r = sharedRenderer();
  const PinholeIntrinsics K;
  const TriangleMesh closed = makeBox(Eigen::Vector3d(0.2, 0.2, 0.2));
  TriangleMesh open = closed, flipped = closed;
  open.triangles.clear();
  for (const auto& t : closed.triangles) {  // without its -z face, the one facing the camera
    const bool near_face = closed.vertices[t[0]].z() < 0 && closed.vertices[t[1]].z() < 0 &&
                           closed.vertices[t[2]].z() < 0;
    if (!near_face) open.triangles.push_back(t);
  }
  for (auto& t : flipped.triangles) std::swap(t[1], t[2]);
  const MeshHandle h_closed = r.addMesh(closed), h_open = r.addMesh(open),
                   h_flipped = r.addMesh(flipped);
  ASSERT_GE(h_closed, 0);
  ASSERT_GE(h_open, 0);
  ASSERT_GE(h_flipped, 0);
  EXPECT_TRUE(r.cullsBackFaces(h_closed));
  EXPECT_FALSE(r.cullsBackFaces(h_open));
  EXPECT_FALSE(r.cullsBackFaces(h_flipped));
  // 1 m ahead: the near face at 0.9 m; through the missing face, the far inside wall at 1.1 m.
  const Eigen::Isometry3d T = pose(Eigen::Vector3d(0.0, 0.0, 1.0));
  const int u = 320, v = 240;
  for (const auto& [mesh, expected] :
       {std::pair<MeshHandle, double>{h_closed, 0.9}, {h_open, 1.1}, {h_flipped, 0.9}}) {
    RenderedImages out;
    ASSERT_TRUE(r.render(K, {{mesh, T, 1}}, &out, PixelBox{}, OffscreenRenderer::kDepth));
    EXPECT_NEAR(out.depthAt(u, v), expected, 1e-3) << "mesh " << mesh;
  }
}

TEST(Renderer, BadInputIsRefusedWithAReason) {
  OffscreenRenderer& r = sharedRenderer();
  const PinholeIntrinsics K;
  EXPECT_EQ(r.addMesh(TriangleMesh()), -1);
  EXPECT_NE(r.error().find("empty"), std::string::npos);
  TriangleMesh broken = makeBox(Eigen::Vector3d(0.1, 0.1, 0.1));
  broken.triangles.emplace_back(0, 1, 999);
  EXPECT_EQ(r.addMesh(broken), -1);
  EXPECT_NE(r.error().find("index"), std::string::npos);

  TriangleMesh missing_texture = makeBox(Eigen::Vector3d(0.1, 0.1, 0.1));
  missing_texture.texture_path = "/nonexistent/texture.png";
  const MeshHandle untextured = r.addMesh(missing_texture);
  EXPECT_GE(untextured, 0);  // still drawn, untextured
  EXPECT_NE(r.error().find("/nonexistent/texture.png"), std::string::npos);

  RenderedImages out;
  RenderItem item;
  item.mesh = 4242;
  EXPECT_FALSE(r.render(K, {item}, &out));
  item.mesh = untextured;
  item.T_cam_model.translation().x() = std::nan("");
  EXPECT_FALSE(r.render(K, {item}, &out));
  EXPECT_TRUE(out.depth.empty());
  item.T_cam_model = Eigen::Isometry3d::Identity();
  PinholeIntrinsics huge = K;
  huge.width = 5000;
  EXPECT_FALSE(r.render(huge, {item}, &out));
  PinholeIntrinsics zero = K;
  zero.fx = 0.0;
  EXPECT_FALSE(r.render(zero, {item}, &out));
  // Nothing to draw is not an error: empty images of the right size.
  ASSERT_TRUE(r.render(K, {}, &out));
  EXPECT_EQ(out.depth.size(), static_cast<std::size_t>(K.width * K.height));
}

}  // namespace
}  // namespace geofusion
