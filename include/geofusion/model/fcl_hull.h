// FCL forms of the collision hulls and the two FCL queries on them. Includes FCL: for the .cpp
// files that work with FCL objects directly (model/collision.cpp, simulation/clutter_scene.cpp),
// never for a widely included header.
#pragma once

#include "geofusion/model/collision.h"

#include <fcl/geometry/shape/convex.h>
#include <fcl/narrowphase/collision_object.h>

#include <memory>

namespace geofusion {

/// The model's collision hull (collisionHullOf) as an FCL convex shape.
std::shared_ptr<fcl::CollisionGeometryd> fclHull(const ObjectModel& model);

/// Deepest penetration of the two objects' contacts (libccd's MPR: the depth along the line of
/// the centres, an upper bound of the smallest parting translation HullCollider gives; the
/// generator's settled-scene check keeps it so that its scenes stay as they were made), 0 when
/// they do not collide.
double fclPenetration(fcl::CollisionObjectd* a, fcl::CollisionObjectd* b);

/// Distance between the two objects, 0 when they touch or intersect.
double fclDistance(fcl::CollisionObjectd* a, fcl::CollisionObjectd* b);

}  // namespace geofusion
