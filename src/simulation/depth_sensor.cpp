// Depth camera models of the data generator (depth_sensor.h, docs/dataset.md "Sensor models").
#include "geofusion/simulation/depth_sensor.h"

#include "geofusion/common/enum_names.h"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace geofusion {
namespace {

constexpr std::pair<DepthSensorKind, const char*> kKindNames[] = {
    {DepthSensorKind::kNguyen2012, "nguyen2012"},
    {DepthSensorKind::kStructuredLight, "structured_light"},
    {DepthSensorKind::kActiveStereo, "active_stereo"},
    {DepthSensorKind::kTimeOfFlight, "time_of_flight"},
};

// The generator's earlier model, unchanged (its recordings stay byte for byte the same).
void applyNguyen2012(const PinholeIntrinsics& K, const DepthNoise& noise, std::mt19937& rng,
                     std::vector<float>* depth) {
  std::normal_distribution<float> gauss(0.f, 1.f);
  std::uniform_real_distribution<float> uni(0.f, 1.f);
  const int W = K.width, H = K.height;
  const std::vector<float> clean = *depth;
  auto at = [&](int u, int v) { return clean[static_cast<std::size_t>(v) * W + u]; };
  const double cos_grazing = std::cos(noise.grazing_angle_deg * M_PI / 180.0);
  for (int v = 0; v < H; ++v) {
    for (int u = 0; u < W; ++u) {
      float& z = (*depth)[static_cast<std::size_t>(v) * W + u];
      if (!(z > 0.f)) continue;
      if (z > noise.max_range_m) {
        z = 0.f;
        continue;
      }
      // Holes beside depth discontinuities.
      bool edge = false;
      for (const auto& d : {std::make_pair(1, 0), std::make_pair(-1, 0), std::make_pair(0, 1),
                            std::make_pair(0, -1)}) {
        const int uu = u + d.first, vv = v + d.second;
        if (uu < 0 || vv < 0 || uu >= W || vv >= H) continue;
        const float zn = at(uu, vv);
        if (zn <= 0.f || std::abs(zn - at(u, v)) > noise.edge_jump_m) edge = true;
      }
      if (edge && uni(rng) < noise.edge_dropout) {
        z = 0.f;
        continue;
      }
      // Holes at grazing angles: surface normal from the clean neighbours.
      if (u + 1 < W && v + 1 < H && at(u + 1, v) > 0.f && at(u, v + 1) > 0.f) {
        const Eigen::Vector3d p = K.backProject(u, v, at(u, v));
        const Eigen::Vector3d n = (K.backProject(u + 1, v, at(u + 1, v)) - p)
                                      .cross(K.backProject(u, v + 1, at(u, v + 1)) - p);
        if (n.norm() > 0 && std::abs(n.normalized().dot(p.normalized())) < cos_grazing &&
            uni(rng) < noise.grazing_dropout) {
          z = 0.f;
          continue;
        }
      }
      const double dz = z - 0.4;
      const double sigma = noise.sigma_base_m + noise.sigma_quad_m * dz * dz;
      z = static_cast<float>(z + sigma * gauss(rng));
      if (noise.quantisation_m > 0)
        z = static_cast<float>(std::round(z / noise.quantisation_m) * noise.quantisation_m);
    }
  }
}

/// Pixels the emitter (projector, or the stereo pair's second camera) `baseline_m` along the
/// camera's x cannot see: along a row, a point whose column in the emitter's view (u - f b / z)
/// lies behind one nearer the emitter's side.
std::vector<std::uint8_t> shadowMask(const PinholeIntrinsics& K, double baseline_m,
                                     const std::vector<float>& clean) {
  const int W = K.width, H = K.height;
  std::vector<std::uint8_t> shadow(clean.size(), 0);
  const bool right = baseline_m > 0.0;  // emitter at +x: scan from the right
  for (int v = 0; v < H; ++v) {
    double nearest =
        right ? std::numeric_limits<double>::infinity() : -std::numeric_limits<double>::infinity();
    for (int k = 0; k < W; ++k) {
      const int u = right ? W - 1 - k : k;
      const float z = clean[static_cast<std::size_t>(v) * W + u];
      if (!(z > 0.f)) continue;
      const double column = u - K.fx * baseline_m / z;
      if (right ? column > nearest + 0.5 : column < nearest - 0.5) {
        shadow[static_cast<std::size_t>(v) * W + u] = 1;
      }
      nearest = right ? std::min(nearest, column) : std::max(nearest, column);
    }
  }
  return shadow;
}

/// Distance (pixels) of each pixel to the nearest depth edge: a pixel with a neighbour further
/// than `jump` away or without depth.
cv::Mat edgeDistance(const PinholeIntrinsics& K, double jump, const std::vector<float>& clean) {
  const int W = K.width, H = K.height;
  cv::Mat not_edge(H, W, CV_8U, cv::Scalar(1));
  for (int v = 0; v < H; ++v) {
    for (int u = 0; u < W; ++u) {
      const float z = clean[static_cast<std::size_t>(v) * W + u];
      if (!(z > 0.f)) continue;
      for (const auto& [du, dv] : {std::make_pair(1, 0), std::make_pair(-1, 0),
                                   std::make_pair(0, 1), std::make_pair(0, -1)}) {
        const int uu = u + du, vv = v + dv;
        if (uu < 0 || vv < 0 || uu >= W || vv >= H) continue;
        const float zn = clean[static_cast<std::size_t>(vv) * W + uu];
        if (!(zn > 0.f) || std::abs(zn - z) > jump) not_edge.at<std::uint8_t>(v, u) = 0;
      }
    }
  }
  cv::Mat distance;
  cv::distanceTransform(not_edge, distance, cv::DIST_L2, 3);
  return distance;
}

/// A flying pixel: a depth between the nearest and farthest surface around it.
float flyingDepth(const PinholeIntrinsics& K, const std::vector<float>& clean, int u, int v,
                  int radius, double t) {
  float lo = std::numeric_limits<float>::infinity(), hi = 0.f;
  for (int dv = -radius; dv <= radius; ++dv) {
    for (int du = -radius; du <= radius; ++du) {
      const int uu = u + du, vv = v + dv;
      if (uu < 0 || vv < 0 || uu >= K.width || vv >= K.height) continue;
      const float z = clean[static_cast<std::size_t>(vv) * K.width + uu];
      if (z > 0.f) lo = std::min(lo, z), hi = std::max(hi, z);
    }
  }
  return hi > 0.f ? static_cast<float>(lo + t * (hi - lo)) : 0.f;
}

double materialDropout(const DepthNoise& n, SurfaceMaterial m) {
  switch (m) {
    case SurfaceMaterial::kDark: return n.dark_dropout;
    case SurfaceMaterial::kSpecular: return n.specular_dropout;
    case SurfaceMaterial::kTransparent: return n.transparent_dropout;
    default: return 0.0;
  }
}

/// The random error of one reading: in disparity (structured light, stereo) or in phase (ToF).
float noisyDepth(const DepthNoise& n, double z, double gauss, double width_scale) {
  if (n.kind == DepthSensorKind::kTimeOfFlight) {
    return static_cast<float>(z + (n.tof_sigma_m + n.tof_sigma_per_m * z) * gauss);
  }
  const double fb = n.focal_px * width_scale * n.baseline_m;
  const double step = n.disparity_step_px * width_scale;
  double d = fb / z + n.disparity_sigma_px * width_scale * gauss;
  if (step > 0.0) d = std::round(d / step) * step;
  return d > 0.0 ? static_cast<float>(fb / d) : 0.f;
}

/// The depth image moved by (dx, dy) pixels against the colour image.
void shift(int dx, int dy, int W, int H, std::vector<float>* depth) {
  if (dx == 0 && dy == 0) return;
  const std::vector<float> in = *depth;
  std::fill(depth->begin(), depth->end(), 0.f);
  for (int v = 0; v < H; ++v) {
    for (int u = 0; u < W; ++u) {
      const int su = u - dx, sv = v - dy;
      if (su < 0 || sv < 0 || su >= W || sv >= H) continue;
      (*depth)[static_cast<std::size_t>(v) * W + u] = in[static_cast<std::size_t>(sv) * W + su];
    }
  }
}

/// A surface seen more obliquely than the grazing angle (a depth edge is not a surface).
bool grazing(const PinholeIntrinsics& K, const std::vector<float>& clean, int u, int v,
             double cos_grazing, double jump) {
  const int W = K.width;
  if (u + 1 >= W || v + 1 >= K.height) return false;
  const float z = clean[static_cast<std::size_t>(v) * W + u];
  const float zr = clean[static_cast<std::size_t>(v) * W + u + 1];
  const float zd = clean[static_cast<std::size_t>(v + 1) * W + u];
  if (!(zr > 0.f) || !(zd > 0.f) || std::abs(zr - z) > jump || std::abs(zd - z) > jump) {
    return false;
  }
  const Eigen::Vector3d p = K.backProject(u, v, z);
  const Eigen::Vector3d n =
      (K.backProject(u + 1, v, zr) - p).cross(K.backProject(u, v + 1, zd) - p);
  return n.norm() > 0 && std::abs(n.normalized().dot(p.normalized())) < cos_grazing;
}

/// Structured light, active stereo and time of flight (depth_sensor.h).
void applySensorModel(const PinholeIntrinsics& K, const DepthNoise& n, std::mt19937& rng,
                      std::vector<float>* depth, const std::vector<std::uint16_t>* instance,
                      const std::vector<SurfaceMaterial>* material_of) {
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  const int W = K.width, H = K.height;
  const double width_scale = W / 640.0;  // focal_px and the disparity figures are at 640 px
  const std::vector<float> clean = *depth;
  const std::vector<std::uint8_t> shadow =
      n.shadow ? shadowMask(K, n.shadow_baseline_m, clean) : std::vector<std::uint8_t>();
  const cv::Mat edge = edgeDistance(K, n.edge_jump_m, clean);
  const int bw = (W + 3) / 4, bh = (H + 3) / 4;  // material holes come in 4 x 4 blocks
  std::vector<double> block(static_cast<std::size_t>(bw) * bh);
  for (double& b : block) b = uni(rng);
  const double cos_grazing = std::cos(n.grazing_angle_deg * M_PI / 180.0);
  for (int v = 0; v < H; ++v) {
    for (int u = 0; u < W; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * W + u;
      float& z = (*depth)[i];
      if (!(z > 0.f)) continue;
      if (z > n.max_range_m || z < n.min_range_m || (n.shadow && shadow[i])) {
        z = 0.f;
        continue;
      }
      if (instance && material_of && (*instance)[i] < material_of->size()) {
        const double p = materialDropout(n, (*material_of)[(*instance)[i]]);
        if (p > 0.0 && block[static_cast<std::size_t>(v / 4) * bw + u / 4] < p) {
          z = 0.f;
          continue;
        }
      }
      if (edge.at<float>(v, u) <= n.edge_band_px) {
        if (uni(rng) < n.edge_dropout) {
          z = 0.f;
          continue;
        }
        if (uni(rng) < n.edge_flying) z = flyingDepth(K, clean, u, v, n.edge_band_px + 1, uni(rng));
      }
      if (grazing(K, clean, u, v, cos_grazing, n.edge_jump_m) && uni(rng) < n.grazing_dropout) {
        z = 0.f;
        continue;
      }
      if (!(z > 0.f)) continue;
      z = noisyDepth(n, z, gauss(rng), width_scale);
      if (n.quantisation_m > 0 && z > 0.f)
        z = static_cast<float>(std::round(z / n.quantisation_m) * n.quantisation_m);
    }
  }
  shift(n.misregistration_x_px, n.misregistration_y_px, W, H, depth);
}

}  // namespace

const char* toString(DepthSensorKind kind) {
  return nameIn(kKindNames, kind);
}

DepthNoise DepthNoise::nguyen2012() {
  return DepthNoise();
}

DepthNoise DepthNoise::structuredLight() {
  DepthNoise n;
  n.kind = DepthSensorKind::kStructuredLight;
  n.name = "structured_light";
  // Primesense's IR camera (about 570 px at VGA) and projector 7.5 cm apart; sub-pixel disparity
  // in 1/8 px steps (Khoshelham and Elberink 2012). sigma_d and the edge band: calibrated on the
  // real Xtion frames (docs/dataset.md, "Sensor models").
  n.focal_px = 570.0;
  n.baseline_m = 0.075;
  // In the depth registered to colour the holes of the projector's shadow lie right of the
  // objects and narrower than the IR camera's 7.5 cm give: measured on the real frames.
  n.shadow_baseline_m = -0.03;
  n.disparity_sigma_px = 0.17;
  n.disparity_step_px = 0.125;
  n.shadow = true;
  n.edge_band_px = 2;
  n.edge_dropout = 0.55;
  n.edge_flying = 0.03;
  n.min_range_m = 0.35;
  n.max_range_m = 4.0;
  n.dark_dropout = 0.2;
  n.specular_dropout = 0.12;
  n.transparent_dropout = 0.9;
  n.misregistration_x_px = 0;
  return n;
}

DepthNoise DepthNoise::activeStereo() {
  DepthNoise n;
  n.kind = DepthSensorKind::kActiveStereo;
  n.name = "active_stereo";
  // RealSense D435 at 640 x 480: about 383 px focal, 50 mm baseline, 0.08 px sub-pixel RMS
  // (Intel's datasheet), 1/32 px steps; the left imager is the reference, the right one at +x
  // cannot see the band left of every object.
  n.focal_px = 383.0;
  n.baseline_m = 0.050;
  n.disparity_sigma_px = 0.08;
  n.disparity_step_px = 1.0 / 32.0;
  n.shadow = true;
  n.shadow_baseline_m = 0.050;
  n.edge_band_px = 2;
  n.edge_dropout = 0.3;
  n.edge_flying = 0.3;
  n.min_range_m = 0.28;
  n.max_range_m = 6.0;
  n.dark_dropout = 0.05;
  n.specular_dropout = 0.2;
  n.transparent_dropout = 0.8;
  n.misregistration_x_px = 1;
  return n;
}

DepthNoise DepthNoise::timeOfFlight() {
  DepthNoise n;
  n.kind = DepthSensorKind::kTimeOfFlight;
  n.name = "time_of_flight";
  // Azure Kinect NFOV unbinned: random error about 1-2 mm at 1 m growing with distance
  // (Toelgyessy et al. 2021), mixed pixels at edges, illuminator beside the sensor (no shadow),
  // little return from dark surfaces.
  n.tof_sigma_m = 0.0006;
  n.tof_sigma_per_m = 0.0009;
  n.edge_band_px = 1;
  n.edge_dropout = 0.3;
  n.edge_flying = 0.6;
  n.min_range_m = 0.5;
  n.max_range_m = 3.86;
  n.dark_dropout = 0.3;
  n.specular_dropout = 0.3;
  n.transparent_dropout = 0.9;
  n.misregistration_x_px = 1;
  return n;
}

bool DepthNoise::byName(const std::string& name, DepthNoise* noise) {
  if (name == "nguyen2012") {
    *noise = nguyen2012();
  } else if (name == "structured_light" || name == "fetch_head") {
    *noise = structuredLight();
  } else if (name == "active_stereo") {
    *noise = activeStereo();
  } else if (name == "time_of_flight") {
    *noise = timeOfFlight();
  } else {
    return false;
  }
  return true;
}

const std::vector<std::string>& DepthNoise::names() {
  static const std::vector<std::string> n{"nguyen2012", "structured_light", "active_stereo",
                                          "time_of_flight"};
  return n;
}

std::string DepthNoise::describe() const {
  std::ostringstream o;
  o.precision(9);
  o << sigma_base_m << " " << sigma_quad_m << " " << quantisation_m << " " << edge_jump_m << " "
    << edge_dropout << " " << grazing_angle_deg << " " << grazing_dropout << " " << max_range_m;
  if (kind == DepthSensorKind::kNguyen2012) return o.str();  // the earlier requests unchanged
  o << "; sensor " << toString(kind) << " " << min_range_m << " " << focal_px << " " << baseline_m
    << " " << disparity_sigma_px << " " << disparity_step_px << " " << shadow << " "
    << shadow_baseline_m << " " << tof_sigma_m << " " << tof_sigma_per_m << " " << edge_band_px
    << " " << edge_flying << " " << dark_dropout << " " << specular_dropout << " "
    << transparent_dropout << " " << misregistration_x_px << " " << misregistration_y_px;
  return o.str();
}

void applyDepthNoise(const PinholeIntrinsics& K, const DepthNoise& noise, std::mt19937& rng,
                     std::vector<float>* depth, const std::vector<std::uint16_t>* instance,
                     const std::vector<SurfaceMaterial>* material_of) {
  if (noise.kind == DepthSensorKind::kNguyen2012) {
    applyNguyen2012(K, noise, rng, depth);
  } else {
    applySensorModel(K, noise, rng, depth, instance, material_of);
  }
}

}  // namespace geofusion
