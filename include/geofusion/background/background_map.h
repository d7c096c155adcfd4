// The static background as an OctoMap (liboctomap): each keyframe's depth, sampled every
// pixel_stride-th row and column, minus the samples the map's objects cover (rendered with the
// OSMesa renderer at the samples' resolution, grown by a margin), is inserted by octomap's
// discretised ray casting from the camera. The objects never enter it; the table and everything
// else do. BackgroundWorker (background_worker.h) runs it beside the estimator.
#pragma once

#include "geofusion/common/camera.h"
#include "geofusion/model/object_model.h"
#include "geofusion/render/consistency.h"

#include <Eigen/Geometry>

#include <memory>
#include <string>
#include <vector>

namespace geofusion {

class OffscreenRenderer;

struct BackgroundMapConfig {
  double resolution_m = 0.02;     ///< voxel edge
  double max_range_m = 2.5;       ///< rays are cut here
  int pixel_stride = 4;           ///< use every n-th row and column
  int object_margin_px = 4;       ///< object masks grow by this many pixels
  double object_margin_m = 0.02;  ///< ... and points this close behind an object are left out
  /// > 0: only the square of this half extent about the map origin (x and y, every height) is
  /// mapped (OctoMap's bounding box limit), so the map's memory is bounded by the region however
  /// long the robot drives; 0: unbounded.
  double region_half_extent_m = 0.0;
  /// A keyframe whose camera moved less than min_translation_m and turned less than
  /// min_rotation_deg since the last inserted one adds little the map does not have: it is
  /// passed over (wanted() false), except that at least every max_interval_keyframes-th
  /// keyframe goes in (changes in a scene watched from one place still reach the map).
  double min_translation_m = 0.03;
  double min_rotation_deg = 3.0;
  int max_interval_keyframes = 5;
  /// Free space is cleared along the rays to every free_space_stride-th sample (in each
  /// direction; 1: every sample): the rays converge on the camera, so fewer of them clear
  /// nearly the same voxels. Every sample still marks its voxel occupied. The rays' phase steps
  /// with each insertion, so that over f x f insertions every sampled direction clears once.
  int free_space_stride = 2;
  /// The object masks render each model simplified to about this many triangles (deviation at
  /// most a quarter voxel).
  int mask_mesh_triangles = 1000;
  /// The node inserts keyframes in a thread of its own (BackgroundWorker): the object map never
  /// waits for the background, and a keyframe arriving while one is still being inserted
  /// replaces the one waiting (counted as skipped). false: inserted in the estimator's thread.
  /// The offline runner inserts every keyframe, in order, either way.
  bool threaded = true;
};

/// An object of the map to keep out of the background.
struct MaskObject {
  std::shared_ptr<const ObjectModel> model;
  Eigen::Isometry3d T_map_obj = Eigen::Isometry3d::Identity();
};

class BackgroundMap {
 public:
  explicit BackgroundMap(const BackgroundMapConfig& config = {},
                         std::shared_ptr<OffscreenRenderer> renderer = nullptr);
  ~BackgroundMap();

  /// Uploads every model's mask mesh now, so that no keyframe waits for it.
  void prepare(const ModelSet& models);
  /// Whether a keyframe seen from here is worth inserting (min_translation_m, min_rotation_deg,
  /// max_interval_keyframes); counts it as passed over when not. insert() itself never skips.
  bool wanted(const Eigen::Isometry3d& T_map_cam);
  /// Inserts a keyframe. Returns the number of depth points inserted (after masking).
  int insert(const DepthImageView& depth, const PinholeIntrinsics& K,
             const Eigen::Isometry3d& T_map_cam, const std::vector<MaskObject>& objects);
  /// Centres of the occupied leaf voxels, map frame.
  std::vector<Eigen::Vector3d> occupiedCentres() const;
  /// The same at the finest resolution (a pruned leaf gives each of its voxels).
  std::vector<Eigen::Vector3d> occupiedVoxels() const;
  bool isOccupied(const Eigen::Vector3d& p) const;  ///< false for free or unknown
  std::size_t numLeaves() const;
  /// Writes the tree as an OctoMap binary file (.bt), through a temporary file and a rename.
  bool writeBinary(const std::string& path, std::string* error) const;
  /// Replaces the tree with an OctoMap binary file's (.bt of writeBinary). Fails, leaving the
  /// tree as it was, when the file cannot be read or its resolution is not config().resolution_m.
  bool readBinary(const std::string& path, std::string* error);
  /// The tree's binary (free/occupied) serialisation without the file header, as
  /// octomap::OcTree::writeBinaryData writes it: what an octomap_msgs/Octomap carries in `data`
  /// (with binary = true and id = "OcTree").
  std::string binaryData() const;
  void clear();
  /// Removes the voxels inside the objects' boxes (plus object_margin_m); insert() does it.
  void carve(const std::vector<MaskObject>& objects);
  const BackgroundMapConfig& config() const { return config_; }

 private:
  struct Impl;
  int meshFor(const std::shared_ptr<const ObjectModel>& model);  ///< MeshHandle, -1: none
  void castRays(const Eigen::Vector3d& origin, const std::vector<Eigen::Vector3d>& points,
                const std::vector<char>& casts);
  BackgroundMapConfig config_;
  std::unique_ptr<Impl> impl_;
};

/// Occupied-voxel agreement of two maps at the finest resolution (the background benchmark's
/// quality figure): voxels occupied in each, in both, and their intersection over union.
struct OccupiedAgreement {
  std::size_t a = 0, b = 0, both = 0;
  double iou() const { return a + b > both ? double(both) / double(a + b - both) : 1.0; }
  double ofA() const { return a ? double(both) / a : 1.0; }  ///< share of a's voxels also in b
  double ofB() const { return b ? double(both) / b : 1.0; }
};
OccupiedAgreement compareOccupied(const BackgroundMap& a, const BackgroundMap& b);

}  // namespace geofusion
