// BOP's pose errors (bop_metrics.h) on cases with known answers: identity, a known shift, a turn
// about the axis of a can whose appearance is symmetric (0) or not (the chord of the turn), a
// half-turn symmetric label, and the projection of a known shift (MSPD).
#include "geofusion/evaluation/bop_metrics.h"
#include "geofusion/evaluation/vsd.h"
#include "geofusion/render/renderer.h"

#include <gtest/gtest.h>

#include <cmath>

namespace geofusion {
namespace {

ObjectModel tunaCan(const Symmetry& appearance) {
  ObjectModel m = *ModelSet::builtinPrimitives().find("007_tuna_fish_can");  // r 42.5, h 34 mm
  m.appearance_symmetry = appearance;
  return m;
}

Eigen::Isometry3d poseAt(double x, double y, double z) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 1, 0).normalized()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(x, y, z);
  return T;
}

Eigen::Isometry3d turnedAboutZ(const Eigen::Isometry3d& T, double angle) {
  Eigen::Isometry3d out = T;
  out.linear() = T.linear() * Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return out;
}

double largestRadius(const BopModel& m) {
  double r = 0.0;
  for (const auto& p : m.points) r = std::max(r, (p - m.centre).head<2>().norm());
  return r;
}

TEST(BopMetrics, ModelDiameterAndSymmetries) {
  const BopModel plain = bopModelOf(tunaCan(Symmetry()));
  EXPECT_NEAR(plain.diameter_m, std::hypot(0.085, 0.034), 0.002);
  EXPECT_EQ(plain.symmetries.size(), 1u);
  const ObjectModel untextured = *ModelSet::builtinPrimitives().find("007_tuna_fish_can");
  EXPECT_EQ(bopModelOf(untextured).symmetries.size(), 315u);
  Symmetry half;
  half.type = Symmetry::Type::kDiscrete;
  half.rotations.emplace_back(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitZ()));
  EXPECT_EQ(bopModelOf(tunaCan(half)).symmetries.size(), 2u);
}

TEST(BopMetrics, IdentityAndAKnownShift) {
  const BopModel m = bopModelOf(tunaCan(Symmetry()));
  const Eigen::Isometry3d T = poseAt(0.05, -0.02, 0.7);
  EXPECT_NEAR(mssdError(m, T, T), 0.0, 1e-12);
  EXPECT_NEAR(mspdError(m, T, T, PinholeIntrinsics()), 0.0, 1e-9);
  Eigen::Isometry3d shifted = T;
  shifted.translation() += Eigen::Vector3d(0.003, -0.004, 0.0);  // 5 mm across the view
  EXPECT_NEAR(mssdError(m, shifted, T), 0.005, 1e-9);
  // Across the view at depth z, a shift d moves each point by about f d / z pixels.
  const PinholeIntrinsics K;
  const double mspd = mspdError(m, shifted, T, K);
  EXPECT_NEAR(mspd, K.fx * 0.005 / 0.7, 0.6);
}

TEST(BopMetrics, ACanTurnedAboutItsAxis) {
  const Eigen::Isometry3d T = poseAt(0.0, 0.0, 0.8);
  const Eigen::Isometry3d turned = turnedAboutZ(T, 60.0 * M_PI / 180.0);
  // Untextured (appearance continuous): the turn costs nothing but the discretisation.
  const BopModel smooth = bopModelOf(*ModelSet::builtinPrimitives().find("007_tuna_fish_can"));
  EXPECT_LT(mssdError(smooth, turned, T), 0.0006);  // half a 1.14-degree step at 42.5 mm
  // Labelled (appearance none): the chord of 60 degrees at the largest radius.
  const BopModel labelled = bopModelOf(tunaCan(Symmetry()));
  // (within 0.01 mm: the points' box centre, the turn's centre, is the origin within float error)
  EXPECT_NEAR(mssdError(labelled, turned, T), 2.0 * largestRadius(labelled) * std::sin(M_PI / 6),
              1e-5);
  EXPECT_GT(mspdError(labelled, turned, T, PinholeIntrinsics()), 20.0);
  // A half-turn symmetric label: 180 degrees is free, 60 is not.
  Symmetry half;
  half.type = Symmetry::Type::kDiscrete;
  half.rotations.emplace_back(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitZ()));
  const BopModel chef = bopModelOf(tunaCan(half));
  EXPECT_NEAR(mssdError(chef, turnedAboutZ(T, M_PI), T), 0.0, 1e-5);
  EXPECT_GT(mssdError(chef, turned, T), 0.03);
}

TEST(BopMetrics, BehindTheCameraIsInfinite) {
  const BopModel m = bopModelOf(tunaCan(Symmetry()));
  Eigen::Isometry3d behind = poseAt(0.0, 0.0, -0.5);
  EXPECT_TRUE(std::isinf(mspdError(m, behind, poseAt(0.0, 0.0, 0.5), PinholeIntrinsics())));
  ObjectModel empty;
  EXPECT_TRUE(std::isinf(mssdError(bopModelOf(empty), behind, behind)));
}

// VSD (vsd.h) of a can in front of the camera, the test image the can itself rendered: nothing
// wrong at the true pose; 2 cm along the ray, wrong at BOP's smallest tau (4.5 mm) and right at
// its largest (45 mm); turned about its axis, the same surface (VSD does not see it).
TEST(BopMetrics, VisibleSurfaceDiscrepancy) {
  auto renderer = std::make_shared<OffscreenRenderer>();
  ASSERT_TRUE(renderer->ok()) << renderer->error();
  const ObjectModel can = *ModelSet::builtinPrimitives().find("007_tuna_fish_can");
  const BopModel m = bopModelOf(can);
  const PinholeIntrinsics K;
  const Eigen::Isometry3d T = poseAt(0.02, 0.01, 0.6);
  VsdScorer vsd(renderer);
  ASSERT_TRUE(vsd.setScene(K, {{&can, T}}));
  const std::vector<double> exact = vsd.errors(can, T, T, m.diameter_m);
  ASSERT_EQ(exact.size(), 10u);
  for (double e : exact) EXPECT_NEAR(e, 0.0, 1e-9);
  Eigen::Isometry3d farther = T;
  farther.translation() *= (0.62 / 0.6);  // 2 cm farther along the ray
  const std::vector<double> off = vsd.errors(can, farther, T, m.diameter_m);
  EXPECT_GT(off.front(), 0.9);
  EXPECT_LT(off.back(), 0.2);
  const std::vector<double> turned = vsd.errors(can, turnedAboutZ(T, 1.0), T, m.diameter_m);
  EXPECT_LT(turned.front(), 0.05);
  // Nothing in view: the worst error; no scene: nothing computed.
  Eigen::Isometry3d behind = T;
  behind.translation().z() = -1.0;
  EXPECT_EQ(vsd.errors(can, behind, behind, m.diameter_m), std::vector<double>(10, 1.0));
  VsdScorer unset(renderer);
  EXPECT_TRUE(unset.errors(can, T, T, m.diameter_m).empty());
}

}  // namespace
}  // namespace geofusion
