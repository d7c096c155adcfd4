// The estimator's map as messages: geofusion/ObjectMap and rviz markers (objects as meshes or
// primitive shapes coloured by class with labels, contacts as arrows coloured by type).
#pragma once

#include "geofusion/estimation/relations.h"
#include "geofusion/estimation/scene_estimator.h"

#include <geofusion/ObjectMap.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_msgs/Header.h>
#include <visualization_msgs/MarkerArray.h>

namespace geofusion {

/// Marker namespaces of the estimator's map.
constexpr const char* kObjectNs = "objects";      ///< the object: mesh, cube or cylinder
constexpr const char* kObjectLabelNs = "labels";  ///< TEXT "id class score"
constexpr const char* kContactNs = "contacts";    ///< ARROW supporter -> supported feature
/// One LINE_LIST: each contact as a line from the supporter's centre (the point under the
/// supported feature for the table) to the supported object's centre, coloured by type.
constexpr const char* kContactLinkNs = "contact_links";
constexpr const char* kSupportPlaneNs = "support_plane";

/// Map ids in messages: object id + 1 (0 is the support plane, ContactRelation::SUPPORT_PLANE_ID).
inline uint32_t messageId(int object_id) {
  return static_cast<uint32_t>(object_id + 1);
}

geofusion::ObjectMap toObjectMapMsg(const KeyframeResult& result, const SupportPlane& plane,
                                    const Eigen::Vector3d& gravity, const std_msgs::Header& header);

/// A DELETEALL first (removed and merged objects never linger), then every object, its label,
/// every contact and the support plane.
visualization_msgs::MarkerArray mapMarkers(const KeyframeResult& result, const SupportPlane& plane,
                                           const std_msgs::Header& header);

/// Occupied background voxels as one CUBE_LIST (ns "background"), coloured by height.
visualization_msgs::MarkerArray backgroundMarkers(const std::vector<Eigen::Vector3d>& centres,
                                                  double resolution_m,
                                                  const std_msgs::Header& header);
/// Points (x, y, z float32) as a PointCloud2.
sensor_msgs::PointCloud2 pointCloud(const std::vector<Eigen::Vector3d>& points,
                                    const std_msgs::Header& header);

}  // namespace geofusion
