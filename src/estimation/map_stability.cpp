#include "geofusion/estimation/map_stability.h"

namespace geofusion {

physics::StabilityResult checkMapStability(const std::vector<ObjectEstimate>& objects,
                                           const SupportPlane* plane,
                                           const Eigen::Vector3d& gravity,
                                           const physics::StabilityConfig& config) {
  std::vector<physics::StabilityBody> bodies;
  bodies.reserve(objects.size());
  for (const ObjectEstimate& o : objects) bodies.push_back({o.id, o.model, o.T_map_obj});
  if (!plane || !plane->valid) return physics::checkStability(bodies, nullptr, gravity, config);
  const physics::StabilityPlane support{plane->normal, plane->height};
  return physics::checkStability(bodies, &support, gravity, config);
}

}  // namespace geofusion
