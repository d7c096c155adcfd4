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

SupportGraph mapSupportGraph(const std::vector<ObjectEstimate>& objects,
                             const std::vector<FeatureContact>& contacts,
                             const Eigen::Vector3d& gravity,
                             const physics::StabilityResult* stability) {
  std::vector<SupportGraphObject> list;
  list.reserve(objects.size());
  for (const ObjectEstimate& o : objects) {
    SupportGraphObject g;
    g.id = o.id;
    g.visibility = o.existence;
    g.centre = o.T_map_obj.translation();
    if (o.model) {
      g.class_name = o.model->name;
      g.centre = o.T_map_obj * boxOf(*o.model).center().cast<double>();
    }
    if (stability) {
      const physics::BodyMotion* m = stability->find(o.id);
      if (m && m->simulated) g.stable = m->stable ? 1 : 0;
    }
    list.push_back(std::move(g));
  }
  return buildSupportGraph(list, contacts, gravity);
}

}  // namespace geofusion
