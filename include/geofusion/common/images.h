// Views of images in memory (not owned), the form in which every module takes depth and grey
// images: the ROS layer, the simulation and the tests fill them from their own buffers.
#pragma once

#include <cstddef>
#include <cstdint>

namespace geofusion {

/// Observed depth: metres along the optical axis, row-major, `width` values a row. 0 or NaN (and
/// any non-positive or non-finite value) means "no reading".
struct DepthImageView {
  const float* data = nullptr;
  int width = 0;
  int height = 0;
  float at(int u, int v) const { return data[static_cast<std::size_t>(v) * width + u]; }
};

/// An 8-bit grey image in memory (not owned). `step` is bytes per row (0: width).
struct GrayImageView {
  const std::uint8_t* data = nullptr;
  int width = 0;
  int height = 0;
  int step = 0;
};

}  // namespace geofusion
