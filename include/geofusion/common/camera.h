// Pinhole camera model shared by the renderer, the consistency score and the scene generators.
// Convention: optical frame (x right, y down, z forward); pixel (u, v) has its centre at integer
// coordinates, so the ray through pixel (u, v) is ((u - cx) / fx, (v - cy) / fy, 1).
#pragma once

#include <Eigen/Geometry>

namespace geofusion {

/// A 2D box in image pixels; width or height of 0 means "no box".
struct PixelBox {
  int x = 0;
  int y = 0;
  int width = 0;
  int height = 0;
  bool valid() const { return width > 0 && height > 0; }
  int area() const { return valid() ? width * height : 0; }
};

/// Pinhole intrinsics of a 640x480 PrimeSense Carmine class camera (Fetch head camera).
struct PinholeIntrinsics {
  int width = 640;
  int height = 480;
  double fx = 554.254691191187;
  double fy = 554.254691191187;
  double cx = 320.5;
  double cy = 240.5;

  bool valid() const { return width > 0 && height > 0 && fx > 0.0 && fy > 0.0; }
  /// Continuous pixel coordinates of a point in the optical frame (z > 0).
  Eigen::Vector2d project(const Eigen::Vector3d& p) const {
    return {fx * p.x() / p.z() + cx, fy * p.y() / p.z() + cy};
  }
  /// The pixel whose centre is nearest to continuous coordinates `uv`; false when that pixel is
  /// outside the image (or uv is not finite).
  bool nearestPixel(const Eigen::Vector2d& uv, int* u, int* v) const {
    const double x = uv.x() + 0.5, y = uv.y() + 0.5;  // floor(x) rounds uv.x() for x >= 0
    if (!(x >= 0.0 && y >= 0.0 && x < width && y < height)) return false;
    *u = static_cast<int>(x);
    *v = static_cast<int>(y);
    return true;
  }
  /// The point at depth `z` (along the optical axis) on the ray through pixel (u, v).
  Eigen::Vector3d backProject(double u, double v, double z) const {
    return {(u - cx) / fx * z, (v - cy) / fy * z, z};
  }
};

/// Pose of an optical frame (z forward, x right, y down) at `eye` looking at `target`, with the
/// image's up direction as close to `up` as possible. `target - eye` must not be parallel to `up`.
inline Eigen::Isometry3d lookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target,
                                const Eigen::Vector3d& up = Eigen::Vector3d::UnitZ()) {
  const Eigen::Vector3d z = (target - eye).normalized();
  const Eigen::Vector3d x = z.cross(up).normalized();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear().col(0) = x;
  T.linear().col(1) = z.cross(x);
  T.linear().col(2) = z;
  T.translation() = eye;
  return T;
}

}  // namespace geofusion
