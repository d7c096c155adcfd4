// A stable colour per class name, the same in every run, node and plot.
#pragma once

#include <string>

namespace geofusion {

struct Rgb {
  float r = 0.f;
  float g = 0.f;
  float b = 0.f;
};

/// Saturated colour derived from a stable (FNV-1a) hash of the class name; hues of different
/// names are spread by the golden angle.
Rgb classColor(const std::string& class_name);

/// HSV (h in [0, 1), s and v in [0, 1]) to RGB.
Rgb hsvToRgb(double h, double s, double v);

}  // namespace geofusion
