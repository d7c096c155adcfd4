// RGB-D sequences of a clutter scene seen by a Fetch-like robot: base trajectory around the table,
// head camera images (OSMesa) with a structured-light depth noise model, noisy per-frame
// detections (DenseFusion-like or PoseCNN-like), and drifting odometry. ROS-free; the
// generate_dataset tool writes them as bags.
#pragma once

#include "geofusion/common/camera.h"
#include "geofusion/common/measurement.h"
#include "geofusion/render/renderer.h"
#include "geofusion/simulation/clutter_scene.h"
#include "geofusion/simulation/depth_sensor.h"
#include "geofusion/simulation/detector_errors.h"

#include <Eigen/Geometry>

#include <cstdint>
#include <memory>
#include <random>
#include <string>
#include <utility>
#include <vector>

namespace geofusion {

/// Fixed transforms of the Fetch-like head (REP-103 optical frame).
struct RobotGeometry {
  /// base_link -> head_camera_link for a given camera height and pan/tilt.
  static Eigen::Isometry3d baseToCameraLink(double height_m, double pan_rad, double tilt_rad);
  /// head_camera_link -> head_camera_rgb_optical_frame (x right, y down, z forward).
  static Eigen::Isometry3d cameraLinkToOptical();
};

struct TrajectoryConfig {
  int frames = 200;              ///< keyframes
  double rate_hz = 5.0;          ///< keyframe rate
  double min_distance_m = 0.75;  ///< base distance from the clutter centre
  double max_distance_m = 1.1;
  double min_height_m = 1.0;  ///< camera height above the floor
  double max_height_m = 1.45;
  double arc_rad = 2.6;          ///< angle swept around the table
  double pause_fraction = 0.15;  ///< share of frames standing still
  /// The head's look-at point swings about the clutter centre by this much (metres) ...
  double look_amplitude_m = 0.03;
  /// ... this many times faster than the default swing (larger: faster head turns).
  double look_rate = 1.0;
};

struct FramePose {
  double stamp_s = 0.0;                                             ///< from the sequence start
  Eigen::Isometry3d T_map_base = Eigen::Isometry3d::Identity();     ///< ground truth
  Eigen::Isometry3d T_base_link = Eigen::Isometry3d::Identity();    ///< base -> head_camera_link
  Eigen::Isometry3d T_map_optical = Eigen::Isometry3d::Identity();  ///< ground truth camera
  Eigen::Isometry3d T_odom_base = Eigen::Isometry3d::Identity();    ///< drifting odometry
};

/// Smooth arcs around the table at varying distance and camera height, with pauses and turns,
/// head looking at the clutter. Deterministic for the seed. Odometry left equal to ground truth.
std::vector<FramePose> makeTrajectory(const ClutterScene& scene, const TrajectoryConfig& config,
                                      unsigned seed);

struct OdometryNoise {
  /// Systematic, drawn once a sequence (random sign, magnitude 0.5 to 1 times these): the scale
  /// error of travelled distance ...
  double translation_fraction = 0.006;
  double yaw_rad_per_m = 0.006;  ///< ... and the heading bias per metre travelled.
  /// Random, each step: std of the position error (random walk, grows with sqrt(distance)) ...
  double translation_m_per_sqrt_m = 0.0003;
  double yaw_rad_per_sqrt_rad = 0.0008;  ///< ... and of the heading error per sqrt(radian) turned.
};

/// Fills T_odom_base by integrating the ground-truth increments with noise (odom = map at the
/// first frame).
void addOdometryDrift(std::vector<FramePose>* poses, const OdometryNoise& noise, unsigned seed);

/// Largest and final position error of odometry against ground truth (odom aligned at start).
struct DriftStats {
  double max_m = 0.0;
  double final_m = 0.0;
  double path_length_m = 0.0;
};
DriftStats measureDrift(const std::vector<FramePose>& poses);

/// Detector error model. Defaults: DenseFusion-like (YCB-Video ADD-S AUC about 93, about 97 %
/// under 2 cm); posecnn() is the harsher PoseCNN-like preset (AUC about 76).
struct DetectorModel {
  double translation_sigma_m = 0.005;  ///< per axis
  double rotation_sigma_rad = 0.06;
  double gross_error_rate = 0.03;    ///< pose off by 3-10 cm and a random rotation
  double symmetric_flip_rate = 0.3;  ///< a symmetric object's pose by one of its symmetries
  double class_swap_rate = 0.02;     ///< look-alike classes confused
  double miss_rate = 0.03;           ///< fully visible objects missed
  double miss_occlusion_gain = 0.9;  ///< miss rate grows with occluded fraction squared
  int min_visible_pixels = 250;
  double false_positives_per_frame = 0.3;
  /// Per-class multipliers of the pose noise (the clamps are much worse).
  std::vector<std::pair<std::string, double>> class_noise_gain = {{"051_large_clamp", 3.0},
                                                                  {"052_extra_large_clamp", 3.5},
                                                                  {"011_banana", 1.5},
                                                                  {"037_scissors", 1.8},
                                                                  {"040_large_marker", 1.5}};
  std::vector<std::pair<std::string, std::string>> look_alikes = {
      {"051_large_clamp", "052_extra_large_clamp"},
      {"008_pudding_box", "009_gelatin_box"},
      {"005_tomato_soup_can", "007_tuna_fish_can"},
      {"024_bowl", "025_mug"}};
  /// Errors that persist over keyframes (all off in the independent presets).
  PersistentErrorModel persistence;

  /// Independent errors per frame (the paper's setting): DenseFusion-like, PoseCNN-like.
  static DetectorModel denseFusion() { return DetectorModel(); }
  static DetectorModel posecnn();
  /// Persistent errors of real estimators: DenseFusion-like with a slowly drifting bias,
  /// swapped and missed stretches and a phantom; colour-only (MegaPose / PoseCNN RGB-like) with
  /// centimetres of error along the viewing ray (docs/dataset.md).
  static DetectorModel denseFusionPersistent();
  static DetectorModel rgbOnly();
  /// The preset of a name: densefusion, posecnn, densefusion_persistent, rgb. False for others.
  static bool byName(const std::string& name, DetectorModel* model);
  static const std::vector<std::string>& names();
};

/// One frame of a sequence: images, ground truth per object, detections.
struct SequenceFrame {
  RenderedImages images;                 ///< rgb, depth (noisy), instance (object index + 1)
  std::vector<float> clean_depth;        ///< before noise
  std::vector<double> visible_fraction;  ///< per object: visible / unoccluded pixels
  std::vector<int> visible_pixels;
  std::vector<PixelBox> visible_boxes;  ///< per object: box of its visible pixels (empty: none)
  /// Per object taken away (a changed scene), the share of its old place the camera sees (its
  /// silhouette at its old pose that nothing hides); -1 for the others.
  std::vector<double> place_visible_fraction;
  std::vector<RawDetection> detections;
  /// Per detection: object index; -1 a one-off false positive; -2 - k the persistent phantom k.
  std::vector<int> detection_truth;
  std::vector<int> swapped;  ///< objects reported with a look-alike's class in this frame
};

/// A persistent phantom of a sequence: a false object at a fixed place in the world.
struct PhantomObject {
  int host = 0;            ///< the real object it sits beside
  std::string class_name;  ///< the class it is reported as
  Eigen::Isometry3d T_world_obj = Eigen::Isometry3d::Identity();
};

/// Writes deterministic procedural textures for the table (wood-like grain) and the floor
/// (speckled tiles) as PNG files into `dir` (created) and returns their paths (table, floor);
/// empty paths and `error` set on failure. Scenes rendered with them have texture everywhere a
/// real room has, which feature-based visual odometry needs.
std::pair<std::string, std::string> writeBackgroundTextures(const std::string& dir,
                                                            std::string* error);

/// Renders frames of a scene and makes their detections. Holds the renderer and the uploaded
/// meshes (textured) of the scene, the table and the floor.
class SequenceRenderer {
 public:
  /// `background_textures`: textures for the table top and the floor (writeBackgroundTextures);
  /// default: plain colours.
  SequenceRenderer(const ClutterScene& scene, const PinholeIntrinsics& K,
                   const std::pair<std::string, std::string>& background_textures = {});
  bool ok() const { return renderer_.ok(); }
  const PinholeIntrinsics& intrinsics() const { return K_; }

  /// Camera frame `frame` (which objects are there, SceneObject::presentAt).
  SequenceFrame render(const FramePose& pose, const DepthNoise& depth_noise,
                       const DetectorModel& detector, const ModelSet& models, std::mt19937& rng,
                       int frame = 0);

  /// The sequence's persistent phantoms (none before the first frame, or for a detector without
  /// them); detection_truth -2 - k refers to entry k.
  std::vector<PhantomObject> phantoms(const ModelSet& models) const;

 private:
  struct Draws;
  /// The objects there at camera frame `frame` (SceneObject::presentAt).
  std::vector<RenderItem> sceneItems(const Eigen::Isometry3d& T_cam_map, int frame) const;
  std::vector<PixelBox> measureVisibility(const std::vector<RenderItem>& items,
                                          const Eigen::Isometry3d& T_cam_map, int frame_index,
                                          SequenceFrame* frame);
  void stepPersistentErrors(const DetectorModel& detector, const ModelSet& models,
                            std::mt19937& rng);
  void detectObjects(const Eigen::Isometry3d& T_cam_map, const std::vector<PixelBox>& boxes,
                     const DetectorModel& detector, const ModelSet& models, Draws* draws,
                     SequenceFrame* frame) const;
  PhantomObject phantomOf(const PersistentErrors::Phantom& p, const ModelSet& models) const;
  void addPhantoms(const Eigen::Isometry3d& T_cam_map, const std::vector<PixelBox>& boxes,
                   const DetectorModel& detector, const ModelSet& models, Draws* draws,
                   SequenceFrame* frame) const;
  void addFalsePositives(const FramePose& pose, const std::vector<PixelBox>& boxes,
                         const DetectorModel& detector, const ModelSet& models, Draws* draws,
                         SequenceFrame* frame) const;

  const ClutterScene& scene_;
  PinholeIntrinsics K_;
  std::unique_ptr<PersistentErrors> errors_;  ///< the detector's persistent errors, per sequence
  OffscreenRenderer renderer_;
  std::vector<MeshHandle> object_meshes_;
  MeshHandle table_mesh_ = -1, floor_mesh_ = -1;
};

}  // namespace geofusion
