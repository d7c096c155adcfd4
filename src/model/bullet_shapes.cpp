#include "geofusion/model/bullet_shapes.h"

namespace geofusion {

btTransform toBullet(const Eigen::Isometry3d& T) {
  const Eigen::Quaterniond q(T.linear());
  const Eigen::Vector3d& t = T.translation();
  return btTransform(
      btQuaternion(btScalar(q.x()), btScalar(q.y()), btScalar(q.z()), btScalar(q.w())),
      btVector3(btScalar(t.x()), btScalar(t.y()), btScalar(t.z())));
}

std::unique_ptr<btConvexHullShape> bulletHull(const TriangleMesh& hull,
                                              const Eigen::Vector3f& centre, double margin) {
  auto shape = std::make_unique<btConvexHullShape>();
  for (const Eigen::Vector3f& v : hull.vertices) {
    const Eigen::Vector3f p = v - centre;
    shape->addPoint(btVector3(p.x(), p.y(), p.z()), false);
  }
  shape->recalcLocalAabb();
  shape->setMargin(btScalar(margin));
  return shape;
}

}  // namespace geofusion
