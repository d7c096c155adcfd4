#include "geofusion/common/image_box.h"

#include <algorithm>
#include <limits>

namespace geofusion {

Box2d projectedBox(const std::vector<Eigen::Vector3f>& points, const Eigen::Isometry3d& T_cam_obj,
                   const PinholeIntrinsics& K) {
  Box2d b;
  b.x0 = b.y0 = std::numeric_limits<double>::infinity();
  b.x1 = b.y1 = -std::numeric_limits<double>::infinity();
  bool any = false;
  for (const auto& p : points) {
    const Eigen::Vector3d q = T_cam_obj * p.cast<double>();
    if (!(q.z() > 0.01)) continue;
    const Eigen::Vector2d uv = K.project(q);
    b.x0 = std::min(b.x0, uv.x());
    b.y0 = std::min(b.y0, uv.y());
    b.x1 = std::max(b.x1, uv.x());
    b.y1 = std::max(b.y1, uv.y());
    any = true;
  }
  if (!any) return Box2d();
  b.x0 = std::clamp(b.x0, 0.0, static_cast<double>(K.width));
  b.x1 = std::clamp(b.x1, 0.0, static_cast<double>(K.width));
  b.y0 = std::clamp(b.y0, 0.0, static_cast<double>(K.height));
  b.y1 = std::clamp(b.y1, 0.0, static_cast<double>(K.height));
  return b.empty() ? Box2d() : b;
}

double boxIou(const Box2d& a, const Box2d& b) {
  if (a.empty() || b.empty()) return 0.0;
  const double w = std::min(a.x1, b.x1) - std::max(a.x0, b.x0);
  const double h = std::min(a.y1, b.y1) - std::max(a.y0, b.y0);
  if (w <= 0 || h <= 0) return 0.0;
  const double inter = w * h;
  return inter / (a.width() * a.height() + b.width() * b.height() - inter);
}

}  // namespace geofusion
