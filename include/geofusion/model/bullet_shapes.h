// Bullet forms of poses and collision hulls, shared by model/collision.cpp (penetration depths)
// and physics/rigid_world.cpp (the simulated bodies). Includes Bullet: for those .cpp files,
// never for a widely included header.
#pragma once

#include "geofusion/model/mesh.h"

#include <BulletCollision/CollisionShapes/btConvexHullShape.h>
#include <LinearMath/btTransform.h>

#include <Eigen/Geometry>

#include <memory>

namespace geofusion {

btTransform toBullet(const Eigen::Isometry3d& T);

/// The hull's vertices less `centre` as a Bullet convex hull with the collision `margin` (0: the
/// hull itself, not Bullet's rounded shell around it).
std::unique_ptr<btConvexHullShape> bulletHull(const TriangleMesh& hull,
                                              const Eigen::Vector3f& centre, double margin);

}  // namespace geofusion
