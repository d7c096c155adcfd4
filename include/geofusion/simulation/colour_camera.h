// What a robot's colour camera does to the rendered image (docs/dataset.md, "Sensor models"):
// motion blur over the exposure, the rolling shutter's row delay, auto exposure drifting from
// frame to frame, read and shot noise. The image motion comes from the camera's own motion
// between two frames (its flow at the image centre for a point at the scene's median depth), so
// blur and shear follow how fast the head turns. Lens distortion is not modelled: the images
// stay pinhole, as camera_info says.
#pragma once

#include "geofusion/common/camera.h"

#include <Eigen/Geometry>

#include <cstdint>
#include <random>
#include <string>
#include <vector>

namespace geofusion {

struct ColourNoise {
  bool enabled = false;
  double exposure_s = 0.015;   ///< the shutter is open this long: the image smears
  double readout_s = 0.025;    ///< the last row is read this much after the first
  double read_noise_dn = 2.0;  ///< sigma of the noise, grey levels: read + shot * sqrt(level)
  double shot_noise = 0.5;
  double exposure_walk = 0.02;   ///< auto exposure: the gain's log random walk a frame ...
  double exposure_range = 0.15;  ///< ... within 1 +- this

  /// The Fetch head camera's colour (Primesense RGB, 30 Hz, rolling shutter; indoor exposure).
  static ColourNoise fetchHead();
  std::string describe() const;
};

class ColourCamera {
 public:
  ColourCamera(const ColourNoise& noise, unsigned seed);
  /// The image seen at T_map_cur, the camera having been at T_map_prev dt_s before (optical
  /// frames); `scene_depth_m` the depth whose image motion blurs (the median of the frame's).
  /// rgb8, row-major, in place.
  void apply(const PinholeIntrinsics& K, const Eigen::Isometry3d& T_map_prev,
             const Eigen::Isometry3d& T_map_cur, double dt_s, double scene_depth_m,
             std::vector<std::uint8_t>* rgb);
  /// The image motion at the centre of the last frame, pixels a second.
  const Eigen::Vector2d& lastFlow() const { return flow_; }
  double gain() const { return gain_; }

 private:
  ColourNoise noise_;
  std::mt19937 rng_;
  double gain_ = 1.0;
  Eigen::Vector2d flow_ = Eigen::Vector2d::Zero();
};

}  // namespace geofusion
