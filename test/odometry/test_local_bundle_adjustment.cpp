// The visual odometry's local bundle adjustment on a generated keyframe window: points in front
// of five cameras along a path, observed with pixel and depth noise (and a share of gross
// outliers); poses and points perturbed as tracking drift would. The adjustment must bring the
// poses back near the truth, find the outliers, and hold the fixed keyframe.
#include "geofusion/odometry/local_bundle_adjustment.h"

#include <gtest/gtest.h>

#include <random>
#include <vector>

namespace geofusion {
namespace {

struct Window {
  PinholeIntrinsics K;
  std::vector<Eigen::Isometry3d> truth, poses;
  std::vector<Eigen::Vector3d> true_points, points;
  std::vector<BundleObservation> observations;
  std::vector<char> gross;  ///< observations made outliers on purpose
};

// Five cameras 8 cm apart looking at a wall of points 1.5-2.5 m away; every point seen from each
// camera it projects into, with 1 px and 0.005 z^2 depth noise; one observation in 40 moved by
// 30 px. Poses after the first drift by up to 2 cm and 1 deg, points by 2 cm.
Window makeWindow(unsigned seed, double noise = 1.0) {
  Window w;
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int k = 0; k < 5; ++k) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation() = Eigen::Vector3d(0.08 * k, 0.01 * k, 0.0);
    T.linear() = Eigen::AngleAxisd(0.03 * k, Eigen::Vector3d::UnitY()).toRotationMatrix();
    w.truth.push_back(T);
  }
  for (int j = 0; j < 400; ++j)
    w.true_points.emplace_back(-1.2 + 2.6 * u(rng), -0.8 + 1.6 * u(rng), 1.5 + u(rng));
  for (int k = 0; k < 5; ++k) {
    for (int j = 0; j < 400; ++j) {
      const Eigen::Vector3d p = w.truth[k].inverse() * w.true_points[j];
      const Eigen::Vector2d uv = w.K.project(p);
      if (uv.x() < 0 || uv.y() < 0 || uv.x() >= w.K.width || uv.y() >= w.K.height) continue;
      BundleObservation o;
      o.keyframe = k, o.point = j, o.level = 0;
      o.uv = uv + noise * Eigen::Vector2d(n(rng), n(rng));
      o.depth_m = p.z() + noise * 0.005 * p.z() * p.z() * n(rng);
      const bool bad = u(rng) < noise / 40.0;
      if (bad) o.uv += Eigen::Vector2d(30.0, -30.0);
      w.observations.push_back(o);
      w.gross.push_back(bad);
    }
  }
  w.poses = w.truth;
  for (int k = 1; k < 5; ++k) {
    Eigen::Isometry3d D = Eigen::Isometry3d::Identity();
    D.translation() = 0.02 * Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
    D.linear() =
        Eigen::AngleAxisd(M_PI / 180.0, Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized())
            .toRotationMatrix();
    w.poses[k] = w.truth[k] * D;
  }
  for (const Eigen::Vector3d& X : w.true_points)
    w.points.push_back(X + 0.02 * Eigen::Vector3d(n(rng), n(rng), n(rng)) / std::sqrt(3.0));
  return w;
}

double worstPoseError(const std::vector<Eigen::Isometry3d>& a,
                      const std::vector<Eigen::Isometry3d>& b) {
  double worst = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k)
    worst = std::max(worst, (a[k].translation() - b[k].translation()).norm());
  return worst;
}

TEST(LocalBundleAdjustment, BringsADriftedWindowBackAndFindsTheOutliers) {
  for (unsigned seed : {1u, 2u, 3u}) {
    Window w = makeWindow(seed);
    const double before = worstPoseError(w.poses, w.truth);
    EXPECT_GT(before, 0.015);
    std::vector<char> fixed = {1, 0, 0, 0, 0}, outlier;
    LocalBundleAdjustmentOptions options;
    options.iterations = 10;
    const BundleAdjustmentResult r =
        localBundleAdjustment(w.K, options, w.observations, fixed, &w.poses, &w.points, &outlier);
    ASSERT_TRUE(r.solved) << r.problem;
    EXPECT_LT(r.final_cost, r.initial_cost);
    EXPECT_TRUE(w.poses[0].isApprox(w.truth[0], 1e-12)) << "the fixed keyframe moved";
    const double after = worstPoseError(w.poses, w.truth);
    // The noise leaves about 1-2 mm in each keyframe (about 300 points each, 1 to 3 cm of depth
    // noise): the worst of the four within 5 mm, from 2 cm.
    EXPECT_LT(after, 0.005) << "seed " << seed << ": worst keyframe " << 100 * after << " cm off";
    std::vector<int> views(w.points.size(), 0);
    for (const BundleObservation& o : w.observations) ++views[static_cast<std::size_t>(o.point)];
    int found = 0, gross = 0, false_alarms = 0;
    for (std::size_t i = 0; i < outlier.size(); ++i) {
      if (views[static_cast<std::size_t>(w.observations[i].point)] < 2) continue;  // not adjusted
      gross += w.gross[i];
      found += w.gross[i] && outlier[i];
      false_alarms += !w.gross[i] && outlier[i];
    }
    EXPECT_EQ(found, gross) << "seed " << seed;
    EXPECT_LT(false_alarms, static_cast<int>(outlier.size()) / 20) << "seed " << seed;
  }
}

TEST(LocalBundleAdjustment, NoiselessWindowExactly) {
  Window w = makeWindow(5, 0.0);
  std::vector<char> fixed = {1, 0, 0, 0, 0}, outlier;
  LocalBundleAdjustmentOptions options;
  options.iterations = 20;
  const BundleAdjustmentResult r =
      localBundleAdjustment(w.K, options, w.observations, fixed, &w.poses, &w.points, &outlier);
  ASSERT_TRUE(r.solved) << r.problem;
  EXPECT_LT(worstPoseError(w.poses, w.truth), 1e-4);
  EXPECT_EQ(r.outliers, 0);
}

TEST(LocalBundleAdjustment, ReportsBadInputAndChangesNothing) {
  Window w = makeWindow(4);
  const std::vector<Eigen::Isometry3d> poses = w.poses;
  std::vector<char> outlier;
  // A fixed flag missing.
  BundleAdjustmentResult r =
      localBundleAdjustment(w.K, {}, w.observations, {1, 0}, &w.poses, &w.points, &outlier);
  EXPECT_FALSE(r.solved);
  EXPECT_FALSE(r.problem.empty());
  // An observation of a point that does not exist.
  std::vector<BundleObservation> bad = w.observations;
  bad[3].point = 100000;
  r = localBundleAdjustment(w.K, {}, bad, {1, 0, 0, 0, 0}, &w.poses, &w.points, &outlier);
  EXPECT_FALSE(r.solved);
  // A point seen from one keyframe only: nothing to adjust.
  std::vector<BundleObservation> one = {w.observations.front()};
  r = localBundleAdjustment(w.K, {}, one, {1, 0, 0, 0, 0}, &w.poses, &w.points, &outlier);
  EXPECT_FALSE(r.solved);
  for (std::size_t k = 0; k < poses.size(); ++k) EXPECT_TRUE(w.poses[k].isApprox(poses[k]));
}

}  // namespace
}  // namespace geofusion
