// The static background as an OctoMap (liboctomap): each keyframe's depth, minus the pixels the
// map's objects cover (rendered with the OSMesa renderer, dilated by a margin), is inserted by
// ray casting from the camera. The objects never enter it; the table and everything else do.
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

  /// Inserts a keyframe. Returns the number of depth points inserted (after masking).
  int insert(const DepthImageView& depth, const PinholeIntrinsics& K,
             const Eigen::Isometry3d& T_map_cam, const std::vector<MaskObject>& objects);
  /// Centres of the occupied leaf voxels, map frame.
  std::vector<Eigen::Vector3d> occupiedCentres() const;
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
  BackgroundMapConfig config_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace geofusion
