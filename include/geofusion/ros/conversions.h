// Messages <-> core types. The only place the ROS layer touches message fields one by one.
#pragma once

#include "geofusion/common/measurement.h"

#include "geofusion/common/camera.h"
#include "geofusion/common/lens.h"

#include <geofusion/DetectionArray.h>
#include <geometry_msgs/Point.h>
#include <geometry_msgs/Pose.h>
#include <geometry_msgs/Twist.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include <cstdint>
#include <string>
#include <vector>

namespace geofusion {

/// The raw detection, unchecked: NaNs and non-unit quaternions pass through to the core's check.
RawDetection fromMsg(const geofusion::Detection& msg);
std::vector<RawDetection> fromMsg(const geofusion::DetectionArray& msg);

geofusion::Detection toMsg(const RawDetection& detection);
geometry_msgs::Pose toPoseMsg(const Eigen::Isometry3d& T);
geometry_msgs::Point toPointMsg(const Eigen::Vector3d& p);
/// Twist in the moving frame that takes `from` to `to` in `dt` seconds (zero for dt <= 0).
geometry_msgs::Twist twistBetween(const Eigen::Isometry3d& from, const Eigen::Isometry3d& to,
                                  double dt);

/// Why a depth image cannot be used (empty, encoding other than 32FC1 metres / 16UC1
/// millimetres, data shorter than step * height), or nullptr.
const char* depthProblem(const sensor_msgs::Image& depth);
/// Depth in metres, row-major, 0 = no reading (NaN, inf, non-positive and 16-bit 0 become 0).
/// False when depthProblem() says the image is unusable.
bool depthToMetres(const sensor_msgs::Image& depth, std::vector<float>* metres);
/// The image as 8-bit grey, row-major without padding (cv_bridge: mono8 as is, colour and 16-bit
/// converted). False, with the reason, for an empty or unconvertible image.
bool toGray(const sensor_msgs::Image& image, std::vector<std::uint8_t>* gray, std::string* error);
/// Pinhole intrinsics from the K matrix (the lens, if any, is lensFromCameraInfo's).
PinholeIntrinsics intrinsicsFromCameraInfo(const sensor_msgs::CameraInfo& info);
/// The lens distortion of a camera_info: plumb_bob (5 coefficients) and rational_polynomial (8),
/// as OpenCV models them; any model with D empty or all zero is no distortion. False, with the
/// reason, for another model with a non-zero D (equidistant, ...) or unusable coefficients.
bool lensFromCameraInfo(const sensor_msgs::CameraInfo& info, LensDistortion* lens,
                        std::string* error);

/// A camera's raw images made pinhole: K and the lens taken from each camera_info, the warp's
/// maps made once and rebuilt only when the calibration changes (common/lens.h). What every
/// consumer of the cameras' images calls before using them (the estimator, the visual odometry,
/// the tools), so a camera that publishes distorted images with its plumb_bob D just works.
class CameraRectifier {
 public:
  /// K and the lens of `info`; false, with the reason, when K is not a camera (size or focal
  /// length not positive) or the distortion cannot be rectified.
  bool update(const sensor_msgs::CameraInfo& info, std::string* error);
  const PinholeIntrinsics& K() const { return K_; }
  const LensDistortion& lens() const { return lens_; }
  /// The image, K.width x K.height, made pinhole in place (nothing to do without distortion).
  /// False when its size is not the camera_info's.
  bool rectifyDepth(std::vector<float>* depth) { return warp_.rectifyDepth(K_, lens_, depth); }
  bool rectifyGrey(std::vector<std::uint8_t>* grey) { return warp_.rectifyGrey(K_, lens_, grey); }

 private:
  PinholeIntrinsics K_;
  LensDistortion lens_;
  LensWarp warp_;
};

/// A synchronised colour, depth and camera_info as the visual odometry takes them: 8-bit grey and
/// metric depth of one size, made pinhole by `camera` (updated from `info`). False, with the
/// reason, for an unconvertible image, sizes that differ or an unusable camera_info. The one
/// preparation of the odometry node and vo_benchmark.
bool odometryImages(const sensor_msgs::Image& rgb, const sensor_msgs::Image& depth,
                    const sensor_msgs::CameraInfo& info, CameraRectifier* camera,
                    std::vector<std::uint8_t>* gray, std::vector<float>* metres,
                    std::string* error);

}  // namespace geofusion
