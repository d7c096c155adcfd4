// Named data suites (demo, bench) and the ground-truth file written beside each recording.
// (The calibration check of a suite's noisy inputs is evaluation/sequence_calibration.h.) ROS-free;
// the generate_dataset tool writes the recordings (docs/dataset.md documents the file formats).
#pragma once

#include "geofusion/common/lens.h"
#include "geofusion/common/robot_names.h"
#include "geofusion/simulation/clutter_scene.h"
#include "geofusion/simulation/colour_camera.h"
#include "geofusion/simulation/sequence.h"

#include <map>
#include <string>
#include <vector>

namespace geofusion {

struct SceneSpec {
  std::string name;  ///< file stem, e.g. "bench_01"
  unsigned seed = 1;
  int num_objects = 12;
  /// A changed scene (issue 20): at camera frame change_at x frames, `removed` objects are taken
  /// away and `moved` ones set down elsewhere on the table (applySceneChanges).
  int removed = 0;
  int moved = 0;
  double change_at = 0.5;
  /// What makes the changes, for the cache key ("" for a static scene).
  std::string describeChanges() const;
};

/// Everything that makes a suite; deterministic for the scene seeds.
struct SuiteSpec {
  std::string name;
  /// "primitives" (built in) or "ycb_video" (config/models/ycb_video.yaml, meshes from a folder).
  std::string model_set = "primitives";
  std::vector<SceneSpec> scenes;
  ClutterConfig clutter;
  double camera_rate_hz = 30.0;  ///< TF and odometry at this rate
  int keyframes = 200;           ///< frames with images and detections
  int image_every = 6;           ///< images every Nth camera frame (1: all, at 30 Hz)
  TrajectoryConfig trajectory;   ///< frames and rate_hz are derived from the three above
  OdometryNoise odometry;
  DepthNoise depth;
  DetectorModel detector;
  std::string detector_name = "densefusion";  ///< its preset (DetectorModel::byName)
  double stamp_origin_s = 1600000000.0;       ///< ROS time of the first frame
  /// Table and floor textured (writeBackgroundTextures) instead of plain colours.
  bool textured_background = false;
  ColourNoise
      colour;  ///< the colour camera's blur, rolling shutter, exposure and noise (vo suites)
  /// The lens: the images are distorted by it and camera_info's D says so (bench suites).
  LensDistortion lens;

  int cameraFrames() const { return (keyframes - 1) * image_every + 1; }
  bool isKeyframe(int frame) const { return image_every > 0 && frame % image_every == 0; }
};

/// Bumped whenever the generator's output for the same request changes (cached scenes made by
/// another version are remade). v5: the true contacts' types with eps_n_pp 6 degrees (a face
/// 6-14 degrees off is a plane-edge contact).
constexpr int kGeneratorVersion = 5;

/// Every setting of a suite that shapes its data, one line (the cache key of generated scenes).
std::string describeSuite(const SuiteSpec& suite);

/// The suites the package knows: "demo" (one small scene, built-in primitives, seconds to make)
/// and "bench" (6 scenes of about 18 YCB-Video objects, 200 keyframes each). False for others.
bool suiteByName(const std::string& name, SuiteSpec* suite);
std::vector<std::string> suiteNames();

/// The settled clutter scene of a suite's scene spec. A seed whose scene fails the penetration
/// bound is followed by derived seeds (deterministically) until one settles; `used_seed` receives
/// it. False with `report` when none of `attempts` settles.
bool makeSuiteScene(const SuiteSpec& suite, const SceneSpec& spec, const ModelSet& models,
                    ClutterScene* scene, unsigned* used_seed, std::string* report,
                    int attempts = 8);

/// Ground truth of one recording.
struct GroundTruthFrame {
  int index = 0;         ///< camera frame number
  double stamp_s = 0.0;  ///< ROS time, seconds
  bool keyframe = false;
  Eigen::Isometry3d T_map_base = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_odom_base = Eigen::Isometry3d::Identity();    ///< as recorded
  Eigen::Isometry3d T_base_link = Eigen::Isometry3d::Identity();    ///< base -> camera link
  Eigen::Isometry3d T_map_optical = Eigen::Isometry3d::Identity();  ///< camera
  std::vector<double> visible_fraction;                             ///< keyframes, per object
  std::vector<int> visible_pixels;                                  ///< keyframes, per object
  std::vector<PixelBox> visible_boxes;  ///< keyframes, per object: box of its visible pixels
  /// Keyframes, per object taken away: the share of its old place the camera sees (nothing
  /// hides it); -1 for the others; empty in files before issue 32 (changed scenes only).
  std::vector<double> place_visible_fraction;
  /// Keyframes, per detection: object index; -1 a one-off false positive, -2 - k phantom k.
  std::vector<int> detection_truth;
  std::vector<int> swapped;  ///< keyframes: objects reported as a look-alike class
};

struct GroundTruth {
  std::string suite;
  std::string scene_name;
  unsigned seed = 0;        ///< the scene spec's seed
  unsigned scene_seed = 0;  ///< the seed the clutter scene settled with (makeSuiteScene)
  std::string model_set;    ///< name of the model set the classes come from
  std::string detector;     ///< detector preset
  /// "robot" (a base with wheel odometry, the generated suites) or "hand_held" (an imported real
  /// sequence: no base, the camera is its own base frame).
  std::string platform = "robot";
  /// What the recording's odometry is: "wheel" (drifting wheel odometry on /odom and /tf),
  /// "camera_trajectory" (hand-held: the dataset's camera poses on /tf as odom -> camera, i.e.
  /// the truth) or "none" (no pose at all: run with the visual odometry).
  std::string odometry = "wheel";
  PinholeIntrinsics intrinsics;
  std::string map_frame = kMapFrame, odom_frame = kOdomFrame, base_frame = kBaseFrame,
              camera_link_frame = kCameraLinkFrame, camera_frame = kOpticalFrame;
  ClutterScene scene;                   ///< table, objects (map frame), contact graph
  std::vector<PhantomObject> phantoms;  ///< the detector's persistent false objects
  std::vector<GroundTruthFrame> frames;
};

/// Applies the spec's changes to a settled scene whose sequence has `frames` camera frames: objects
/// nothing rests or leans on are taken away (present until the change); objects that stand on
/// the table alone are moved (the original until the change, a copy at a free spot of the table
/// from it). The contact graph is made again. False (with `report`) when too few objects qualify
/// or no free spot is found; nothing to do for a static spec.
bool applySceneChanges(const SceneSpec& spec, int frames, const ClutterConfig& clutter,
                       ClutterScene* scene, std::string* report);

/// Writes the ground-truth YAML atomically (temporary file, then rename).
bool writeGroundTruth(const std::string& path, const GroundTruth& gt, std::string* error);
/// Reads it back; object classes are looked up in `models` (unknown classes fail).
bool readGroundTruth(const std::string& path, const ModelSet& models, GroundTruth* gt,
                     std::string* error);

/// Writes PNGs of a frame for looking at: <prefix>_rgb.png, <prefix>_depth.png (colour map over
/// 0.4-2.5 m, holes black) and <prefix>_detections.png (RGB with detection boxes and labels,
/// green true, red false positive).
bool writeFramePreview(const std::string& prefix, const PinholeIntrinsics& K,
                       const SequenceFrame& frame, std::string* error);

}  // namespace geofusion
