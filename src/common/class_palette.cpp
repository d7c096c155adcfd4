#include "geofusion/common/class_palette.h"

#include <cmath>
#include <cstdint>

namespace geofusion {

Rgb hsvToRgb(double h, double s, double v) {
  h = h - std::floor(h);
  const double hh = h * 6.0;
  const int sector = static_cast<int>(hh) % 6;
  const double f = hh - std::floor(hh);
  const double p = v * (1.0 - s);
  const double q = v * (1.0 - s * f);
  const double t = v * (1.0 - s * (1.0 - f));
  double r = v, g = t, b = p;
  switch (sector) {
    case 0:
      r = v;
      g = t;
      b = p;
      break;
    case 1:
      r = q;
      g = v;
      b = p;
      break;
    case 2:
      r = p;
      g = v;
      b = t;
      break;
    case 3:
      r = p;
      g = q;
      b = v;
      break;
    case 4:
      r = t;
      g = p;
      b = v;
      break;
    default:
      r = v;
      g = p;
      b = q;
      break;
  }
  return Rgb{static_cast<float>(r), static_cast<float>(g), static_cast<float>(b)};
}

Rgb classColor(const std::string& class_name) {
  std::uint64_t hash = 1469598103934665603ull;  // FNV-1a 64-bit
  for (unsigned char c : class_name) {
    hash ^= c;
    hash *= 1099511628211ull;
  }
  constexpr double kGoldenRatioConjugate = 0.618033988749895;
  const double hue = std::fmod(static_cast<double>(hash % 1000003ull) * kGoldenRatioConjugate, 1.0);
  const double value = 0.75 + 0.25 * static_cast<double>((hash >> 32) % 2);
  return hsvToRgb(hue, 0.85, value);
}

}  // namespace geofusion
