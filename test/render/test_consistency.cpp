// Geometric consistency score f_gc on rendered tabletop scenes with realistic depth noise.
#include "geofusion/model/object_model.h"
#include "geofusion/render/consistency.h"

#include "table_scene.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>

namespace geofusion {
namespace {

using test::pose;
using test::sharedRenderer;
using test::TableScene;

Eigen::Isometry3d shifted(const Eigen::Isometry3d& T, const Eigen::Vector3d& d) {
  Eigen::Isometry3d out = T;
  out.translation() += d;
  return out;
}

Eigen::Isometry3d rotated(const Eigen::Isometry3d& T, const Eigen::Vector3d& axis_world,
                          double degrees) {
  Eigen::Isometry3d out = T;
  out.linear() = Eigen::AngleAxisd(degrees * M_PI / 180.0, axis_world.normalized()) * T.linear();
  return out;
}

TEST(ModifiedSigmoid, SpansZeroToOneMonotonically) {
  const ModifiedSigmoid s{0.3, 10.0};
  EXPECT_NEAR(s(0.0), 0.0, 1e-12);
  EXPECT_NEAR(s(1.0), 1.0, 1e-12);
  EXPECT_EQ(s(-0.5), s(0.0));
  EXPECT_EQ(s(1.5), s(1.0));
  double last = -1.0;
  for (double x = 0.0; x <= 1.0; x += 0.01) {
    EXPECT_GT(s(x), last);
    last = s(x);
  }
  EXPECT_GT(s(0.5), 0.8);  // half the points as inliers is still good evidence
  EXPECT_NEAR((ModifiedSigmoid{0.5, 0.0})(0.37), 0.37, 1e-12);
}

void checkScene(const ModelSet& models, const std::string& box_name, const std::string& can_name,
                const std::string& wrong_box, const std::string& wrong_can) {
  TableScene scene(models);
  const int box = scene.place(box_name, -0.05, 0.05, 0.4);
  const int can = scene.place(can_name, 0.14, -0.02);
  scene.renderObserved();

  for (int i : {box, can}) {
    const auto& o = scene.object(i);
    SCOPED_TRACE(o.model->name);
    const ConsistencyResult truth = scene.scoreTrue(i);
    ASSERT_TRUE(truth.determined);
    EXPECT_GT(truth.score, 0.85) << "r_in " << truth.r_in << " r_out " << truth.r_out << " r_occ "
                                 << truth.r_occ;
    EXPECT_LT(truth.r_out, 0.05);
    EXPECT_LT(truth.missing, truth.rendered / 100);  // silhouette edge of the simplified mesh

    const double ceiling = truth.score - 0.3;  // "clearly lower"
    const std::vector<Eigen::Vector3d> directions = {
        Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(),
        -Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ()};
    for (const Eigen::Vector3d& d : directions) {
      const ConsistencyResult s = scene.score(o.model, shifted(o.T_world_obj, 0.02 * d));
      EXPECT_LT(s.score, ceiling) << "shift 2 cm along " << d.transpose() << ": r_in " << s.r_in
                                  << " r_out " << s.r_out << " r_occ " << s.r_occ;
    }
    // 20 degrees about an axis that is not a symmetry axis (cans are symmetric about z).
    const Eigen::Vector3d axis = i == can ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitZ();
    const Eigen::Vector3d centre = o.T_world_obj.translation();
    for (double deg : {20.0, -20.0}) {
      Eigen::Isometry3d T = rotated(o.T_world_obj, axis, deg);
      T.translation() = centre;
      const ConsistencyResult s = scene.score(o.model, T);
      EXPECT_LT(s.score, ceiling) << "rotated " << deg << " deg: r_in " << s.r_in << " r_out "
                                  << s.r_out << " r_occ " << s.r_occ;
    }
    // The wrong class at the true pose (standing on the table like the true object).
    auto wrong = scene.model(i == can ? wrong_can : wrong_box);
    Eigen::Vector3f lo_true, hi_true, lo_wrong, hi_wrong;
    o.model->mesh.bounds(&lo_true, &hi_true);
    wrong->mesh.bounds(&lo_wrong, &hi_wrong);
    const Eigen::Isometry3d T_wrong =
        shifted(o.T_world_obj, Eigen::Vector3d(0, 0, lo_true.z() - lo_wrong.z()));
    const ConsistencyResult w = scene.score(wrong, T_wrong);
    EXPECT_LT(w.score, ceiling) << "wrong class " << wrong->name << ": r_in " << w.r_in << " r_out "
                                << w.r_out << " r_occ " << w.r_occ;
  }
}

TEST(Consistency, PrimitivesTruePoseHighPerturbedAndWrongClassClearlyLower) {
  checkScene(ModelSet::builtinPrimitives(), "003_cracker_box", "005_tomato_soup_can",
             "004_sugar_box", "002_master_chef_can");
}

TEST(Consistency, YcbMeshesTruePoseHighPerturbedAndWrongClassClearlyLower) {
  if (!test::haveYcb()) GTEST_SKIP() << "YCB-Video models not found at " << test::ycbDir();
  ModelSet models;
  std::vector<std::string> errors;
  ASSERT_TRUE(test::loadYcbModels(&models, &errors));
  checkScene(models, "003_cracker_box", "005_tomato_soup_can", "004_sugar_box",
             "002_master_chef_can");
}

TEST(Consistency, HalfHiddenObjectIsNotPunishedAsOutlier) {
  const ModelSet models = ModelSet::builtinPrimitives();
  TableScene scene(models);
  // A soup can behind the cracker box, slid sideways until about half of it shows.
  double best_gap = 1.0, best_x = 0.0;
  for (double x = 0.0; x <= 0.12; x += 0.005) {
    scene.clear();
    scene.place("003_cracker_box", 0.0, 0.0, 0.0);
    scene.place("005_tomato_soup_can", x, 0.16);
    scene.renderObserved();
    const double gap = std::abs(scene.visibleFraction(1) - 0.5);
    if (gap < best_gap) best_gap = gap, best_x = x;
  }
  scene.clear();
  scene.place("003_cracker_box", 0.0, 0.0, 0.0);
  const int can = scene.place("005_tomato_soup_can", best_x, 0.16);
  scene.renderObserved();
  const double visible = scene.visibleFraction(can);
  ASSERT_GT(visible, 0.35);
  ASSERT_LT(visible, 0.65);
  const ConsistencyResult r = scene.scoreTrue(can);
  EXPECT_NEAR(r.r_occ, 1.0 - visible, 0.05);
  EXPECT_LT(r.r_out, 0.05);
  EXPECT_GT(r.score, 0.75) << "r_in " << r.r_in << " r_occ " << r.r_occ;
  // The same can floating 10 cm above the table in front of the box is a false positive.
  const auto& o = scene.object(can);
  const ConsistencyResult floating =
      scene.score(o.model, shifted(o.T_world_obj, Eigen::Vector3d(0.1, -0.25, 0.1)));
  ASSERT_TRUE(floating.determined);
  EXPECT_GT(floating.r_out, 0.8);
  EXPECT_LT(floating.score, 0.05);
}

// Issue 22: a depth refinement's pose is scored by moving the first rendering's points instead of
// rendering again; unmoved it is compareDepth exactly, moved by centimetres it agrees with a new
// rendering.
TEST(Consistency, MovedRenderingScoresLikeARenderingAtTheMovedPose) {
  const ModelSet models = ModelSet::builtinPrimitives();
  TableScene scene(models);
  const int box = scene.place("003_cracker_box", -0.05, 0.0, 0.4);
  scene.place("005_tomato_soup_can", 0.1, 0.1);
  scene.renderObserved();
  const auto& o = scene.object(box);
  const Eigen::Isometry3d T_cam = scene.T_world_cam().inverse() * o.T_world_obj;
  // The detection 2 cm too near along the ray (floating in front of what the camera sees) and
  // turned by 3 degrees.
  Eigen::Isometry3d T_detected = T_cam;
  T_detected.translation() -= 0.02 * T_cam.translation().normalized();
  T_detected.linear() = Eigen::AngleAxisd(0.05, Eigen::Vector3d::UnitY()) * T_cam.linear();
  const RenderedImages* rendered = scene.scorer().render(o.model, T_detected, scene.K());
  ASSERT_NE(rendered, nullptr);
  const RenderedImages first = *rendered;
  const ConsistencyConfig& config = scene.scorer().config();
  const ConsistencyResult same = compareDepth(first, scene.depth(), scene.K(), config);
  const ConsistencyResult unmoved =
      compareMovedDepth(first, Eigen::Isometry3d::Identity(), scene.depth(), scene.K(), config);
  EXPECT_EQ(unmoved.rendered, same.rendered);
  EXPECT_EQ(unmoved.inliers, same.inliers);
  EXPECT_EQ(unmoved.outliers, same.outliers);
  EXPECT_EQ(unmoved.occluded, same.occluded);
  EXPECT_LT(same.r_in, 0.3);  // the detected pose is visibly off
  EXPECT_GT(same.r_out, 0.5);
  // Moved back to the true pose: as good as rendering it there.
  const ConsistencyResult moved =
      compareMovedDepth(first, T_cam * T_detected.inverse(), scene.depth(), scene.K(), config);
  const ConsistencyResult rendered_true = scene.scoreTrue(box);
  ASSERT_TRUE(moved.determined && rendered_true.determined);
  EXPECT_NEAR(moved.r_in, rendered_true.r_in, 0.05);
  EXPECT_NEAR(moved.r_out, rendered_true.r_out, 0.05);
  EXPECT_NEAR(moved.r_occ, rendered_true.r_occ, 0.05);
  EXPECT_NEAR(moved.score, rendered_true.score, 0.05);
}

TEST(Consistency, PointsAreClassedByTheirDistanceAlongTheRay) {
  // A flat rendering at 1 m in the image's corner (rays up to 20 degrees off the axis) against
  // observed depths placed at chosen distances along each pixel's ray, on both sides of eps_res
  // and eps_out: every point lands in the class of its distance.
  const PinholeIntrinsics K;
  const ConsistencyConfig config;  // eps_res 1 cm, eps_out 2 cm
  RenderedImages rendered;
  rendered.region = PixelBox{520, 400, 120, 80};
  rendered.depth.assign(static_cast<std::size_t>(rendered.region.area()), 1.f);
  std::vector<float> observed(static_cast<std::size_t>(K.width * K.height), 0.f);
  const std::vector<double> along = {-0.05,  -0.0105, -0.0095, 0.0,    0.0095,
                                     0.0105, 0.015,   0.0195,  0.0205, 0.08};
  ConsistencyResult expected;
  int k = 0;
  for (int v = rendered.region.y; v < rendered.region.y + rendered.region.height; ++v) {
    for (int u = rendered.region.x; u < rendered.region.x + rendered.region.width; ++u, ++k) {
      ++expected.rendered;
      if (k % 11 == 10) {
        ++expected.missing;
        continue;
      }
      const double a = along[static_cast<std::size_t>(k % 11)];
      const double ray = std::hypot(1.0, (u - K.cx) / K.fx, (v - K.cy) / K.fy);
      observed[static_cast<std::size_t>(v * K.width + u)] = static_cast<float>(1.0 + a / ray);
      ASSERT_NEAR(distanceAlongRay(K, u, v, 1.0 + a / ray, 1.0), a, 1e-9);
      if (a < -config.eps_res)
        ++expected.occluded;
      else if (a <= config.eps_res)
        ++expected.inliers;
      else if (a > config.eps_out)
        ++expected.outliers;
      else
        ++expected.uncertain;
    }
  }
  const DepthImageView view{observed.data(), K.width, K.height};
  for (const ConsistencyResult& r :
       {compareDepth(rendered, view, K, config),
        compareMovedDepth(rendered, Eigen::Isometry3d::Identity(), view, K, config)}) {
    EXPECT_EQ(r.rendered, expected.rendered);
    EXPECT_EQ(r.missing, expected.missing);
    EXPECT_EQ(r.occluded, expected.occluded);
    EXPECT_EQ(r.inliers, expected.inliers);
    EXPECT_EQ(r.outliers, expected.outliers);
    EXPECT_EQ(r.uncertain, expected.uncertain);
  }
}

TEST(Camera, NearestPixelRoundsAndStaysInTheImage) {
  const PinholeIntrinsics K;  // 640 x 480
  int u = -1, v = -1;
  EXPECT_TRUE(K.nearestPixel({-0.49, 0.49}, &u, &v));
  EXPECT_EQ(u, 0);
  EXPECT_EQ(v, 0);
  EXPECT_TRUE(K.nearestPixel({12.5, 7.51}, &u, &v));
  EXPECT_EQ(u, 13);
  EXPECT_EQ(v, 8);
  EXPECT_TRUE(K.nearestPixel({639.49, 479.49}, &u, &v));
  EXPECT_EQ(u, 639);
  EXPECT_EQ(v, 479);
  EXPECT_FALSE(K.nearestPixel({-0.51, 10.0}, &u, &v));
  EXPECT_FALSE(K.nearestPixel({639.5, 10.0}, &u, &v));
  EXPECT_FALSE(K.nearestPixel({10.0, 479.5}, &u, &v));
  EXPECT_FALSE(K.nearestPixel({std::nan(""), 10.0}, &u, &v));
}

TEST(Consistency, MissingDepthIsNeitherInlierNorOutlier) {
  const ModelSet models = ModelSet::builtinPrimitives();
  TableScene scene(models);
  const int box = scene.place("003_cracker_box", 0.0, 0.0, 0.3);
  scene.renderObserved();
  const ConsistencyResult full = scene.scoreTrue(box);
  ASSERT_TRUE(full.determined);

  // Holes (0 and NaN) over every other row of the object: those points become "missing" and the
  // ratios are taken over the rest, so the score barely moves.
  RenderedImages& obs = scene.observed();
  const int W = scene.K().width;
  for (std::size_t p = 0; p < obs.depth.size(); ++p) {
    const int row = static_cast<int>(p) / W;
    if (obs.instance[p] == box + 1 && row % 2 == 0)
      obs.depth[p] = (row % 4 == 0) ? 0.f : std::nanf("");
  }
  const ConsistencyResult holes = scene.scoreTrue(box);
  ASSERT_TRUE(holes.determined);
  EXPECT_NEAR(static_cast<double>(holes.missing) / holes.rendered, 0.5, 0.05);
  EXPECT_EQ(holes.inliers + holes.outliers + holes.occluded + holes.uncertain + holes.missing,
            holes.rendered);
  EXPECT_NEAR(holes.score, full.score, 0.05);
  EXPECT_NEAR(holes.r_out, full.r_out, 0.02);

  // No depth at all where the object projects: undetermined, neutral score.
  std::fill(obs.depth.begin(), obs.depth.end(), 0.f);
  const ConsistencyResult none = scene.scoreTrue(box);
  EXPECT_FALSE(none.determined);
  EXPECT_EQ(none.missing, none.rendered);
  EXPECT_DOUBLE_EQ(none.score, scene.scorer().config().undetermined_score);
}

TEST(Consistency, UnrenderablePosesAreUndetermined) {
  const ModelSet models = ModelSet::builtinPrimitives();
  TableScene scene(models);
  const int box = scene.place("003_cracker_box", 0.0, 0.0);
  scene.renderObserved();
  const auto m = scene.object(box).model;
  const ConsistencyResult behind = scene.score(m, pose(Eigen::Vector3d(0.0, -3.0, 0.5)));
  EXPECT_FALSE(behind.determined);
  Eigen::Isometry3d nan_pose = scene.object(box).T_world_obj;
  nan_pose.translation().x() = std::nan("");
  EXPECT_FALSE(scene.score(m, nan_pose).determined);
  EXPECT_FALSE(scene.score(nullptr, scene.object(box).T_world_obj).determined);
}

TEST(Consistency, StrideSubsamplesWithoutChangingTheVerdict) {
  const ModelSet models = ModelSet::builtinPrimitives();
  TableScene scene(models);
  const int box = scene.place("004_sugar_box", 0.02, 0.0, 0.7);
  scene.renderObserved();
  const ConsistencyResult dense = scene.scoreTrue(box);
  ConsistencyConfig sparse_config;
  sparse_config.pixel_stride = 2;
  scene.scorer().setConfig(sparse_config);
  const ConsistencyResult sparse = scene.scoreTrue(box);
  EXPECT_NEAR(sparse.rendered, dense.rendered / 4.0, dense.rendered * 0.05);
  EXPECT_NEAR(sparse.score, dense.score, 0.05);
}

}  // namespace
}  // namespace geofusion
