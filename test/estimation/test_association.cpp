// Data association pieces on constructed cases with known answers.
#include "geofusion/estimation/association.h"

#include "test_geometry.h"

#include <gtest/gtest.h>

#include <cmath>

namespace geofusion {
namespace {

using namespace test;  // NOLINT: the shared test helpers

TEST(Association, HungarianFindsTheOptimum) {
  Eigen::MatrixXd cost(3, 3);
  cost << 4, 1, 3,  //
      2, 0, 5,      //
      3, 2, 2;
  // Optimum: 0->1 (1), 1->0 (2), 2->2 (2) = 5.
  EXPECT_EQ(solveAssignment(cost), (std::vector<int>{1, 0, 2}));
  // More rows than columns: one row stays unassigned, the cheapest overall is kept.
  Eigen::MatrixXd tall(3, 2);
  tall << 1, 9,  //
      9, 1,      //
      5, 5;
  EXPECT_EQ(solveAssignment(tall), (std::vector<int>{0, 1, -1}));
  // Brute force agreement on random 5x7 matrices.
  std::srand(3);
  for (int trial = 0; trial < 20; ++trial) {
    Eigen::MatrixXd c = Eigen::MatrixXd::Random(5, 7).cwiseAbs();
    const auto sol = solveAssignment(c);
    double got = 0;
    for (int r = 0; r < 5; ++r) got += c(r, sol[static_cast<std::size_t>(r)]);
    std::vector<int> cols = {0, 1, 2, 3, 4, 5, 6};
    double best = 1e9;
    do {
      double s = 0;
      for (int r = 0; r < 5; ++r) s += c(r, cols[static_cast<std::size_t>(r)]);
      best = std::min(best, s);
    } while (std::next_permutation(cols.begin(), cols.end()));
    EXPECT_NEAR(got, best, 1e-9);
  }
}

TEST(Association, JointAssignmentBeatsTheGreedyOrder) {
  // Measurement 0 fits object 0 best and object 1 well; measurement 1 fits only object 0.
  Eigen::MatrixXd l(2, 2);
  l << 0.9, 0.8,  //
      0.85, 0.0;
  AssociationConfig joint, greedy;
  greedy.joint_assignment = false;
  EXPECT_EQ(associate(l, joint), (std::vector<int>{1, 0}));
  // The paper's order: the later measurement finds its object taken and starts a new one.
  EXPECT_EQ(associate(l, greedy), (std::vector<int>{0, -1}));
  // Below eps_new: a new object either way.
  Eigen::MatrixXd weak(1, 1);
  weak << 0.01;
  EXPECT_EQ(associate(weak, joint), (std::vector<int>{-1}));
  EXPECT_EQ(associate(weak, greedy), (std::vector<int>{-1}));
}

TEST(Association, TwoMeasurementsOfOneKeyframeNeverJoinOneObject) {
  Eigen::MatrixXd l(3, 1);
  l << 0.9, 0.95, 0.7;  // all want the only object
  for (bool joint : {true, false}) {
    AssociationConfig c;
    c.joint_assignment = joint;
    const auto a = associate(l, c);
    int to_object = 0;
    for (int j : a) to_object += j == 0;
    EXPECT_EQ(to_object, 1) << (joint ? "joint" : "greedy");
  }
}

TEST(Association, PoseLikelihoodIgnoresSymmetricRotations) {
  AssociationConfig c;
  Symmetry none, can, box;
  can.type = Symmetry::Type::kContinuous;
  box.type = Symmetry::Type::kDiscrete;
  box.rotations = {Eigen::Quaterniond(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitZ()))};
  const Eigen::Isometry3d a = at(0.1, 0.0, 0.8);
  const Eigen::Isometry3d spun = at(0.1, 0.0, 0.8, rot(70, Eigen::Vector3d::UnitZ()));
  const Eigen::Isometry3d flipped = at(0.1, 0.0, 0.8, rot(180, Eigen::Vector3d::UnitZ()));
  EXPECT_NEAR(poseLikelihood(can, a, spun, c), 1.0, 1e-9);
  EXPECT_LT(poseLikelihood(none, a, spun, c), 0.25);
  EXPECT_NEAR(poseLikelihood(box, a, flipped, c), 1.0, 1e-9);
  EXPECT_LT(poseLikelihood(none, a, flipped, c), 0.01);
  // Tilting a can's axis is not free.
  EXPECT_NEAR(symmetricRotationError(can, a.linear(), rot(30, Eigen::Vector3d::UnitX())),
              30 * M_PI / 180, 1e-9);
  // Translation: 1 sigma gives exp(-1/2).
  EXPECT_NEAR(poseLikelihood(none, a, at(0.1 + c.sigma_position_m, 0, 0.8), c), std::exp(-0.5),
              1e-9);
  // The closest discrete equivalent of the flipped box is the reference itself.
  EXPECT_TRUE(closestSymmetricEquivalent(box, a.linear(), flipped.linear()).isApprox(a.linear()));
}

TEST(Association, FalsePositiveScoreFollowsThePaper) {
  EXPECT_NEAR(falsePositiveScore(1.0, 1), 1.0 - 1.0 / (1.0 + std::exp(-1.0)), 1e-12);
  // More measurements and better consistency both lower it.
  EXPECT_LT(falsePositiveScore(0.9, 5), falsePositiveScore(0.9, 1));
  EXPECT_LT(falsePositiveScore(0.9, 3), falsePositiveScore(0.4, 3));
  EXPECT_NEAR(falsePositiveScore(0.0, 10), 1.0, 1e-12);
}

TEST(Association, BoxCollisionRatioBySeparatingAxes) {
  const Eigen::Vector3d half(0.05, 0.05, 0.05);
  EXPECT_NEAR(boxCollisionRatio(at(0, 0, 0), half, at(0, 0, 0), half), 1.0, 1e-9);
  EXPECT_NEAR(boxCollisionRatio(at(0, 0, 0), half, at(0.05, 0, 0), half), 0.5, 1e-9);
  EXPECT_EQ(boxCollisionRatio(at(0, 0, 0), half, at(0.2, 0, 0), half), 0.0);
  // A small box inside a big one: fully inside along every axis.
  EXPECT_NEAR(boxCollisionRatio(at(0, 0, 0), Eigen::Vector3d(0.2, 0.2, 0.2), at(0.01, 0, 0),
                                Eigen::Vector3d(0.02, 0.02, 0.02)),
              1.0, 1e-9);
  // Two parallel diagonal slabs 12.7 cm apart along their normal: the rotated face axis
  // separates them although their world-axis bounding boxes overlap.
  const Eigen::Vector3d slab(0.1, 0.005, 0.1);
  const double r = boxCollisionRatio(at(0, 0, 0, rot(45, Eigen::Vector3d::UnitZ())), slab,
                                     at(0.09, -0.09, 0.0, rot(45, Eigen::Vector3d::UnitZ())), slab);
  EXPECT_EQ(r, 0.0);
}

}  // namespace
}  // namespace geofusion
