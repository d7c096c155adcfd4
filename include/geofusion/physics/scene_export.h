// The map in a simulator (issue 50): the objects the stability check simulates, written as an SDF
// world and a URDF, with their meshes beside them. The same bodies as the check (bodyShapes), the
// same mass and inertia (compoundMassProperties), the same slab under them (supportSlab): loading
// the SDF back into the check gives the same motions (test SceneExport.*). Format and use in
// docs/scene_export.md.
#pragma once
#include "geofusion/physics/stability.h"

#include <string>
#include <vector>

namespace geofusion {
namespace physics {

/// What exportScene wrote.
struct SceneExport {
  std::string sdf_path;   ///< <folder>/scene.sdf: one world, a model per object, the slab
  std::string urdf_path;  ///< <folder>/scene.urdf: a link per object on a floating joint
  std::vector<std::string> mesh_paths;  ///< <folder>/meshes/*.stl, visual and collision
  int exported = 0;                     ///< objects written
  /// Objects not written (no model, pose not finite, no collision shape) and bad settings, each
  /// named; the rest of the map is still written.
  std::vector<std::string> warnings;
};

/// The name of a body in the exported files: "<class>_<id>" ("object_<id>" without a model),
/// made of letters, digits and '_' only.
std::string exportedBodyName(const StabilityBody& body);

/// Writes `folder`/scene.sdf, `folder`/scene.urdf and `folder`/meshes/ (the folder is made when
/// missing; files already there are replaced). The bodies as checkStability puts them: each
/// object's convex shapes as collisions, its model mesh as the visual, mass density x volume and
/// Bullet's inertia, the support plane (none: a floor under the lowest object) as a static box,
/// gravity along `gravity` (zero: -plane normal), friction from `config`. Meshes are referred to
/// by absolute file:// URIs. False (with `error`) when the folder or a file cannot be written.
bool exportScene(const std::vector<StabilityBody>& bodies, const StabilityPlane* plane,
                 const Eigen::Vector3d& gravity, const StabilityConfig& config,
                 const std::string& folder, SceneExport* result, std::string* error);

}  // namespace physics
}  // namespace geofusion
