// What the rviz panel and the markers show of a map (ros/map_inspection.h, labelLevels), no master.
#include "geofusion/ros/map_inspection.h"
#include "geofusion/ros/map_messages.h"

#include <gtest/gtest.h>

#include <cmath>

namespace geofusion {
namespace {

geofusion::MapObject object(uint32_t id, double x, double y, double z) {
  geofusion::MapObject o;
  o.id = id;
  o.class_name = "box" + std::to_string(id);
  o.state = geofusion::MapObject::STATE_CONFIRMED;
  o.pose.pose.position.x = x;
  o.pose.pose.position.y = y;
  o.pose.pose.position.z = z;
  o.pose.pose.orientation.w = 1.0;
  o.bbox_size.x = o.bbox_size.y = o.bbox_size.z = 0.1;
  return o;
}

geofusion::ContactRelation contact(uint32_t a, uint32_t b, uint8_t kind) {
  geofusion::ContactRelation c;
  c.object_a = a;
  c.object_b = b;
  c.kind = kind;
  c.type = geofusion::ContactRelation::PLANE_PLANE;
  c.a_supports_b = kind != geofusion::ContactRelation::KIND_SIDE;
  return c;
}

// A box (1) on the table, a can (2) on the box, a brick (3) beside the box; one tentative (4).
geofusion::ObjectMap stack() {
  geofusion::ObjectMap map;
  map.header.frame_id = "map";
  map.objects = {object(1, 0, 0, 0.05), object(2, 0, 0, 0.15), object(3, 0.1, 0, 0.05)};
  map.tentative = {object(4, 0.5, 0, 0.05)};
  map.tentative[0].state = geofusion::MapObject::STATE_TENTATIVE;
  map.contacts = {contact(0, 1, geofusion::ContactRelation::KIND_SUPPORT),
                  contact(1, 2, geofusion::ContactRelation::KIND_SUPPORT),
                  contact(1, 3, geofusion::ContactRelation::KIND_SIDE)};
  map.contacts[0].point_a.z = 0.0;
  return map;
}

TEST(MapInspection, ContactsAreNamedFromEitherSide) {
  const auto map = stack();
  EXPECT_EQ(describeContact(map.contacts[0], 1), "rests on the table");
  EXPECT_EQ(describeContact(map.contacts[1], 1), "supports 2");
  EXPECT_EQ(describeContact(map.contacts[1], 2), "rests on 1");
  EXPECT_EQ(describeContact(map.contacts[2], 3), "beside 1");
  auto leaning = contact(2, 5, geofusion::ContactRelation::KIND_LEANING);
  EXPECT_EQ(describeContact(leaning, 5), "leans on 2");
  EXPECT_EQ(contactKindName(geofusion::ContactRelation::KIND_LEANING), "leaning");
  EXPECT_EQ(contactTypeName(geofusion::ContactRelation::PLANE_EDGE), "P2E");
}

TEST(MapInspection, SelectionHighlightsTheObjectAndItsContacts) {
  const auto map = stack();
  const auto none = selectionMarkers(map, 0);
  ASSERT_EQ(none.markers.size(), 1u);
  EXPECT_EQ(none.markers[0].action, visualization_msgs::Marker::DELETEALL);
  EXPECT_EQ(selectionMarkers(map, 99).markers.size(), 1u);  // gone from the map: cleared

  const auto box = selectionMarkers(map, 1);
  // DELETEALL, the box, then per contact (3) a line, the touch points and a text.
  ASSERT_EQ(box.markers.size(), 2u + 3 * 3);
  EXPECT_EQ(box.markers[1].type, visualization_msgs::Marker::CUBE);
  EXPECT_NEAR(box.markers[1].scale.x, 0.125, 1e-9);
  int texts = 0;
  for (const auto& m : box.markers) {
    EXPECT_EQ(m.ns, kSelectionNs);
    if (m.type == visualization_msgs::Marker::TEXT_VIEW_FACING) ++texts;
    if (m.type == visualization_msgs::Marker::LINE_LIST) {
      EXPECT_DOUBLE_EQ(m.points[0].z, 0.05);  // from the selected object's centre
    }
  }
  EXPECT_EQ(texts, 3);
  // The can: only its contact with the box, in the support colour.
  const auto can = selectionMarkers(map, 2);
  ASSERT_EQ(can.markers.size(), 2u + 3);
  EXPECT_NE(can.markers.back().text.find("rests on 1 (support, P2P)"), std::string::npos);
  EXPECT_FLOAT_EQ(can.markers[2].color.g, contactKindColour(ContactKind::kSupport).g);
  // A tentative object can be selected too.
  EXPECT_EQ(selectionMarkers(map, 4).markers.size(), 2u);
}

TEST(MapInspection, PlanCellsSayTheOrderAndWhatRestsOnAnObject) {
  geofusion::SceneGraph graph;
  geofusion::SceneGraphObject box, mug;
  box.id = 3;
  box.removal_step = 1;
  box.free_to_pick = false;
  box.supports = {5};
  box.leaned_on_by = {7};
  mug.id = 5;
  mug.removal_step = 0;
  mug.free_to_pick = true;
  graph.objects = {box, mug};
  EXPECT_EQ(planCells(graph, 3).take, "2");
  EXPECT_EQ(planCells(graph, 3).free, "under 5, 7");
  EXPECT_EQ(planCells(graph, 5).take, "1");
  EXPECT_EQ(planCells(graph, 5).free, "free");
  EXPECT_EQ(planCells(graph, 9).take, "-");  // not in the plan (yet)
  EXPECT_EQ(planCells(graph, 9).free, "");
  EXPECT_EQ(sceneGraphTopicFor("/scene_estimator/object_map"), "/scene_estimator/scene_graph");
  EXPECT_EQ(sceneGraphTopicFor("object_map"), "scene_graph");
}

TEST(MapInspection, PoseSpreadLeavesOutTheFreeRotation) {
  auto can = object(2, 0, 0, 0.15);
  can.pose.covariance[0] = 4e-6;   // 2 mm in x
  can.pose.covariance[14] = 1e-6;  // 1 mm in z
  can.pose.covariance[21] = 1e-4;  // 0.01 rad about x
  EXPECT_NEAR(poseSpread(can).position_m, 0.002, 1e-9);
  EXPECT_NEAR(poseSpread(can).rotation_rad, 0.01, 1e-9);
  can.symmetry = geofusion::MapObject::SYMMETRY_CONTINUOUS;
  can.symmetry_axis.z = 1.0;
  can.pose.covariance[35] = M_PI * M_PI / 3.0;  // free about the axis (z), as published
  EXPECT_NEAR(poseSpread(can).rotation_rad, 0.01, 1e-9);
}

TEST(MapInspection, LabelsInClutterRiseAboveEachOther) {
  // Three objects 5 cm apart in a row and one far away: the near ones take levels 0, 1, 2.
  const std::vector<Eigen::Vector3d> tops = {
      {0, 0, 0.1}, {0.05, 0, 0.1}, {0.1, 0, 0.1}, {1.0, 0, 0.1}, {0.3, 0, 0.1}};
  const auto levels = labelLevels(tops, 0.12);
  EXPECT_EQ(levels, (std::vector<int>{0, 1, 2, 0, 0}));
  // No two labels on one level closer than the spacing.
  for (std::size_t i = 0; i < tops.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      if (levels[i] == levels[j]) {
        EXPECT_GE((tops[i] - tops[j]).head<2>().norm(), 0.12);
      }
    }
  }
}

}  // namespace
}  // namespace geofusion
