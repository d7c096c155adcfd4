// A map's stability and its support graph as a plan (issue 50): its objects on its support plane
// through the physics module's check, and its scene graph. One place for run_offline, the Python
// API, the ROS node and the evaluation.
#pragma once
#include "geofusion/estimation/relations.h"
#include "geofusion/estimation/scene_estimator.h"
#include "geofusion/estimation/scene_graph.h"
#include "geofusion/physics/scene_export.h"
#include "geofusion/physics/stability.h"

#include <string>
#include <vector>

namespace geofusion {

/// The objects under `gravity` on `plane` (invalid or null: a floor under the lowest object, said
/// in the result's warnings).
physics::StabilityResult checkMapStability(const std::vector<ObjectEstimate>& objects,
                                           const SupportPlane* plane,
                                           const Eigen::Vector3d& gravity,
                                           const physics::StabilityConfig& config);

/// The map written for simulators (physics/scene_export.h): an SDF world and a URDF in `folder`,
/// the objects on `plane` as the stability check puts them.
bool exportMapScene(const std::vector<ObjectEstimate>& objects, const SupportPlane* plane,
                    const Eigen::Vector3d& gravity, const physics::StabilityConfig& config,
                    const std::string& folder, physics::SceneExport* result, std::string* error);

/// The map's scene graph (scene_graph.h) from its contacts (indices into `objects`): the existence
/// score is what the robot sees best, the centre the model box's; whether each object stands
/// comes from `stability` when given (its check of the same objects).
SupportGraph mapSupportGraph(const std::vector<ObjectEstimate>& objects,
                             const std::vector<FeatureContact>& contacts,
                             const Eigen::Vector3d& gravity,
                             const physics::StabilityResult* stability,
                             const SupportGraphConfig& config = SupportGraphConfig());

}  // namespace geofusion
