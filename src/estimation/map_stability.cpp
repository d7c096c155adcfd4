#include "geofusion/estimation/map_stability.h"

namespace geofusion {

namespace {

std::vector<physics::StabilityBody> bodiesOf(const std::vector<ObjectEstimate>& objects) {
  std::vector<physics::StabilityBody> bodies;
  bodies.reserve(objects.size());
  for (const ObjectEstimate& o : objects) bodies.push_back({o.id, o.model, o.T_map_obj});
  return bodies;
}

/// The map's plane as the physics module's; false when there is none.
bool planeOf(const SupportPlane* plane, physics::StabilityPlane* out) {
  if (!plane || !plane->valid) return false;
  *out = physics::StabilityPlane{plane->normal, plane->height};
  return true;
}

}  // namespace

physics::StabilityResult checkMapStability(const std::vector<ObjectEstimate>& objects,
                                           const SupportPlane* plane,
                                           const Eigen::Vector3d& gravity,
                                           const physics::StabilityConfig& config) {
  physics::StabilityPlane support;
  const bool has_plane = planeOf(plane, &support);
  return physics::checkStability(bodiesOf(objects), has_plane ? &support : nullptr, gravity,
                                 config);
}

bool exportMapScene(const std::vector<ObjectEstimate>& objects, const SupportPlane* plane,
                    const Eigen::Vector3d& gravity, const physics::StabilityConfig& config,
                    const std::string& folder, physics::SceneExport* result, std::string* error) {
  physics::StabilityPlane support;
  const bool has_plane = planeOf(plane, &support);
  return physics::exportScene(bodiesOf(objects), has_plane ? &support : nullptr, gravity, config,
                              folder, result, error);
}

SupportGraph mapSupportGraph(const std::vector<ObjectEstimate>& objects,
                             const std::vector<FeatureContact>& contacts,
                             const Eigen::Vector3d& gravity,
                             const physics::StabilityResult* stability,
                             const SupportGraphConfig& config) {
  std::vector<SupportGraphObject> list;
  list.reserve(objects.size());
  for (const ObjectEstimate& o : objects) {
    SupportGraphObject g;
    g.id = o.id;
    g.visibility = o.existence;
    g.centre = o.T_map_obj.translation();
    if (o.model) {
      g.class_name = o.model->name;
      const Eigen::AlignedBox3f box = boxOf(*o.model);
      g.centre = o.T_map_obj * box.center().cast<double>();
      g.box_pose = o.T_map_obj * Eigen::Translation3d(box.center().cast<double>());
      g.box_size = box.sizes().cast<double>();
    }
    if (stability) {
      const physics::BodyMotion* m = stability->find(o.id);
      if (m && m->simulated) g.stable = m->stable ? 1 : 0;
    }
    list.push_back(std::move(g));
  }
  return buildSupportGraph(list, contacts, gravity, config);
}

}  // namespace geofusion
