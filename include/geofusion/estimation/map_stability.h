// A map's stability (issue 50): its objects on its support plane through the physics module's
// check. One place for run_offline's summary, the Python API and the evaluation.
#pragma once
#include "geofusion/estimation/relations.h"
#include "geofusion/estimation/scene_estimator.h"
#include "geofusion/physics/stability.h"

#include <vector>

namespace geofusion {

/// The objects under `gravity` on `plane` (invalid or null: a floor under the lowest object, said
/// in the result's warnings).
physics::StabilityResult checkMapStability(const std::vector<ObjectEstimate>& objects,
                                           const SupportPlane* plane,
                                           const Eigen::Vector3d& gravity,
                                           const physics::StabilityConfig& config);

}  // namespace geofusion
