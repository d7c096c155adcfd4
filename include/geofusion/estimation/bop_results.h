// The map as BOP results (issue 51): the format the BOP toolkit scores (bop_toolkit's
// inout.load_bop_results, docs/results.md): one CSV row per keyframe and map object the
// keyframe's camera sees (its projected box is in the image: common/image_box.h, the rule the
// evaluation uses), scene_id,im_id,obj_id,score,R,t,time with R row-major, t in mm, the
// pose in the keyframe's camera frame and in BOP's model frame (ObjectModel::bop_origin), time
// the keyframe's processing time in seconds (the same on every row of an image, as BOP asks).
// FbF's rows are the per-frame detections; a mapping method's are its map at each keyframe.
#pragma once

#include "geofusion/common/camera.h"
#include "geofusion/estimation/run_results.h"

#include <map>
#include <string>
#include <vector>

namespace geofusion {

/// BOP's identifiers of one recording: its scene id, each keyframe's image id (default: the
/// keyframe index) and each class's object id (default: the class id; the YCB-Video model set's
/// ids are BOP's ycbv obj_ids).
struct BopIds {
  int scene_id = 0;
  std::map<int, int> image_of_keyframe;
  std::map<std::string, int> object_of_class;
  int imageOf(int keyframe) const;
  int objectOf(const ObjectModel& model) const;
};

/// One image of BOP results: BOP's image id is ids.imageOf(keyframe); the camera pose in the map,
/// the image's processing time in seconds (-1: not known, as the toolkit reads it) and the map
/// objects estimated for it.
struct BopImage {
  int keyframe = 0;
  Eigen::Isometry3d T_map_cam = Eigen::Isometry3d::Identity();
  double time_s = -1.0;
  const std::vector<ObjectEstimate>* objects = nullptr;
};

/// Each keyframe's map as it was made (what run_offline, the Python API and the benchmark
/// write): the causal estimates, timed.
std::vector<BopImage> keyframeMapImages(const RunResults& results);

/// The final map seen from every keyframe's final camera pose (`trajectory`; what the node's
/// ~save_bop_results writes: a live node keeps no keyframe's map): time -1.
std::vector<BopImage> finalMapImages(const RunResults& results);

/// The rows of `images` as BOP's CSV text, with its header line.
std::string bopResultsCsv(const std::vector<BopImage>& images, const PinholeIntrinsics& K,
                          const BopIds& ids);

/// Writes bopResultsCsv atomically to `path`.
bool writeBopResults(const std::string& path, const std::vector<BopImage>& images,
                     const PinholeIntrinsics& K, const BopIds& ids, std::string* error);

}  // namespace geofusion
