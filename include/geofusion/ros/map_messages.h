// The estimator's map as messages: geofusion/ObjectMap and rviz markers (objects as meshes or
// primitive shapes coloured by class with labels, contacts as arrows coloured by type).
#pragma once

#include "geofusion/estimation/relations.h"
#include "geofusion/estimation/scene_estimator.h"
#include "geofusion/estimation/scene_graph.h"

#include <geofusion/ObjectMap.h>
#include <geofusion/SceneGraph.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_msgs/Header.h>
#include <visualization_msgs/MarkerArray.h>

namespace geofusion {

/// Marker namespaces of the estimator's map.
constexpr const char* kObjectNs = "objects";      ///< the object: mesh, cube or cylinder
constexpr const char* kObjectLabelNs = "labels";  ///< TEXT "id class" / "score state"
/// Objects seen but not confirmed (KeyframeResult::tentative): see-through grey.
constexpr const char* kTentativeNs = "tentative";
constexpr const char* kContactNs = "contacts";  ///< ARROW along the normal, coloured by kind
/// One SPHERE_LIST: where each contact touches (the supported feature), coloured by kind.
constexpr const char* kContactPointNs = "contact_points";
/// One LINE_LIST, the support graph: each contact as a line from the supporter's centre (the
/// point under the supported feature for the table) to the supported object's centre, coloured
/// by kind.
constexpr const char* kContactLinkNs = "contact_links";
constexpr const char* kSupportPlaneNs = "support_plane";

/// Map ids in messages: object id + 1 (0 is the support plane, ContactRelation::SUPPORT_PLANE_ID).
inline uint32_t messageId(int object_id) {
  return static_cast<uint32_t>(object_id + 1);
}

/// One object (state, covariance with a continuous symmetry's free rotation, symmetry, size).
geofusion::MapObject toMapObjectMsg(const ObjectEstimate& object);

/// The support graph as a plan (docs/scene_graph.md): ids as in ObjectMap (messageId; the support
/// plane ContactRelation::SUPPORT_PLANE_ID).
geofusion::SceneGraph toSceneGraphMsg(const SupportGraph& graph, const std_msgs::Header& header);

geofusion::ObjectMap toObjectMapMsg(const KeyframeResult& result, const SupportPlane& plane,
                                    const Eigen::Vector3d& gravity, const std_msgs::Header& header);

/// Contact colours by kind: support green, leaning orange, side by side blue.
std_msgs::ColorRGBA contactKindColour(ContactKind kind);

/// The level (0, 1, ...) of each label above its object so that no two labels on one level are
/// closer than `min_spacing_m` horizontally: labels stay readable in clutter. Greedy in order.
std::vector<int> labelLevels(const std::vector<Eigen::Vector3d>& positions, double min_spacing_m);

/// A DELETEALL first (removed and merged objects never linger), then every object, every
/// tentative object, their labels, every contact (arrow, touch point, support-graph line) and
/// the support plane.
visualization_msgs::MarkerArray mapMarkers(const KeyframeResult& result, const SupportPlane& plane,
                                           const std_msgs::Header& header);

/// Occupied background voxels as one CUBE_LIST (ns "background"), muted colours by height (or
/// grey), so that the objects stand out.
visualization_msgs::MarkerArray backgroundMarkers(const std::vector<Eigen::Vector3d>& centres,
                                                  double resolution_m,
                                                  const std_msgs::Header& header,
                                                  bool by_height = true);
/// Points (x, y, z float32) as a PointCloud2.
sensor_msgs::PointCloud2 pointCloud(const std::vector<Eigen::Vector3d>& points,
                                    const std_msgs::Header& header);

}  // namespace geofusion
