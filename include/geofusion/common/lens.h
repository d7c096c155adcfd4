// Lens distortion as ROS camera_info states it (plumb_bob: k1 k2 p1 p2 k3; rational_polynomial:
// k1 k2 p1 p2 k3 k4 k5 k6) and the warps between a raw image, as the camera delivers it, and the
// pinhole image with the same K that the rest of the package assumes (common/camera.h). OpenCV
// does the work (initUndistortRectifyMap, undistortPoints, remap); its headers stay in lens.cpp.
#pragma once

#include "geofusion/common/camera.h"

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace geofusion {

struct LensDistortion {
  /// k1 k2 p1 p2 k3 [k4 k5 k6] (OpenCV's order, as camera_info's D); empty or all zero: none.
  std::vector<double> D;

  /// True when some coefficient is not zero (the images need warping).
  bool any() const;
  /// Why D cannot be used (not 0, 4, 5 or 8 coefficients; not finite), or "" when it can.
  std::string problem() const;
  /// D as a line of text, "none" when there is no distortion.
  std::string describe() const;

  /// The colour lens of a Primesense-family camera (the Fetch head camera's family): the
  /// calibration the TUM RGB-D benchmark publishes for its Kinect "freiburg2" (PS1080 like the
  /// Carmine 1.09): k1 0.2312, k2 -0.7849, p1 -0.0033, p2 -0.0001, k3 0.9172; 13-17 pixels at a
  /// VGA image's corners, 1.3-1.7 at the corners of its central third.
  static LensDistortion primesense();
};

/// Images OpenCV can warp: width and height below this (remap's coordinates are 16-bit).
constexpr int kMaxWarpSide = 32767;

/// Pixel maps between the raw and the pinhole image of one camera, built on the first call for a
/// K and D and rebuilt only when they change, then applied to every frame (remap). Depth is taken
/// from the nearest pixel (never a mix of two surfaces' depths: z along the optical axis does not
/// change under the warp); colour and grey are interpolated bilinearly. Pixels whose source falls
/// outside the image become 0 (no reading / black). Images are row-major, K.width x K.height.
class LensWarp {
 public:
  LensWarp();
  ~LensWarp();
  LensWarp(const LensWarp&) = delete;
  LensWarp& operator=(const LensWarp&) = delete;

  /// Raw (as the lens forms it) to pinhole, in place. False, nothing changed, when the image's
  /// size is not K's, D has a problem() or the image is too large to warp (kMaxWarpSide); true
  /// and nothing done when D has no distortion.
  bool rectifyDepth(const PinholeIntrinsics& K, const LensDistortion& D, std::vector<float>* depth);
  bool rectifyGrey(const PinholeIntrinsics& K, const LensDistortion& D,
                   std::vector<std::uint8_t>* grey);
  bool rectifyRgb(const PinholeIntrinsics& K, const LensDistortion& D,
                  std::vector<std::uint8_t>* rgb);
  /// Pinhole to raw, in place: what a camera with this lens delivers (the simulation).
  bool distortDepth(const PinholeIntrinsics& K, const LensDistortion& D, std::vector<float>* depth);
  bool distortRgb(const PinholeIntrinsics& K, const LensDistortion& D,
                  std::vector<std::uint8_t>* rgb);

 private:
  struct Maps;
  bool warp(const PinholeIntrinsics& K, const LensDistortion& D, bool rectify, int type,
            bool nearest, void* data, std::size_t size);
  std::unique_ptr<Maps> rectify_, distort_;
};

}  // namespace geofusion
