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

geofusion::MapObject toMapObjectMsg(const ObjectEstimate& o) {
  geofusion::MapObject m;
  m.id = messageId(o.id);
  m.class_name = o.model->name;
  m.class_id = o.model->id;
  m.state =
      o.confirmed ? geofusion::MapObject::STATE_CONFIRMED : geofusion::MapObject::STATE_TENTATIVE;
  m.pose.pose = toPoseMsg(o.T_map_obj);
  Eigen::Matrix<double, 6, 6> covariance = o.covariance;
  if (o.model->symmetry.type == Symmetry::Type::kContinuous) {
    // Rotation about the axis is unobservable: the variance of an angle uniform on the circle.
    const Eigen::Vector3d axis = o.T_map_obj.linear() * o.model->symmetry.axis.normalized();
    covariance.bottomRightCorner<3, 3>() += (M_PI * M_PI / 3.0) * axis * axis.transpose();
  }
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j)
      m.pose.covariance[static_cast<std::size_t>(6 * i + j)] = covariance(i, j);
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
  return m;
}

geofusion::SceneGraph toSceneGraphMsg(const SupportGraph& graph, const std_msgs::Header& header) {
  auto ids = [](const std::vector<int>& list) {
    std::vector<uint32_t> out;
    for (int id : list) out.push_back(messageId(id));  // the plane (-1) becomes 0
    return out;
  };
  geofusion::SceneGraph msg;
  msg.header = header;
  for (const SupportGraphNode& n : graph.nodes) {
    geofusion::SceneGraphObject o;
    o.id = messageId(n.id);
    o.class_name = n.class_name;
    o.supported_by = ids(n.supported_by);
    o.supports = ids(n.supports);
    o.leans_on = ids(n.leans_on);
    o.leaned_on_by = ids(n.leaned_on_by);
    o.beside = ids(n.beside);
    o.over = ids(n.over);
    o.covered_by = ids(n.covered_by);
    o.stable = static_cast<int8_t>(n.stable);
    o.free_to_pick = n.free_to_pick;
    o.removal_step = n.removal_step;
    msg.objects.push_back(std::move(o));
  }
  msg.removal_order = ids(graph.removal_order);
  msg.warnings = graph.warnings;
  return msg;
}

geofusion::ObjectMap toObjectMapMsg(const KeyframeResult& r, const SupportPlane& plane,
                                    const Eigen::Vector3d& gravity,
                                    const std_msgs::Header& header) {
  geofusion::ObjectMap msg;
  msg.header = header;
  for (const ObjectEstimate& o : r.objects)
    if (o.model) msg.objects.push_back(toMapObjectMsg(o));
  for (const ObjectEstimate& o : r.tentative)
    if (o.model) msg.tentative.push_back(toMapObjectMsg(o));
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

std::vector<int> labelLevels(const std::vector<Eigen::Vector3d>& positions, double min_spacing_m) {
  std::vector<int> levels(positions.size(), 0);
  for (std::size_t i = 0; i < positions.size(); ++i) {
    for (int level = 0;; ++level) {
      bool free = true;
      for (std::size_t j = 0; j < i && free; ++j) {
        free =
            levels[j] != level || (positions[i] - positions[j]).head<2>().norm() >= min_spacing_m;
      }
      if (free) {
        levels[i] = level;
        break;
      }
    }
  }
  return levels;
}

std_msgs::ColorRGBA contactKindColour(ContactKind kind) {
  switch (kind) {
    case ContactKind::kSupport: return colorMsg(0.2f, 0.85f, 0.25f);  // green
    case ContactKind::kLeaning: return colorMsg(1.0f, 0.55f, 0.0f);   // orange
    case ContactKind::kSide: return colorMsg(0.25f, 0.55f, 1.0f);     // blue
  }
  return colorMsg(1.0f, 1.0f, 1.0f);
}

namespace {

// The object as a mesh (its file) or, for built-in primitives, a centred box or cylinder.
visualization_msgs::Marker objectMarker(const ObjectEstimate& o, const std_msgs::Header& header,
                                        const char* ns) {
  using visualization_msgs::Marker;
  Marker m = makeMarker(header, ns, static_cast<int>(messageId(o.id)), Marker::CUBE);
  m.pose = toPoseMsg(o.T_map_obj);
  if (!o.model->mesh_path.empty()) {
    m.type = Marker::MESH_RESOURCE;
    m.mesh_resource = "file://" + o.model->mesh_path;
    m.scale.x = m.scale.y = m.scale.z = 1.0;
  } else {
    m.type =
        o.model->symmetry.type == Symmetry::Type::kContinuous ? Marker::CYLINDER : Marker::CUBE;
    m.scale.x = o.model->extents.x();
    m.scale.y = o.model->extents.y();
    m.scale.z = o.model->extents.z();
  }
  return m;
}

// Labels above the objects, "id class" over "score state", raised a line where another label
// below would overlap (clutter: objects closer than a label's width).
void addLabels(const std::vector<const ObjectEstimate*>& objects, const std_msgs::Header& header,
               visualization_msgs::MarkerArray* out) {
  constexpr double kLine = 0.04, kSpacing = 0.18;
  std::vector<Eigen::Vector3d> tops;
  for (const ObjectEstimate* o : objects) {
    Eigen::Vector3d top = o->T_map_obj.translation();
    top.z() += 0.5 * o->model->extents.maxCoeff();
    tops.push_back(top);
  }
  const std::vector<int> levels = labelLevels(tops, kSpacing);
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const ObjectEstimate& o = *objects[i];
    auto label = makeMarker(header, kObjectLabelNs, static_cast<int>(messageId(o.id)),
                            visualization_msgs::Marker::TEXT_VIEW_FACING);
    label.pose.position = toPointMsg(tops[i] + Eigen::Vector3d(0, 0, 0.03 + kLine * levels[i]));
    label.pose.orientation.w = 1.0;
    label.scale.z = 0.015;
    label.color = o.confirmed ? colorMsg(1.0f, 1.0f, 1.0f) : colorMsg(0.7f, 0.7f, 0.7f);
    char text[160];
    std::snprintf(text, sizeof(text), "%u %s\n%.2f %s", messageId(o.id), o.model->name.c_str(),
                  o.existence, o.confirmed ? "confirmed" : "tentative");
    label.text = text;
    out->markers.push_back(label);
  }
}

}  // namespace

visualization_msgs::MarkerArray mapMarkers(const KeyframeResult& r, const SupportPlane& plane,
                                           const std_msgs::Header& header) {
  using visualization_msgs::Marker;
  visualization_msgs::MarkerArray out;
  out.markers.push_back(deleteAllMarker(header));
  std::vector<const ObjectEstimate*> labelled;
  for (const ObjectEstimate& o : r.objects) {
    if (!o.model) continue;
    const Rgb colour = classColor(o.model->name);
    Marker m = objectMarker(o, header, kObjectNs);
    m.mesh_use_embedded_materials = m.type == Marker::MESH_RESOURCE;
    m.color.r = colour.r, m.color.g = colour.g, m.color.b = colour.b;
    m.color.a = static_cast<float>(0.4 + 0.5 * o.existence);
    out.markers.push_back(m);
    labelled.push_back(&o);
  }
  for (const ObjectEstimate& o : r.tentative) {
    if (!o.model) continue;
    Marker m = objectMarker(o, header, kTentativeNs);  // see-through grey: not (yet) in the map
    m.color = colorMsg(0.75f, 0.75f, 0.75f, 0.25f);
    out.markers.push_back(m);
    labelled.push_back(&o);
  }
  addLabels(labelled, header, &out);
  Eigen::Isometry3d T_plane = Eigen::Isometry3d::Identity();
  const auto plane_model = plane.valid ? supportPlaneModel(plane, &T_plane) : nullptr;
  int contact_id = 0;
  Marker links = makeMarker(header, kContactLinkNs, 0, Marker::LINE_LIST);
  links.scale.x = 0.004;
  Marker points = makeMarker(header, kContactPointNs, 0, Marker::SPHERE_LIST);
  points.scale.x = points.scale.y = points.scale.z = 0.012;
  for (const FeatureContact& c : r.contacts) {
    Eigen::Vector3d a, b;
    if (!contactPoints(r, c, plane_model.get(), T_plane, &a, &b)) continue;
    const std_msgs::ColorRGBA colour = contactKindColour(c.kind);
    Marker arrow = makeMarker(header, kContactNs, contact_id++, Marker::ARROW);
    // An arrow along the contact normal (the support direction for support contacts), ending
    // at the supported feature: it sits where the objects touch and points up into what rests.
    arrow.points = {toPointMsg(b - 0.06 * c.normal), toPointMsg(b)};
    arrow.scale.x = 0.008, arrow.scale.y = 0.018, arrow.scale.z = 0.02;
    arrow.color = colour;
    out.markers.push_back(arrow);
    points.points.push_back(toPointMsg(b));
    points.colors.push_back(colour);
    // The support graph: a line between the two objects' centres (the point under the object
    // for the table). (contactPoints checked the indices; -1 is the support plane.)
    auto centre = [&](int index, const Eigen::Vector3d& on_plane) {
      return index < 0 ? on_plane
                       : Eigen::Vector3d(
                             r.objects[static_cast<std::size_t>(index)].T_map_obj.translation());
    };
    links.points.push_back(toPointMsg(centre(c.object_a, b)));
    links.points.push_back(toPointMsg(centre(c.object_b, a)));
    links.colors.push_back(colour);
    links.colors.push_back(colour);
  }
  if (!links.points.empty()) out.markers.push_back(links);
  if (!points.points.empty()) out.markers.push_back(points);
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
                                                  const std_msgs::Header& header, bool by_height) {
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
    // Muted, so that the objects' class colours stand out: a bluish grey, darker low and lighter
    // high, or plain grey.
    const Rgb rgb = by_height ? hsvToRgb(0.6, 0.2, 0.4 + 0.35 * t) : hsvToRgb(0.0, 0.0, 0.55);
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
