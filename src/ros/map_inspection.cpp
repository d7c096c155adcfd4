#include "geofusion/ros/map_inspection.h"

#include "geofusion/estimation/relations.h"
#include "geofusion/ros/map_messages.h"
#include "geofusion/ros/markers.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace geofusion {

PoseSpread poseSpread(const geofusion::MapObject& object) {
  Eigen::Matrix<double, 6, 6> c;
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j)
      c(i, j) = object.pose.covariance[static_cast<std::size_t>(6 * i + j)];
  Eigen::Matrix3d rotation = c.bottomRightCorner<3, 3>();
  if (object.symmetry == geofusion::MapObject::SYMMETRY_CONTINUOUS) {
    const auto& q = object.pose.pose.orientation;
    const Eigen::Vector3d axis =
        Eigen::Quaterniond(q.w, q.x, q.y, q.z).normalized() *
        Eigen::Vector3d(object.symmetry_axis.x, object.symmetry_axis.y, object.symmetry_axis.z)
            .normalized();
    rotation -= (M_PI * M_PI / 3.0) * axis * axis.transpose();
  }
  const auto largest = [](const Eigen::Matrix3d& m) {
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(0.5 * (m + m.transpose()));
    return std::sqrt(std::max(0.0, eig.eigenvalues().maxCoeff()));
  };
  return {largest(c.topLeftCorner<3, 3>()), largest(rotation)};
}

std::string contactKindName(uint8_t kind) {
  switch (kind) {
    case geofusion::ContactRelation::KIND_SUPPORT: return "support";
    case geofusion::ContactRelation::KIND_LEANING: return "leaning";
    case geofusion::ContactRelation::KIND_SIDE: return "side";
    default: return "?";
  }
}

std::string contactTypeName(uint8_t type) {
  switch (type) {
    case geofusion::ContactRelation::PLANE_PLANE: return "P2P";
    case geofusion::ContactRelation::PLANE_CURVE: return "P2C";
    case geofusion::ContactRelation::CURVE_CURVE: return "C2C";
    case geofusion::ContactRelation::PLANE_EDGE: return "P2E";
    default: return "?";
  }
}

std::string describeContact(const geofusion::ContactRelation& c, uint32_t object_id) {
  const bool is_a = c.object_a == object_id;
  const uint32_t other = is_a ? c.object_b : c.object_a;
  const std::string name =
      other == geofusion::ContactRelation::SUPPORT_PLANE_ID ? "the table" : std::to_string(other);
  if (c.kind == geofusion::ContactRelation::KIND_SIDE) return "beside " + name;
  // a_supports_b: a is below. Seen from the supported one it rests (or leans) on the other.
  const bool below = is_a == static_cast<bool>(c.a_supports_b);
  if (below) return "supports " + name;
  return (c.kind == geofusion::ContactRelation::KIND_LEANING ? "leans on " : "rests on ") + name;
}

PlanCells planCells(const geofusion::SceneGraph& graph, uint32_t id) {
  PlanCells cells;
  for (const geofusion::SceneGraphObject& o : graph.objects) {
    if (o.id != id) continue;
    if (o.removal_step >= 0) cells.take = std::to_string(o.removal_step + 1);
    if (o.free_to_pick) {
      cells.free = "free";
    } else {
      std::string above;
      for (const auto* list : {&o.supports, &o.leaned_on_by, &o.covered_by})
        for (uint32_t other : *list) above += (above.empty() ? "" : ", ") + std::to_string(other);
      cells.free = "under " + above;
    }
  }
  return cells;
}

std::string sceneGraphTopicFor(const std::string& object_map_topic) {
  const std::size_t slash = object_map_topic.rfind('/');
  return (slash == std::string::npos ? std::string() : object_map_topic.substr(0, slash + 1)) +
         "scene_graph";
}

const geofusion::MapObject* findObject(const geofusion::ObjectMap& map, uint32_t id) {
  for (const auto* list : {&map.objects, &map.tentative})
    for (const auto& o : *list)
      if (o.id == id) return &o;
  return nullptr;
}

visualization_msgs::MarkerArray selectionMarkers(const geofusion::ObjectMap& map, uint32_t id) {
  using visualization_msgs::Marker;
  visualization_msgs::MarkerArray out;
  Marker clear = deleteAllMarker(map.header);
  clear.ns = kSelectionNs;
  out.markers.push_back(clear);
  const geofusion::MapObject* object = id == 0 ? nullptr : findObject(map, id);
  if (!object) return out;
  Marker box = makeMarker(map.header, kSelectionNs, 0, Marker::CUBE);
  box.pose = object->pose.pose;
  box.scale.x = 1.15 * object->bbox_size.x + 0.01;
  box.scale.y = 1.15 * object->bbox_size.y + 0.01;
  box.scale.z = 1.15 * object->bbox_size.z + 0.01;
  box.color = colorMsg(1.0f, 0.95f, 0.0f, 0.5f);
  out.markers.push_back(box);
  const auto centre = [&](uint32_t other, const geometry_msgs::Point& touch) {
    const geofusion::MapObject* o = findObject(map, other);
    return o ? o->pose.pose.position : touch;
  };
  int n = 1;
  for (const auto& c : map.contacts) {
    if (c.object_a != id && c.object_b != id) continue;
    const ContactKind kind =
        c.kind == geofusion::ContactRelation::KIND_SUPPORT   ? ContactKind::kSupport
        : c.kind == geofusion::ContactRelation::KIND_LEANING ? ContactKind::kLeaning
                                                             : ContactKind::kSide;
    const std_msgs::ColorRGBA colour = contactKindColour(kind);
    const bool is_a = c.object_a == id;
    Marker line = makeMarker(map.header, kSelectionNs, n++, Marker::LINE_LIST);
    line.scale.x = 0.01;
    line.points = {object->pose.pose.position,
                   centre(is_a ? c.object_b : c.object_a, is_a ? c.point_b : c.point_a)};
    line.color = colour;
    out.markers.push_back(line);
    Marker touch = makeMarker(map.header, kSelectionNs, n++, Marker::SPHERE_LIST);
    touch.scale.x = touch.scale.y = touch.scale.z = 0.02;
    touch.points = {c.point_a, c.point_b};
    touch.color = colour;
    out.markers.push_back(touch);
    Marker text = makeMarker(map.header, kSelectionNs, n++, Marker::TEXT_VIEW_FACING);
    text.pose.position.x = 0.5 * (line.points[0].x + line.points[1].x);
    text.pose.position.y = 0.5 * (line.points[0].y + line.points[1].y);
    text.pose.position.z = 0.5 * (line.points[0].z + line.points[1].z) + 0.02;
    text.pose.orientation.w = 1.0;
    text.scale.z = 0.02;
    text.color = colour;
    text.text = describeContact(c, id) + " (" + contactKindName(c.kind) + ", " +
                contactTypeName(c.type) + ")";
    out.markers.push_back(text);
  }
  return out;
}

}  // namespace geofusion
