// A small analytic tabletop scene of boxes, ray-cast into depth, RGB and instance images.
// It makes self-contained test and demo recordings without any model files or GPU: the package's
// foundation tests and the first demo run on it. (The physically settled, OSMesa-rendered
// generator of the data issue supersedes it for benchmarks.)
#pragma once

#include "geofusion/common/camera.h"
#include "geofusion/common/class_palette.h"
#include "geofusion/common/measurement.h"

#include <Eigen/Geometry>

#include <cstdint>
#include <random>
#include <string>
#include <vector>

namespace geofusion {

/// A box-shaped object whose model frame sits at the box centre, axes along its edges.
struct BoxObject {
  std::string class_name;
  int class_id = -1;
  Eigen::Vector3d size = Eigen::Vector3d::Constant(0.1);  ///< full edge lengths, metres
  Eigen::Isometry3d T_world_obj = Eigen::Isometry3d::Identity();
};

/// Rendered images, row-major. depth in metres along the optical axis (z), 0 = no return.
/// instance: index into BoxScene::objects, kTable for the table top, kBackground otherwise.
struct RenderedFrame {
  static constexpr int kBackground = -1;
  static constexpr int kTable = -2;
  int width = 0;
  int height = 0;
  std::vector<float> depth;
  std::vector<std::uint8_t> rgb;  ///< 3 bytes per pixel, rgb8
  std::vector<int> instance;
};

class BoxScene {
 public:
  /// Table top: the rectangle |x| <= half_x, |y| <= half_y at z = table_height_m (world frame,
  /// z up). The floor (z = 0) is visible around it up to max_range_m.
  double table_height_m = 0.72;
  double table_half_x_m = 0.6;
  double table_half_y_m = 0.4;
  double max_range_m = 6.0;
  std::vector<BoxObject> objects;

  /// Six YCB-sized boxes on a table, two of them stacked, some touching.
  static BoxScene demoScene();

  /// Ray-casts the scene seen from a camera whose optical frame is T_world_cam (REP-103 optical:
  /// z forward, x right, y down).
  RenderedFrame render(const PinholeIntrinsics& K, const Eigen::Isometry3d& T_world_cam) const;
};

/// Number of pixels of each object in a rendered frame.
std::vector<int> visiblePixelCounts(const RenderedFrame& frame, std::size_t num_objects);

/// Noise of the simple detection synthesiser.
struct DetectionNoise {
  double translation_sigma_m = 0.003;  ///< per axis
  double rotation_sigma_rad = 0.02;    ///< per axis of a small rotation vector
  double min_score = 0.6;
  double max_score = 1.0;
  int min_visible_pixels = 300;  ///< objects with fewer pixels are not detected
};

/// Detections of every sufficiently visible object of `scene` in `frame`: true pose in the camera
/// frame perturbed by `noise`, a uniform score, and the 2D box of its visible pixels.
std::vector<RawDetection> synthesizeDetections(const BoxScene& scene, const RenderedFrame& frame,
                                               const Eigen::Isometry3d& T_world_cam,
                                               const DetectionNoise& noise, std::mt19937& rng);

}  // namespace geofusion
