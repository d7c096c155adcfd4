// Inspecting a published map (the rviz panel geofusion/MapPanel, tests): what to show of an
// object and its contacts, and the markers that highlight one object in the 3D view. Works on
// the ObjectMap message alone, so any viewer of the topic can use it.
#pragma once

#include <geofusion/ObjectMap.h>
#include <geofusion/SceneGraph.h>
#include <std_msgs/Header.h>
#include <visualization_msgs/MarkerArray.h>

#include <cstdint>
#include <string>

namespace geofusion {

/// Marker namespace of the highlight (geofusion_panel/selection).
constexpr const char* kSelectionNs = "selection";

/// Standard deviations of an object's pose from its covariance: position (largest axis) in
/// metres, rotation (largest axis, a continuous symmetry's free rotation left out) in radians.
struct PoseSpread {
  double position_m = 0.0;
  double rotation_rad = 0.0;
};
PoseSpread poseSpread(const geofusion::MapObject& object);

/// "support", "leaning", "side"; "P2P", "P2C", "C2C", "P2E".
std::string contactKindName(uint8_t kind);
std::string contactTypeName(uint8_t type);
/// One contact seen from `object_id`: "rests on 3", "supports 5", "leans on the table",
/// "beside 7".
std::string describeContact(const geofusion::ContactRelation& contact, uint32_t object_id);

/// The plan's cells of an object for the panel (geofusion/SceneGraph, docs/scene_graph.md):
/// "take" is its place in the removal order from 1 ("-" when the plan does not have it), "free"
/// says "free" when nothing rests or leans on it, else what does ("under 5, 7").
struct PlanCells {
  std::string take = "-";
  std::string free;
};
PlanCells planCells(const geofusion::SceneGraph& graph, uint32_t id);

/// The scene graph topic beside an ObjectMap topic: "/scene_estimator/object_map" ->
/// "/scene_estimator/scene_graph".
std::string sceneGraphTopicFor(const std::string& object_map_topic);

/// The object with `id` among the map's objects or tentative ones, or null.
const geofusion::MapObject* findObject(const geofusion::ObjectMap& map, uint32_t id);

/// A DELETEALL (ns selection), then for the object `id` (none when 0 or absent): a see-through
/// yellow box around it, and per contact of it a thick line to the other object's centre (the
/// touch point for the table), spheres where they touch and a text naming the contact, coloured
/// by kind.
visualization_msgs::MarkerArray selectionMarkers(const geofusion::ObjectMap& map, uint32_t id);

}  // namespace geofusion
