// Contact inference between surface features (plane-plane, plane-curve, curve-curve) with the
// support-direction and projection-overlap checks, on arrangements with known answers.
#include "geofusion/estimation/contacts.h"

#include "test_geometry.h"

#include <gtest/gtest.h>

namespace geofusion {
namespace {

using namespace test;  // NOLINT: the shared test helpers

const Eigen::Vector3d kGravity(0, 0, -1);

// Two feature pairs of one object pair and type are one contact to the user (the closer one);
// another type or another pair stays.
TEST(Contacts, OnePerPairAndTypeKeepsTheClosest) {
  FeatureContact a;
  a.object_a = -1, a.object_b = 2, a.type = ContactType::kPlanePlane, a.distance_residual = 0.004;
  FeatureContact b = a;
  b.distance_residual = -0.001;  // the closer one
  FeatureContact c = a;
  c.type = ContactType::kPlaneCurve;
  FeatureContact d = a;
  d.object_a = 3, d.object_b = 2;
  FeatureContact e = b;
  std::swap(e.object_a, e.object_b);  // the same pair the other way round
  e.distance_residual = 0.002;
  const std::vector<FeatureContact> out = onePerPairAndType({a, b, c, d, e});
  ASSERT_EQ(out.size(), 3u);
  EXPECT_DOUBLE_EQ(out[0].distance_residual, -0.001);
  EXPECT_EQ(out[1].type, ContactType::kPlaneCurve);
  EXPECT_EQ(out[2].object_a, 3);
}

TEST(Contacts, BoxOnTableIsOnePlanePlaneSupport) {
  const ObjectModel table = boxModel(1.0, 1.0, 0.04), box = boxModel(0.1, 0.16, 0.2);
  // Table top at z = 0; the box rests on it with a 1 mm gap (as physics leaves it).
  const std::vector<PosedModel> objects = {{&table, at(0, 0, -0.02)}, {&box, at(0.1, 0, 0.101)}};
  const auto contacts = findAllContacts(objects, kGravity);
  ASSERT_EQ(contacts.size(), 1u);
  const FeatureContact& c = contacts[0];
  EXPECT_EQ(c.type, ContactType::kPlanePlane);
  EXPECT_TRUE(c.support);
  EXPECT_EQ(c.object_a, 0);  // the table supports the box
  EXPECT_EQ(c.object_b, 1);
  EXPECT_NEAR(c.normal.z(), 1.0, 1e-9);
  EXPECT_NEAR(c.distance_residual, 0.001, 1e-6);
  EXPECT_NEAR(table.features.planes[c.feature_a.index].normal.z(), 1.0, 1e-9);
  EXPECT_NEAR(box.features.planes[c.feature_b.index].normal.z(), -1.0, 1e-9);
  // Listed the other way round, the table still comes first.
  const std::vector<PosedModel> swapped = {objects[1], objects[0]};
  const auto again = findAllContacts(swapped, kGravity);
  ASSERT_EQ(again.size(), 1u);
  EXPECT_EQ(again[0].object_a, 1);
}

TEST(Contacts, FloatingTiltedOrBesideTheTableIsNoContact) {
  const ObjectModel table = boxModel(1.0, 1.0, 0.04), box = boxModel(0.1, 0.16, 0.2);
  const PosedModel t{&table, at(0, 0, -0.02)};
  EXPECT_TRUE(findAllContacts({t, {&box, at(0, 0, 0.12)}}, kGravity).empty());  // 2 cm above
  EXPECT_TRUE(findAllContacts({t, {&box, at(0, 0, 0.1, rot(20, Eigen::Vector3d::UnitX()))}},
                              kGravity)
                  .empty());  // tilted 20 degrees
  // At table height but entirely beyond the table's edge: the projections do not overlap.
  EXPECT_TRUE(findAllContacts({t, {&box, at(0.6, 0, 0.1)}}, kGravity).empty());
}

TEST(Contacts, BoxesSideBySideTouchOnlyAsSideContacts) {
  const ObjectModel table = boxModel(1.0, 1.0, 0.04), box = boxModel(0.1, 0.1, 0.1);
  const std::vector<PosedModel> objects = {
      {&table, at(0, 0, -0.02)}, {&box, at(0, 0, 0.05)}, {&box, at(0.101, 0.02, 0.05)}};
  // Support only (the paper): both boxes on the table, nothing between them.
  const auto support = findAllContacts(objects, kGravity);
  EXPECT_EQ(support.size(), 2u);
  for (const auto& c : support) {
    EXPECT_EQ(c.object_a, 0);
    EXPECT_TRUE(c.support);
  }
  ContactConfig all;
  all.support_only = false;
  const auto contacts = findAllContacts(objects, kGravity, all);
  ASSERT_EQ(contacts.size(), 3u);
  const FeatureContact& side = contacts[2];
  EXPECT_EQ(side.type, ContactType::kPlanePlane);
  EXPECT_FALSE(side.support);
  EXPECT_NEAR(std::abs(side.normal.x()), 1.0, 1e-9);
}

TEST(Contacts, CanLyingOnABoxIsPlaneCurve) {
  const ObjectModel box = boxModel(0.2, 0.2, 0.1), can = canModel(0.033, 0.1);
  // Box top at z = 0.1; the can's axis along x, 0.033 + 0.001 above it.
  const std::vector<PosedModel> objects = {
      {&box, at(0, 0, 0.05)}, {&can, at(0.02, 0, 0.134, rot(90, Eigen::Vector3d::UnitY()))}};
  const auto contacts = findAllContacts(objects, kGravity);
  ASSERT_EQ(contacts.size(), 1u);
  EXPECT_EQ(contacts[0].type, ContactType::kPlaneCurve);
  EXPECT_TRUE(contacts[0].support);
  EXPECT_EQ(contacts[0].object_a, 0);
  EXPECT_FALSE(contacts[0].feature_b.plane);
  EXPECT_NEAR(can.features.curves[contacts[0].feature_b.index].radius_m, 0.033, 0.002);
}

TEST(Contacts, CrossedCansAreCurveCurve) {
  const ObjectModel can = canModel(0.033, 0.1);
  // Lower can along x, upper can along y resting across it: axes 2 r + 1 mm apart.
  const std::vector<PosedModel> objects = {
      {&can, at(0, 0, 0.033, rot(90, Eigen::Vector3d::UnitY()))},
      {&can, at(0, 0, 0.033 + 0.067, rot(90, Eigen::Vector3d::UnitX()))}};
  const auto contacts = findAllContacts(objects, kGravity);
  ASSERT_EQ(contacts.size(), 1u);
  EXPECT_EQ(contacts[0].type, ContactType::kCurveCurve);
  EXPECT_TRUE(contacts[0].support);
  EXPECT_EQ(contacts[0].object_a, 0);
  EXPECT_NEAR(contacts[0].normal.z(), 1.0, 1e-6);
  // Lifted 2 cm: no contact.
  const std::vector<PosedModel> apart = {objects[0],
                                         {&can, at(0, 0, 0.12, rot(90, Eigen::Vector3d::UnitX()))}};
  EXPECT_TRUE(findAllContacts(apart, kGravity).empty());
}

TEST(Contacts, BoxLeaningOnItsEdgeIsPlaneCurve) {
  const ObjectModel table = boxModel(1.0, 1.0, 0.04), box = boxModel(0.1, 0.1, 0.2);
  // Rotated 45 degrees about y: rests on one bottom edge, the edge 1 mm above the table top.
  const double half_diag = std::sqrt(0.05 * 0.05 + 0.1 * 0.1);
  const double lowest = half_diag * std::sin(45.0 * M_PI / 180.0 + std::atan2(0.05, 0.1));
  const std::vector<PosedModel> objects = {
      {&table, at(0, 0, -0.02)},
      {&box, at(0, 0, lowest + 0.001, rot(45, Eigen::Vector3d::UnitY()))}};
  const auto contacts = findAllContacts(objects, kGravity);
  ASSERT_EQ(contacts.size(), 1u);
  EXPECT_EQ(contacts[0].type, ContactType::kPlaneCurve);
  EXPECT_NEAR(box.features.curves[contacts[0].feature_b.index].radius_m, 0.0, 1e-9);
}

TEST(Contacts, ProjectionOverlapNeedsRealOverlap) {
  const std::vector<Eigen::Vector3d> square = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  const Eigen::Vector3d z = Eigen::Vector3d::UnitZ();
  std::vector<Eigen::Vector3d> shifted;
  for (const auto& p : square) shifted.push_back(p + Eigen::Vector3d(0.5, 0.5, 0.3));
  EXPECT_TRUE(projectionsOverlap(square, shifted, z, 0.1));
  EXPECT_FALSE(projectionsOverlap(square, shifted, z, 0.6));
  std::vector<Eigen::Vector3d> beside;
  for (const auto& p : square) beside.push_back(p + Eigen::Vector3d(1.0, 0.0, 0.0));
  EXPECT_FALSE(projectionsOverlap(square, beside, z, 0.01));  // shares an edge only
  EXPECT_TRUE(projectionsOverlap(square, beside, z, -0.01));
  const std::vector<Eigen::Vector3d> segment = {{0.2, 0.5, 1}, {0.8, 0.5, 1}};
  EXPECT_TRUE(projectionsOverlap(square, segment, z, 0.1));  // a segment inside the square
  const std::vector<Eigen::Vector3d> far_segment = {{2.2, 0.5, 1}, {2.8, 0.5, 1}};
  EXPECT_FALSE(projectionsOverlap(square, far_segment, z, 0.0));
}

}  // namespace
}  // namespace geofusion
