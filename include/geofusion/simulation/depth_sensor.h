// Depth camera models of the data generator: what a robot's depth camera does to the true depth.
// One model per camera family a Fetch-style robot carries (docs/dataset.md, "Sensor models"):
// - structured light (Primesense Carmine / Asus Xtion / Kinect v1: the Fetch head camera):
//   disparity noise, sigma_z = z^2 sigma_d / (f b), disparity quantisation, holes in the
//   projector's shadow, a band of flying or missing pixels at depth edges;
// - active stereo (RealSense D4xx): the same disparity model with the second camera's occlusion,
//   finer sub-pixel steps;
// - time of flight (Azure Kinect): phase noise growing with distance, mixed (flying) pixels at
//   edges, no shadow;
// and for all of them holes on materials that return nothing (dark, specular, transparent: a
// per-class flag of the model set), holes at grazing angles, and a colour-depth misregistration.
// `nguyen2012` is the generator's earlier model (sigma from Nguyen et al. 2012, 1 mm steps).
#pragma once

#include "geofusion/common/camera.h"
#include "geofusion/model/object_model.h"

#include <cstdint>
#include <random>
#include <string>
#include <vector>

namespace geofusion {

enum class DepthSensorKind { kNguyen2012, kStructuredLight, kActiveStereo, kTimeOfFlight };
const char* toString(DepthSensorKind kind);

struct DepthNoise {
  DepthSensorKind kind = DepthSensorKind::kNguyen2012;
  std::string name = "nguyen2012";  ///< the preset it came from
  // Nguyen et al. 2012 (kNguyen2012): sigma(z) = base + quad * (z - 0.4)^2.
  double sigma_base_m = 0.0012;
  double sigma_quad_m = 0.0019;
  double quantisation_m = 0.001;    ///< output steps (16-bit millimetres); 0: none
  double edge_jump_m = 0.02;        ///< a depth edge: neighbours further apart than this
  double edge_dropout = 0.5;        ///< pixels at (or within edge_band_px of) an edge: no depth
  double grazing_angle_deg = 78.0;  ///< surfaces seen more obliquely lose their depth ...
  double grazing_dropout = 0.8;     ///< ... with this probability
  double max_range_m = 4.0;         ///< beyond: no depth
  double min_range_m = 0.0;         ///< nearer: no depth
  // Disparity models (structured light, active stereo).
  double focal_px = 570.0;          ///< the depth camera's focal length at 640 px width
  double baseline_m = 0.075;        ///< projector or second camera, along the camera's +x
  double disparity_sigma_px = 0.0;  ///< random disparity error (sigma_z = z^2 sigma_d / (f b))
  double disparity_step_px = 0.0;   ///< disparity quantisation (0: none)
  bool shadow = false;              ///< no depth where the projector (second camera) cannot see ...
  /// ... from this far along the camera's x (signed; in the image the depth is registered to,
  /// not necessarily the baseline of the disparity).
  double shadow_baseline_m = 0.075;
  // Time of flight: sigma(z) = tof_sigma_m + tof_sigma_per_m * z.
  double tof_sigma_m = 0.0;
  double tof_sigma_per_m = 0.0;
  // Depth edges (all but kNguyen2012): within edge_band_px of an edge a pixel loses its depth
  // (edge_dropout) or, with edge_flying, reads a depth between the two sides.
  int edge_band_px = 0;
  double edge_flying = 0.0;
  // Materials: the share of an object's surface (in 4 x 4 pixel blocks) with no reading.
  double dark_dropout = 0.0;
  double specular_dropout = 0.0;
  double transparent_dropout = 0.0;
  /// Colour-depth misregistration: the depth image is this many pixels off the colour image.
  int misregistration_x_px = 0;
  int misregistration_y_px = 0;

  static DepthNoise nguyen2012();
  /// Primesense Carmine 1.09 / Asus Xtion Pro Live (the Fetch head camera), calibrated against
  /// real Xtion frames of YCB-Video (docs/dataset.md).
  static DepthNoise structuredLight();
  static DepthNoise activeStereo();  ///< Intel RealSense D435 at 640 x 480
  static DepthNoise timeOfFlight();  ///< Azure Kinect, NFOV unbinned
  /// The preset of a name: nguyen2012, structured_light (alias fetch_head), active_stereo,
  /// time_of_flight. False for others.
  static bool byName(const std::string& name, DepthNoise* noise);
  static const std::vector<std::string>& names();
  /// Every setting, for a generator request (cache key) and the docs.
  std::string describe() const;
};

/// Applies the model to a rendered depth image (metres, 0 = nothing). `instance` (optional): the
/// render's instance id per pixel; `material_of[id]` the material of that instance (ids beyond
/// it, and without `instance`, are diffuse).
void applyDepthNoise(const PinholeIntrinsics& K, const DepthNoise& noise, std::mt19937& rng,
                     std::vector<float>* depth,
                     const std::vector<std::uint16_t>* instance = nullptr,
                     const std::vector<SurfaceMaterial>* material_of = nullptr);

}  // namespace geofusion
