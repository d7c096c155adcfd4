// Image boxes of posed models: the one rule for "the camera sees this object" that the BOP
// results writer (runtime) and the evaluation (COCO boxes, BOP targets) share.
#pragma once

#include "geofusion/common/camera.h"

#include <Eigen/Geometry>

#include <vector>

namespace geofusion {

/// An axis-aligned image box [x0, x1] x [y0, y1], pixels.
struct Box2d {
  double x0 = 0.0, y0 = 0.0, x1 = 0.0, y1 = 0.0;
  double width() const { return x1 - x0; }
  double height() const { return y1 - y0; }
  bool empty() const { return !(x1 > x0 && y1 > y0); }
};

/// Intersection over union of two boxes (COCO's, no +1 on widths); 0 when either is empty.
double boxIou(const Box2d& a, const Box2d& b);

/// The box of the model points posed in the camera frame, projected with K and clipped to the
/// image (bop_toolkit's calc_2d_bbox). Points less than 1 cm in front of the camera are left
/// out; empty when none is left or the box misses the image.
Box2d projectedBox(const std::vector<Eigen::Vector3f>& points, const Eigen::Isometry3d& T_cam_obj,
                   const PinholeIntrinsics& K);

}  // namespace geofusion
