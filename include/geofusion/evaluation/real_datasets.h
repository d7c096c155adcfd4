// Readers of real RGB-D datasets, for the importer (src/tools/import_dataset.cpp), the real-data
// tests and the real-data benchmark (docs/dataset.md, "Real recordings"):
// - BOP scenes (scene_camera.json, scene_gt.json, optional scene_gt_info.json, rgb/ and depth/),
//   and the YCB-Video folder layout (NNNNNN-color.png, NNNNNN-depth.png, NNNNNN-label.png) with
//   the same two JSON files;
// - 7-Scenes sequences (frame-NNNNNN.color.{png,jpg}, .depth.png, .pose.txt,
//   camera-intrinsics.txt);
// - TUM RGB-D sequences (rgb.txt, depth.txt, groundtruth.txt).
// Images are read with OpenCV, JSON with nlohmann-json. Offline only (evaluation module).
#pragma once

#include "geofusion/common/camera.h"
#include "geofusion/common/measurement.h"

#include <Eigen/Geometry>

#include <cstdint>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <vector>

namespace geofusion {

class ModelSet;
class ObjectModel;
class OffscreenRenderer;

/// One ground-truth object of a frame (BOP scenes).
struct RealObjectTruth {
  int obj_id = 0;  ///< the dataset's object id (BOP obj_id; YCB-Video: the class index)
  Eigen::Isometry3d T_cam_obj = Eigen::Isometry3d::Identity();
  int visible_pixels = -1;         ///< -1: unknown (no visibility information in the folder)
  double visible_fraction = -1.0;  ///< visible pixels / pixels it would cover alone; -1 unknown
  PixelBox visible_box;            ///< box of its visible pixels
};

struct RealFrame {
  int index = 0;         ///< position in the sequence
  std::string name;      ///< the dataset's frame name (BOP im_id, 7-Scenes number, TUM stamp)
  double stamp_s = 0.0;  ///< seconds from the sequence's start (TUM: its own stamps)
  std::string rgb_path, depth_path;
  std::string label_path;  ///< YCB-Video per-pixel class index image; empty when none
  PinholeIntrinsics K;
  double depth_unit_m = 0.001;      ///< metres per depth-image unit
  std::uint16_t depth_invalid = 0;  ///< a value besides 0 that means "no reading" (0: none)
  bool has_camera_pose = false;     ///< the dataset gives the camera's pose
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();
  std::vector<RealObjectTruth> objects;
};

/// A sequence of one of these formats is hand-held: no robot base, no wheel odometry; its camera
/// poses (when given) are the truth.
struct RealSequence {
  std::string format;  ///< "bop", "ycbv" (BOP files, YCB-Video names), "7scenes", "tum"
  std::string name;    ///< the folder's name
  std::string dir;
  std::vector<RealFrame> frames;
};

/// `format`: auto (from the files present), bop, 7scenes or tum. `fps` gives BOP frames their
/// stamps (im_id / fps). False with `error` on a missing or malformed file, an image listed but
/// absent, or a folder with no frame.
bool readRealSequence(const std::string& dir, const std::string& format, double fps,
                      RealSequence* sequence, std::string* error);
bool readBopScene(const std::string& dir, double fps, RealSequence* sequence, std::string* error);
bool readSevenScenes(const std::string& dir, RealSequence* sequence, std::string* error);
bool readTumRgbd(const std::string& dir, RealSequence* sequence, std::string* error);

/// Depth in metres (0 = no reading), row-major.
bool loadDepthMetres(const RealFrame& frame, std::vector<float>* depth, int* width, int* height,
                     std::string* error);
/// Colour as rgb8, row-major, 3 bytes a pixel.
bool loadRgb(const RealFrame& frame, std::vector<std::uint8_t>* rgb, int* width, int* height,
             std::string* error);
/// Grey (8 bit) from the colour image, for the visual odometry.
bool loadGray(const RealFrame& frame, std::vector<std::uint8_t>* gray, int* width, int* height,
              std::string* error);
/// Visible pixels and boxes of the frame's objects from its YCB-Video label image (each class
/// once a frame); objects whose class has no pixel get 0. False without a label image.
bool loadLabelVisibility(RealFrame* frame, std::string* error);

/// How much of each ground-truth object a frame shows, by rendering the frame's objects at their
/// true poses (OSMesa): the pixels each covers alone and in the scene. Fills visible_fraction
/// (visible / alone, at most 1) and, for objects whose visible pixels are unknown (no label image,
/// no scene_gt_info.json), the visible pixels and box of the render. Objects of ids the model set
/// does not have are left as they are.
class TruthVisibility {
 public:
  TruthVisibility(const ModelSet& models, std::shared_ptr<OffscreenRenderer> renderer);
  bool measure(RealFrame* frame, std::string* error);

 private:
  int meshOf(const ObjectModel* model);
  const ModelSet& models_;
  std::shared_ptr<OffscreenRenderer> renderer_;
  std::map<const ObjectModel*, int> meshes_;
};

/// What a depth camera does to the true depth, measured against a clean depth image (the depth
/// rendered at the ground truth on object pixels, docs/dataset.md "Sensor models"): the sensor
/// model's calibration against real frames compares these figures.
struct DepthStatistics {
  std::vector<double> bin_upper_m;            ///< object pixels by true depth, bins [.., upper)
  std::vector<double> median_abs_residual_m;  ///< per bin, readings only (NaN: empty bin)
  std::vector<long> bin_pixels;
  double object_invalid = 0.0;  ///< object pixels more than 3 px from an edge with no reading
  double edge_invalid = 0.0;    ///< pixels within 3 px of a depth edge with no reading
  /// Width of the error band at edges: over the distances d = 0..10 px from an edge, the sum of
  /// the shares of readings off by more than 1 cm (px).
  double edge_band_px = 0.0;
  /// Background pixels 1-6 px left / right of an object with no reading (the emitter's shadow
  /// falls on one side).
  double left_of_objects_invalid = 0.0, right_of_objects_invalid = 0.0;
};

class DepthStatisticsAccumulator {
 public:
  explicit DepthStatisticsAccumulator(std::vector<double> bin_upper_m = {0.7, 1.0, 1.3});
  /// One frame: `observed` and `clean` depth (metres, 0 = none), `instance` per pixel (0 =
  /// background, else an object).
  void add(const PinholeIntrinsics& K, const std::vector<float>& observed,
           const std::vector<float>& clean, const std::vector<std::uint16_t>& instance);
  DepthStatistics result() const;

 private:
  std::vector<double> bin_upper_m_;
  std::vector<std::vector<float>> residuals_;  ///< per bin
  long object_pixels_ = 0, object_holes_ = 0, edge_pixels_ = 0, edge_holes_ = 0;
  long left_ = 0, left_holes_ = 0, right_ = 0, right_holes_ = 0;
  std::vector<long> band_readings_ = std::vector<long>(11, 0), band_bad_ = std::vector<long>(11, 0);
};

/// The clean depth of a real frame: `rendered` (the ground truth's objects) where `instance` is
/// an object, else the real depth with its holes filled along each row from the background beside
/// them (never across an object).
std::vector<float> cleanDepthOf(const PinholeIntrinsics& K, const std::vector<float>& real,
                                const std::vector<float>& rendered,
                                const std::vector<std::uint16_t>& instance);

/// One row of a BOP-challenge results file (scene_id,im_id,obj_id,score,R,t,time).
struct BopEstimate {
  int scene_id = 0, im_id = 0, obj_id = 0;
  double score = 0.0;
  Eigen::Isometry3d T_cam_obj = Eigen::Isometry3d::Identity();  ///< metres
  double time_s = -1.0;
};
/// Reads a results CSV (a header line "scene_id,im_id,..." is skipped; R row-major, t in mm,
/// space-separated inside their fields). False with the line number on a malformed row.
bool readBopEstimates(const std::string& path, std::vector<BopEstimate>* estimates,
                      std::string* error);

/// Class names indexed by the model set's class ids (YCB-Video's: the dataset's class index, BOP's
/// obj_id); "" for ids without a class.
std::vector<std::string> classNamesById(const ModelSet& models);

/// Detections made from the ground truth, with the error of a colour-only 6D estimator: per
/// object a bias along the viewing ray drawn once (magnitude uniform in [min, max], either sign,
/// it persists: the same object seen again is wrong the same way), then per frame Gaussian noise
/// on the translation (per axis) and rotation (per axis). All zero: the ground truth itself.
struct TruthDetectorModel {
  double ray_bias_min_m = 0.0;
  double ray_bias_max_m = 0.0;
  double translation_sigma_m = 0.0;
  double rotation_sigma_rad = 0.0;
  double score = 0.9;
  unsigned seed = 1;
};

class TruthDetector {
 public:
  explicit TruthDetector(const TruthDetectorModel& model);
  /// The frame's objects as detections (class names from `class_names[obj_id]`; objects whose
  /// id has no name are left out). Visible objects only when visibility is known (at least
  /// `min_visible_pixels`).
  std::vector<ObjectMeasurement> detect(const RealFrame& frame,
                                        const std::vector<std::string>& class_names,
                                        int min_visible_pixels = 1);
  /// The along-ray bias of an object (0 before it was first detected).
  double rayBias(int obj_id) const;

 private:
  TruthDetectorModel model_;
  std::mt19937 rng_;
  std::vector<std::pair<int, double>> bias_;  ///< obj_id, signed bias along the ray (m)
};

/// Signed error of `estimate` along the viewing ray of `truth` (positive: farther than the truth).
double alongRayError(const Eigen::Isometry3d& estimate, const Eigen::Isometry3d& truth);

}  // namespace geofusion
