// Contact inference between surface features (plane-plane, plane-curve, curve-curve, plane-edge)
// and their kinds (support, leaning, side), with the
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
  EXPECT_TRUE(c.support());
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

// A narrow box (4 cm deep) on one bottom edge, tilted 10 degrees, its lowest edge 1 mm above the
// table: its bottom face is 10 degrees off and its centre 4.5 mm up, within the distance threshold.
// It rests on the edge, so the contact is the table's plane with that edge (a box's edges are
// 0-radius curve features: plane-curve; a plane-plane factor would turn the box flat); tilted 4
// degrees, the bottom face is the contact.
TEST(Contacts, AFaceTenDegreesOffIsNoPlanePlaneContact) {
  const ObjectModel table = boxModel(1.0, 1.0, 0.04), box = boxModel(0.04, 0.16, 0.2);
  const PosedModel t{&table, at(0, 0, -0.02)};
  auto on_edge = [&](double deg) {  // the edge at x = -0.02 of the bottom 1 mm above the table
    const Eigen::Matrix3d R = rot(deg, Eigen::Vector3d::UnitY());
    const Eigen::Vector3d p = Eigen::Vector3d(0, 0, 0.001) - R * Eigen::Vector3d(-0.02, 0, -0.1);
    return PosedModel{&box, at(p.x(), p.y(), p.z(), R)};
  };
  const auto tilted = findAllContacts({t, on_edge(-10)}, kGravity);
  ASSERT_EQ(tilted.size(), 1u);
  EXPECT_EQ(tilted[0].type, ContactType::kPlaneCurve);
  EXPECT_NEAR(box.features.curves[tilted[0].feature_b.index].radius_m, 0.0, 1e-9);
  EXPECT_TRUE(tilted[0].support());
  EXPECT_NEAR(tilted[0].distance_residual, 0.001, 2e-4);
  ContactConfig fourteen_degrees;  // the threshold before: the face made the contact
  fourteen_degrees.eps_n_pp = 0.03;
  const auto before = findAllContacts({t, on_edge(-10)}, kGravity, fourteen_degrees);
  ASSERT_EQ(before.size(), 1u);
  EXPECT_EQ(before[0].type, ContactType::kPlanePlane);
  const auto nearly_flat = findAllContacts({t, on_edge(-4)}, kGravity);
  ASSERT_EQ(nearly_flat.size(), 1u);
  EXPECT_EQ(nearly_flat[0].type, ContactType::kPlanePlane);
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
  ContactConfig support_only;
  support_only.support_only = true;
  const auto support = findAllContacts(objects, kGravity, support_only);
  EXPECT_EQ(support.size(), 2u);
  for (const auto& c : support) {
    EXPECT_EQ(c.object_a, 0);
    EXPECT_TRUE(c.support());
  }
  const auto contacts = findAllContacts(objects, kGravity);
  ASSERT_EQ(contacts.size(), 3u);
  const FeatureContact& side = contacts[2];
  EXPECT_EQ(side.type, ContactType::kPlanePlane);
  EXPECT_EQ(side.kind, ContactKind::kSide);
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
  EXPECT_TRUE(contacts[0].support());
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
  EXPECT_TRUE(contacts[0].support());
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

// A clamp (a thin box) leaning at 30 degrees with its face on the rim of an upright can: the rim
// is no feature of the can, so it is a plane-edge contact, leaning, with the clamp's face normal.
TEST(Contacts, ClampLeaningOnACanIsOneLeaningContact) {
  const ObjectModel can = canModel(0.033, 0.1), clamp = boxModel(0.02, 0.08, 0.18);
  const double theta = 30.0 * M_PI / 180.0, gap = 0.001;
  const Eigen::Vector3d rim(0.033, 0, 0.1);                        // the rim point it rests on
  const Eigen::Vector3d n(-std::cos(theta), 0, -std::sin(theta));  // the face's normal, to the can
  const Eigen::Vector3d u(-std::sin(theta), 0, std::cos(theta));   // the clamp's long axis
  // The clamp's frame: its x along -n (thickness), z along u (length); the rim 3 cm above the
  // middle of the face.
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear().col(0) = -n, T.linear().col(1) = Eigen::Vector3d::UnitY(), T.linear().col(2) = u;
  T.translation() = rim - n * (gap + 0.01) - u * 0.03;
  const std::vector<PosedModel> objects = {{&can, at(0, 0, 0.05)}, {&clamp, T}};
  const auto contacts = onePerPairAndType(findAllContacts(objects, kGravity));
  ASSERT_EQ(contacts.size(), 1u);
  const FeatureContact& c = contacts[0];
  EXPECT_EQ(c.type, ContactType::kPlaneEdge);
  EXPECT_EQ(c.kind, ContactKind::kLeaning);
  EXPECT_NEAR(c.distance_residual, gap, 1e-4);
  // The normal is the clamp's face normal, from the plane's object to the other.
  const Eigen::Vector3d from_clamp = c.object_a == 1 ? c.normal : Eigen::Vector3d(-c.normal);
  EXPECT_GT(from_clamp.dot(n), 0.999);
  // The touching point is on the rim, in the can's frame (model centre 5 cm below the top).
  const FeatureRef& edge = c.object_a == 1 ? c.feature_b : c.feature_a;
  EXPECT_EQ(edge.index, -1);
  EXPECT_NEAR(c.edge_point.z(), 0.05, 1e-3);
  EXPECT_NEAR(Eigen::Vector2d(c.edge_point.x(), c.edge_point.y()).norm(), 0.033, 2e-3);
  // Lifted 2 cm off the rim along the normal: nothing.
  Eigen::Isometry3d off = T;
  off.translation() -= n * 0.02;
  EXPECT_TRUE(findAllContacts({objects[0], {&clamp, off}}, kGravity).empty());
}

// Estimates interpenetrate: a mug 9 mm into the can it stands on (as hand-annotated YCB-Video
// poses do) is still a support contact, with the interpenetration as its distance term; deeper
// than max_penetration_m it is not.
TEST(Contacts, InterpenetratingEstimatesStillTouch) {
  const ObjectModel can = canModel(0.033, 0.1), mug = canModel(0.04, 0.09);
  const std::vector<PosedModel> sunk = {{&can, at(0, 0, 0.05)}, {&mug, at(0, 0, 0.145 - 0.009)}};
  const auto contacts = findAllContacts(sunk, kGravity);
  ASSERT_EQ(onePerPairAndType(contacts).size(), 1u);
  EXPECT_EQ(contacts[0].type, ContactType::kPlanePlane);
  EXPECT_TRUE(contacts[0].support());
  EXPECT_EQ(contacts[0].object_a, 0);
  EXPECT_NEAR(contacts[0].distance_residual, -0.009, 1e-6);
  ContactConfig strict;
  strict.max_penetration_m = 0.005;
  EXPECT_TRUE(findAllContacts(sunk, kGravity, strict).empty());
}

// Hysteresis: a pair in contact at the last keyframe keeps it a little beyond the thresholds
// that make a new contact, so a gap wobbling about eps_c_pp does not make it blink.
TEST(Contacts, AHeldContactHasLooserThresholds) {
  const ObjectModel table = boxModel(1.0, 1.0, 0.04), box = boxModel(0.1, 0.1, 0.1);
  const std::vector<PosedModel> objects = {{&table, at(0, 0, -0.02)}, {&box, at(0, 0, 0.057)}};
  ContactConfig cfg;  // eps_c_pp 6 mm, hysteresis 1.5: held up to 9 mm
  EXPECT_TRUE(findAllContacts(objects, kGravity, cfg).empty());
  const auto held = findAllContacts(objects, kGravity, cfg, {{0, 1}});
  ASSERT_EQ(held.size(), 1u);
  EXPECT_NEAR(held[0].distance_residual, 0.007, 1e-6);
  EXPECT_TRUE(held[0].held);  // reported, not a constraint for stage II
  // Within the thresholds of a new contact, a held pair's contact is an ordinary one.
  const std::vector<PosedModel> near = {objects[0], {&box, at(0, 0, 0.053)}};
  const auto again = findAllContacts(near, kGravity, cfg, {{0, 1}});
  ASSERT_EQ(again.size(), 1u);
  EXPECT_FALSE(again[0].held);
  cfg.hysteresis = 1.0;
  EXPECT_TRUE(findAllContacts(objects, kGravity, cfg, {{0, 1}}).empty());
  const std::vector<PosedModel> far = {objects[0], {&box, at(0, 0, 0.060)}};
  EXPECT_TRUE(findAllContacts(far, kGravity, ContactConfig(), {{0, 1}}).empty());
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
