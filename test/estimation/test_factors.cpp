// The optimisation stages' factors alone (estimation/factors/): residuals on hand-made cases with
// known answers, and the automatic Jacobians against central numeric differentiation at random
// poses.
#include "geofusion/estimation/factors/contact_factor.h"
#include "geofusion/estimation/factors/pose_block.h"
#include "geofusion/estimation/factors/relative_pose_factor.h"
#include "geofusion/estimation/factors/separation_factor.h"
#include "geofusion/estimation/optimization.h"

#include "test_geometry.h"

#include <ceres/autodiff_cost_function.h>
#include <ceres/numeric_diff_cost_function.h>
#include <gtest/gtest.h>

#include <random>

namespace geofusion {
namespace {

using test::at;
using test::rot;

template <typename Factor>
Eigen::Matrix<double, Factor::kResiduals, 1> residual(const Factor& f, const Eigen::Isometry3d& A,
                                                      const Eigen::Isometry3d& B) {
  const PoseBlock a = PoseBlock::of(A), b = PoseBlock::of(B);
  Eigen::Matrix<double, Factor::kResiduals, 1> r;
  EXPECT_TRUE(f(a.data(), b.data(), r.data()));
  return r;
}

// Largest difference between the automatic and the central numeric Jacobians of `f` at (A, B),
// relative to the largest Jacobian entry.
template <typename Factor>
double jacobianMismatch(const Factor& f, const Eigen::Isometry3d& A, const Eigen::Isometry3d& B) {
  constexpr int N = Factor::kResiduals;
  ceres::AutoDiffCostFunction<Factor, N, 7, 7> autodiff(new Factor(f));
  ceres::NumericDiffCostFunction<Factor, ceres::CENTRAL, N, 7, 7> numeric(new Factor(f));
  PoseBlock a = PoseBlock::of(A), b = PoseBlock::of(B);
  const double* params[2] = {a.data(), b.data()};
  double r_auto[N], r_num[N];
  Eigen::Matrix<double, N, 7, Eigen::RowMajor> Ja_auto, Jb_auto, Ja_num, Jb_num;
  double* J_auto[2] = {Ja_auto.data(), Jb_auto.data()};
  double* J_num[2] = {Ja_num.data(), Jb_num.data()};
  EXPECT_TRUE(autodiff.Evaluate(params, r_auto, J_auto));
  EXPECT_TRUE(numeric.Evaluate(params, r_num, J_num));
  for (int i = 0; i < N; ++i) EXPECT_NEAR(r_auto[i], r_num[i], 1e-12);
  const double scale =
      std::max({1.0, Ja_auto.cwiseAbs().maxCoeff(), Jb_auto.cwiseAbs().maxCoeff()});
  return std::max((Ja_auto - Ja_num).cwiseAbs().maxCoeff(),
                  (Jb_auto - Jb_num).cwiseAbs().maxCoeff()) /
         scale;
}

Eigen::Isometry3d randomPose(std::mt19937* rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Eigen::Vector3d axis(u(*rng), u(*rng), u(*rng));
  return at(0.5 * u(*rng), 0.5 * u(*rng), 0.5 * u(*rng), rot(180.0 * u(*rng), axis));
}

TEST(RelativePoseFactor, ZeroAtTheMeasurementAndKnownResidualsOffIt) {
  const Eigen::Isometry3d z = at(0.3, -0.1, 0.8, rot(30, {1, 2, 0}));
  const Eigen::Isometry3d A = at(1.0, 2.0, 0.5, rot(70, {0, 0, 1}));
  const RelativePoseFactor f(z, /*w_p=*/100.0, /*w_q=*/10.0, false, Eigen::Vector3d::UnitZ());
  EXPECT_LT(residual(f, A, A * z).norm(), 1e-12);

  // 1 cm off along the measured frame's x, expressed in a's frame: w_p * 0.01 on the first row.
  const Eigen::Isometry3d shifted = A * at(0.01, 0, 0) * z;
  const auto r_t = residual(f, A, shifted);
  EXPECT_NEAR(r_t[0], 1.0, 1e-9);
  EXPECT_NEAR(r_t.segment<2>(1).norm(), 0.0, 1e-9);
  EXPECT_NEAR(r_t.tail<3>().norm(), 0.0, 1e-9);

  // 0.1 rad about the measured frame's y: w_q * 2 sin(0.05) on the rotation row of y.
  const Eigen::Isometry3d turned = A * z * at(0, 0, 0, rot(0.1 * 180.0 / M_PI, {0, 1, 0}));
  const auto r_q = residual(f, A, turned);
  EXPECT_NEAR(r_q.head<3>().norm(), 0.0, 1e-9);
  EXPECT_NEAR(r_q[4], 10.0 * 2.0 * std::sin(0.05), 1e-9);
  EXPECT_NEAR(r_q[3], 0.0, 1e-9);
  EXPECT_NEAR(r_q[5], 0.0, 1e-9);
}

TEST(RelativePoseFactor, SymmetryAxisLeftFree) {
  const Eigen::Isometry3d z = at(0.2, 0.0, 0.7);
  const Eigen::Isometry3d spun = z * at(0, 0, 0, rot(40, {0, 0, 1}));  // about the model's z
  const RelativePoseFactor free(z, 100.0, 10.0, true, Eigen::Vector3d::UnitZ());
  const RelativePoseFactor fixed(z, 100.0, 10.0, false, Eigen::Vector3d::UnitZ());
  const Eigen::Isometry3d I = Eigen::Isometry3d::Identity();
  EXPECT_LT(residual(free, I, spun).norm(), 1e-9);
  EXPECT_GT(residual(fixed, I, spun).norm(), 5.0);
  // A tilt of the axis is still penalised.
  const Eigen::Isometry3d tilted = z * at(0, 0, 0, rot(10, {1, 0, 0}));
  EXPECT_GT(residual(free, I, tilted).norm(), 1.0);
}

TEST(RelativePoseFactor, JacobiansMatchNumericDifferentiation) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 20; ++trial) {
    const RelativePoseFactor f(randomPose(&rng), 100.0, 12.5, trial % 2 == 0,
                               Eigen::Vector3d(0.3, -0.2, 1.0));
    EXPECT_LT(jacobianMismatch(f, randomPose(&rng), randomPose(&rng)), 1e-6) << "trial " << trial;
  }
}

// Two boxes stacked: A's top face (normal +z at z = +h/2) under B's bottom face (normal -z).
ContactFactor planePlane(double w_p, double w_q) {
  ContactFactor f;
  f.type = ContactType::kPlanePlane;
  f.c_a = {0, 0, 0.05}, f.n_a = {0, 0, 1};
  f.c_b = {0, 0, -0.03}, f.n_b = {0, 0, -1};
  f.w_p = w_p, f.w_q = w_q;
  return f;
}

TEST(ContactFactor, PlanePlaneZeroWhenTouchingAndTheGapOtherwise) {
  const ContactFactor f = planePlane(1000.0, 100.0);
  const Eigen::Isometry3d A = at(0.1, 0.2, 0.75);
  EXPECT_LT(residual(f, A, A * at(0.02, -0.01, 0.08)).norm(), 1e-9);  // sliding is free
  const auto r = residual(f, A, A * at(0, 0, 0.085));                 // 5 mm above
  EXPECT_NEAR(r[3], 1000.0 * 0.005, 1e-9);
  EXPECT_NEAR(r.head<3>().norm(), 0.0, 1e-9);
  // B tilted by 0.1 rad: the normals no longer oppose.
  const auto tilted = residual(f, A, A * at(0, 0, 0.08, rot(0.1 * 180.0 / M_PI, {1, 0, 0})));
  EXPECT_NEAR(tilted.head<3>().norm(), 100.0 * 2.0 * std::sin(0.05), 1e-9);
}

TEST(ContactFactor, PlaneCurveZeroForACanLyingOnAPlane) {
  ContactFactor f;
  f.type = ContactType::kPlaneCurve;
  f.c_a = {0, 0, 0.0}, f.n_a = {0, 0, 1};  // the table's top face
  f.c_b = {0, 0, 0}, f.n_b = {0, 0, 1};    // the can's axis, model z
  f.r_b = 0.033;
  f.w_p = 1000.0, f.w_q = 100.0;
  const Eigen::Isometry3d table = Eigen::Isometry3d::Identity();
  const Eigen::Isometry3d lying = at(0.1, 0.0, 0.033, rot(90, {1, 0, 0}));  // axis along -y
  EXPECT_LT(residual(f, table, lying).norm(), 1e-9);
  const auto high = residual(f, table, at(0.1, 0.0, 0.043, rot(90, {1, 0, 0})));
  EXPECT_NEAR(high[1], 1000.0 * 0.01, 1e-9);
  const auto upright = residual(f, table, at(0.1, 0.0, 0.033));
  EXPECT_NEAR(std::abs(upright[0]), 100.0, 1e-9);  // axis along the normal: not lying
}

TEST(ContactFactor, CurveCurveZeroForTouchingParallelCans) {
  ContactFactor f;
  f.type = ContactType::kCurveCurve;
  f.n_a = f.n_b = {0, 0, 1};
  f.r_a = 0.033, f.r_b = 0.04;
  f.w_p = 1000.0;
  const Eigen::Isometry3d A = at(0, 0, 0.8);
  EXPECT_LT(residual(f, A, at(0.073, 0, 0.82)).norm(), 1e-6);
  EXPECT_NEAR(residual(f, A, at(0.083, 0, 0.8))[0], 1000.0 * 0.01, 1e-6);
  EXPECT_NEAR(residual(f, A, at(0.063, 0, 0.8))[0], -1000.0 * 0.01, 1e-6);  // interpenetrating
}

TEST(ContactFactor, JacobiansMatchNumericDifferentiation) {
  std::mt19937 rng(11);
  for (ContactType type :
       {ContactType::kPlanePlane, ContactType::kPlaneCurve, ContactType::kCurveCurve}) {
    for (int trial = 0; trial < 10; ++trial) {
      ContactFactor f = planePlane(1000.0, 100.0);
      f.type = type;
      f.n_b = (type == ContactType::kCurveCurve && trial % 2 == 0) ? Eigen::Vector3d(0, 0, 1)
                                                                   : Eigen::Vector3d(1, 0, 0.2);
      f.r_a = 0.02, f.r_b = 0.03;
      EXPECT_LT(jacobianMismatch(f, randomPose(&rng), randomPose(&rng)), 1e-6)
          << toString(type) << " trial " << trial;
    }
  }
}

// Two bodies found 4 mm into each other at a point; b must leave a along +x.
TEST(SeparationFactor, OneSidedAlongTheNormal) {
  SeparationFactor f;
  f.p_a = Eigen::Vector3d(0.05, 0, 0), f.p_b = Eigen::Vector3d(-0.046, 0, 0);
  f.normal = Eigen::Vector3d::UnitX(), f.depth = 0.004, f.weight = 1000.0;
  const auto residual = [&](const Eigen::Isometry3d& Ta, const Eigen::Isometry3d& Tb) {
    const PoseBlock a = PoseBlock::of(Ta), b = PoseBlock::of(Tb);
    double r = -1.0;
    EXPECT_TRUE(f(a.data(), b.data(), &r));
    return r;
  };
  const Eigen::Isometry3d A = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d B = Eigen::Isometry3d::Identity();
  B.translation() = Eigen::Vector3d(0.096, 0, 0);  // where it was found: the full depth
  EXPECT_NEAR(residual(A, B), 4.0, 1e-9);
  B.translation().x() = 0.098;  // half way out
  EXPECT_NEAR(residual(A, B), 2.0, 1e-9);
  B.translation() = Eigen::Vector3d(0.096, 0.05, 0.02);  // along the contact: no help
  EXPECT_NEAR(residual(A, B), 4.0, 1e-9);
  B.translation() = Eigen::Vector3d(0.100, 0, 0);  // touching
  EXPECT_NEAR(residual(A, B), 0.0, 1e-9);
  B.translation() = Eigen::Vector3d(0.150, 0, 0);  // apart: never pulled together
  EXPECT_EQ(residual(A, B), 0.0);
}

TEST(SolveStatus, OnlyUsableOutcomesAreUsedAndNamesRoundTrip) {
  for (SolveStatus s : {SolveStatus::kNotRun, SolveStatus::kConverged, SolveStatus::kIterationLimit,
                        SolveStatus::kNothingToSolve, SolveStatus::kFailed,
                        SolveStatus::kCostIncreased, SolveStatus::kBadInput}) {
    SolveStatus back = SolveStatus::kNotRun;
    ASSERT_TRUE(parseSolveStatus(toString(s), &back));
    EXPECT_EQ(back, s);
  }
  EXPECT_TRUE(usable(SolveStatus::kConverged));
  EXPECT_TRUE(usable(SolveStatus::kIterationLimit));
  EXPECT_FALSE(usable(SolveStatus::kFailed));
  EXPECT_FALSE(usable(SolveStatus::kCostIncreased));
  SolveStatus ignored;
  EXPECT_FALSE(parseSolveStatus("fine", &ignored));
}

TEST(SolveStatus, StagesReportBadInputAndLeaveThePosesAlone) {
  std::vector<Eigen::Isometry3d> cams{at(0, 0, 0), at(1, 0, 0)};
  std::vector<Eigen::Isometry3d> odom{at(0, 0, 0)};  // one short: inconsistent
  std::vector<Eigen::Isometry3d> objects{at(0, 0, 1)};
  const ObjectModel box = test::boxModel(0.1, 0.1, 0.1);
  const StageOneSummary one = optimizeStageOne(&cams, odom, &objects, {&box}, {}, StageOneConfig());
  EXPECT_EQ(one.status, SolveStatus::kBadInput);
  EXPECT_FALSE(one.solved);
  EXPECT_TRUE(cams[1].isApprox(at(1, 0, 0)));
  std::vector<Eigen::Isometry3d> poses{at(0, 0, 1)};
  const StageTwoSummary two = optimizeStageTwo(&poses, {&box}, {}, {}, nullptr, StageTwoConfig());
  EXPECT_EQ(two.status, SolveStatus::kBadInput);
  EXPECT_TRUE(poses[0].isApprox(at(0, 0, 1)));
}

}  // namespace
}  // namespace geofusion
