#include "geofusion/ros/map_messages.h"

#include "geofusion/common/class_palette.h"
#include "geofusion/ros/conversions.h"
#include "geofusion/ros/markers.h"

#include <sensor_msgs/point_cloud2_iterator.h>

#include <algorithm>
#include <cstdio>

namespace geofusion {
namespace {

Eigen::Vector3d featureCentre(const ObjectModel& model, const FeatureRef& f,
                              const Eigen::Isometry3d& T) {
  if (f.plane && f.index >= 0 && f.index < static_cast<int>(model.features.planes.size()))
    return T * model.features.planes[static_cast<std::size_t>(f.index)].center;
  if (!f.plane && f.index >= 0 && f.index < static_cast<int>(model.features.curves.size()))
    return T * model.features.curves[static_cast<std::size_t>(f.index)].center;
  return T.translation();
}

// Contact endpoints in the map frame; index -1 is the support plane.
bool contactPoints(const KeyframeResult& r, const FeatureContact& c, const ObjectModel* plane_model,
                   const Eigen::Isometry3d& T_plane, Eigen::Vector3d* a, Eigen::Vector3d* b) {
  auto at = [&](int index, const FeatureRef& f, Eigen::Vector3d* out) {
    if (index < 0) {
      if (!plane_model) return false;
      *out = featureCentre(*plane_model, f, T_plane);
      return true;
    }
    if (index >= static_cast<int>(r.objects.size())) return false;
    const ObjectEstimate& o = r.objects[static_cast<std::size_t>(index)];
    if (!o.model) return false;
    // A plane-edge contact's edge side: the touching point of its hull.
    *out = c.type == ContactType::kPlaneEdge && !f.plane ? o.T_map_obj * c.edge_point
                                                         : featureCentre(*o.model, f, o.T_map_obj);
    return true;
  };
  return at(c.object_a, c.feature_a, a) && at(c.object_b, c.feature_b, b);
}

}  // namespace

geofusion::ObjectMap toObjectMapMsg(const KeyframeResult& r, const SupportPlane& plane,
                                    const Eigen::Vector3d& gravity,
                                    const std_msgs::Header& header) {
  geofusion::ObjectMap msg;
  msg.header = header;
  for (const ObjectEstimate& o : r.objects) {
    if (!o.model) continue;
    geofusion::MapObject m;
    m.id = messageId(o.id);
    m.class_name = o.model->name;
    m.class_id = o.model->id;
    m.pose.pose = toPoseMsg(o.T_map_obj);
    m.existence_score = static_cast<float>(o.existence);
    m.false_positive_score = static_cast<float>(o.false_positive);
    m.num_measurements = static_cast<uint32_t>(o.measurements);
    switch (o.model->symmetry.type) {
      case Symmetry::Type::kContinuous:
        m.symmetry = geofusion::MapObject::SYMMETRY_CONTINUOUS;
        m.symmetry_axis.x = o.model->symmetry.axis.x();
        m.symmetry_axis.y = o.model->symmetry.axis.y();
        m.symmetry_axis.z = o.model->symmetry.axis.z();
        break;
      case Symmetry::Type::kDiscrete:
        m.symmetry = geofusion::MapObject::SYMMETRY_DISCRETE;
        for (const auto& q : o.model->symmetry.rotations) {
          geometry_msgs::Quaternion mq;
          mq.x = q.x(), mq.y = q.y(), mq.z = q.z(), mq.w = q.w();
          m.symmetry_rotations.push_back(mq);
        }
        break;
      default: m.symmetry = geofusion::MapObject::SYMMETRY_NONE;
    }
    m.bbox_size.x = o.model->extents.x();
    m.bbox_size.y = o.model->extents.y();
    m.bbox_size.z = o.model->extents.z();
    msg.objects.push_back(m);
  }
  Eigen::Isometry3d T_plane = Eigen::Isometry3d::Identity();
  const auto plane_model = plane.valid ? supportPlaneModel(plane, &T_plane) : nullptr;
  for (const FeatureContact& c : r.contacts) {
    Eigen::Vector3d a, b;
    if (!contactPoints(r, c, plane_model.get(), T_plane, &a, &b)) continue;
    geofusion::ContactRelation cr;
    switch (c.type) {
      case ContactType::kPlanePlane: cr.type = geofusion::ContactRelation::PLANE_PLANE; break;
      case ContactType::kPlaneCurve: cr.type = geofusion::ContactRelation::PLANE_CURVE; break;
      case ContactType::kCurveCurve: cr.type = geofusion::ContactRelation::CURVE_CURVE; break;
      case ContactType::kPlaneEdge: cr.type = geofusion::ContactRelation::PLANE_EDGE; break;
    }
    switch (c.kind) {
      case ContactKind::kSupport: cr.kind = geofusion::ContactRelation::KIND_SUPPORT; break;
      case ContactKind::kLeaning: cr.kind = geofusion::ContactRelation::KIND_LEANING; break;
      case ContactKind::kSide: cr.kind = geofusion::ContactRelation::KIND_SIDE; break;
    }
    auto id = [&](int index) {
      return index < 0
                 ? static_cast<decltype(messageId(0))>(geofusion::ContactRelation::SUPPORT_PLANE_ID)
                 : messageId(r.objects[static_cast<std::size_t>(index)].id);
    };
    cr.object_a = id(c.object_a);
    cr.object_b = id(c.object_b);
    cr.feature_a = static_cast<uint32_t>(std::max(0, c.feature_a.index));
    cr.feature_b = static_cast<uint32_t>(std::max(0, c.feature_b.index));
    cr.feature_a_type = c.feature_a.plane ? geofusion::ContactRelation::FEATURE_PLANE
                                          : geofusion::ContactRelation::FEATURE_CURVE;
    cr.feature_b_type = c.feature_b.plane ? geofusion::ContactRelation::FEATURE_PLANE
                                          : geofusion::ContactRelation::FEATURE_CURVE;
    cr.a_supports_b = c.support();
    cr.point_a = toPointMsg(a);
    cr.point_b = toPointMsg(b);
    cr.distance_residual_m = static_cast<float>(c.distance_residual);
    cr.direction_residual = static_cast<float>(c.direction_residual);
    msg.contacts.push_back(cr);
  }
  msg.gravity.x = gravity.x(), msg.gravity.y = gravity.y(), msg.gravity.z = gravity.z();
  msg.has_support_plane = plane.valid;
  if (plane.valid) {
    msg.support_plane = {plane.normal.x(), plane.normal.y(), plane.normal.z(), -plane.height};
  }
  return msg;
}

visualization_msgs::MarkerArray mapMarkers(const KeyframeResult& r, const SupportPlane& plane,
                                           const std_msgs::Header& header) {
  using visualization_msgs::Marker;
  visualization_msgs::MarkerArray out;
  out.markers.push_back(deleteAllMarker(header));
  for (const ObjectEstimate& o : r.objects) {
    if (!o.model) continue;
    const Rgb colour = classColor(o.model->name);
    Marker m = makeMarker(header, kObjectNs, static_cast<int>(messageId(o.id)), Marker::CUBE);
    m.pose = toPoseMsg(o.T_map_obj);
    m.color.r = colour.r, m.color.g = colour.g, m.color.b = colour.b;
    m.color.a = static_cast<float>(0.4 + 0.5 * o.existence);
    if (!o.model->mesh_path.empty()) {
      m.type = Marker::MESH_RESOURCE;
      m.mesh_resource = "file://" + o.model->mesh_path;
      m.mesh_use_embedded_materials = true;
      m.scale.x = m.scale.y = m.scale.z = 1.0;
    } else {
      // Built-in primitives are centred boxes and cylinders (along z).
      m.type =
          o.model->symmetry.type == Symmetry::Type::kContinuous ? Marker::CYLINDER : Marker::CUBE;
      m.scale.x = o.model->extents.x();
      m.scale.y = o.model->extents.y();
      m.scale.z = o.model->extents.z();
    }
    out.markers.push_back(m);
    Marker label = m;
    label.ns = kObjectLabelNs;
    label.type = Marker::TEXT_VIEW_FACING;
    label.mesh_resource.clear();
    label.pose.orientation = geometry_msgs::Quaternion();
    label.pose.orientation.w = 1.0;
    label.pose.position.z += 0.5 * o.model->extents.maxCoeff() + 0.03;
    label.scale.x = label.scale.y = 0.0;
    label.scale.z = 0.025;
    label.color.r = label.color.g = label.color.b = label.color.a = 1.0f;
    char text[128];
    std::snprintf(text, sizeof(text), "%d %s %.2f", m.id, o.model->name.c_str(), o.existence);
    label.text = text;
    out.markers.push_back(label);
  }
  Eigen::Isometry3d T_plane = Eigen::Isometry3d::Identity();
  const auto plane_model = plane.valid ? supportPlaneModel(plane, &T_plane) : nullptr;
  int contact_id = 0;
  Marker links = makeMarker(header, kContactLinkNs, 0, Marker::LINE_LIST);
  links.scale.x = 0.004;
  for (const FeatureContact& c : r.contacts) {
    Eigen::Vector3d a, b;
    if (!contactPoints(r, c, plane_model.get(), T_plane, &a, &b)) continue;
    // P2P magenta, P2C green, C2C cyan, P2E orange.
    const std_msgs::ColorRGBA colour =
        c.type == ContactType::kPlaneEdge
            ? colorMsg(1.0f, 0.55f, 0.0f)
            : colorMsg(c.type == ContactType::kPlanePlane ? 1.0f : 0.1f,
                       c.type == ContactType::kPlanePlane ? 0.1f : 1.0f,
                       c.type == ContactType::kPlaneCurve ? 0.1f : 1.0f);
    Marker arrow = makeMarker(header, kContactNs, contact_id++, Marker::ARROW);
    // An arrow along the contact normal (the support direction for support contacts), ending
    // at the supported feature: it sits where the objects touch and points up into what rests.
    arrow.points = {toPointMsg(b - 0.06 * c.normal), toPointMsg(b)};
    arrow.scale.x = 0.008, arrow.scale.y = 0.018, arrow.scale.z = 0.02;
    arrow.color = colour;
    out.markers.push_back(arrow);
    // The link between the two objects' centres: which rests on which, at a glance.
    // (contactPoints checked the indices; -1 is the support plane.)
    auto centre = [&](int index, const Eigen::Vector3d& on_plane) {
      return index < 0 ? on_plane
                       : Eigen::Vector3d(
                             r.objects[static_cast<std::size_t>(index)].T_map_obj.translation());
    };
    const Eigen::Vector3d from = centre(c.object_a, b), to = centre(c.object_b, a);
    links.points.push_back(toPointMsg(from));
    links.points.push_back(toPointMsg(to));
    links.colors.push_back(colour);
    links.colors.push_back(colour);
  }
  if (!links.points.empty()) out.markers.push_back(links);
  if (plane_model) {
    Marker table = makeMarker(header, kSupportPlaneNs, 0, Marker::CUBE);
    table.pose = toPoseMsg(T_plane);
    table.scale.x = plane_model->extents.x();
    table.scale.y = plane_model->extents.y();
    table.scale.z = plane_model->extents.z();
    table.color.r = 0.55f, table.color.g = 0.4f, table.color.b = 0.25f, table.color.a = 0.35f;
    out.markers.push_back(table);
  }
  return out;
}

visualization_msgs::MarkerArray backgroundMarkers(const std::vector<Eigen::Vector3d>& centres,
                                                  double resolution_m,
                                                  const std_msgs::Header& header) {
  visualization_msgs::MarkerArray out;
  visualization_msgs::Marker m =
      makeMarker(header, "background", 0, visualization_msgs::Marker::CUBE_LIST);
  if (centres.empty()) m.action = visualization_msgs::Marker::DELETE;
  m.scale.x = m.scale.y = m.scale.z = resolution_m;
  double lo = 1e9, hi = -1e9;
  for (const auto& c : centres) lo = std::min(lo, c.z()), hi = std::max(hi, c.z());
  for (const auto& c : centres) {
    m.points.push_back(toPointMsg(c));
    const double t = hi > lo ? (c.z() - lo) / (hi - lo) : 0.5;
    const Rgb rgb = hsvToRgb(0.66 * (1.0 - t), 0.8, 0.9);  // blue low, red high
    m.colors.push_back(colorMsg(rgb.r, rgb.g, rgb.b));
  }
  out.markers.push_back(m);
  return out;
}

sensor_msgs::PointCloud2 pointCloud(const std::vector<Eigen::Vector3d>& points,
                                    const std_msgs::Header& header) {
  sensor_msgs::PointCloud2 cloud;
  cloud.header = header;
  sensor_msgs::PointCloud2Modifier modifier(cloud);
  modifier.setPointCloud2FieldsByString(1, "xyz");
  modifier.resize(points.size());
  if (points.empty()) return cloud;  // an iterator on no data binds a reference to data.front()
  sensor_msgs::PointCloud2Iterator<float> x(cloud, "x"), y(cloud, "y"), z(cloud, "z");
  for (const auto& p : points) {
    *x = static_cast<float>(p.x()), *y = static_cast<float>(p.y()), *z = static_cast<float>(p.z());
    ++x, ++y, ++z;
  }
  return cloud;
}

}  // namespace geofusion
