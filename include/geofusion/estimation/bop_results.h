// The map as BOP results (issue 51): the format the BOP toolkit scores (bop_toolkit's
// inout.load_bop_results, docs/results.md): one CSV row per keyframe and map object the
// keyframe's camera sees, scene_id,im_id,obj_id,score,R,t,time with R row-major, t in mm, the
// pose in the keyframe's camera frame and in BOP's model frame (ObjectModel::bop_origin), time
// the keyframe's processing time in seconds (the same on every row of an image, as BOP asks).
// FbF's rows are the per-frame detections; a mapping method's are its map at each keyframe.
#pragma once

#include "geofusion/common/camera.h"
#include "geofusion/estimation/run_results.h"

#include <map>
#include <string>

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

/// Whether the camera sees a map object: its origin in front (more than 1 cm) and projecting
/// inside the image.
bool cameraSees(const Eigen::Isometry3d& T_cam_obj, const PinholeIntrinsics& K);

/// The rows of `results` as BOP's CSV text, with its header line.
std::string bopResultsCsv(const RunResults& results, const PinholeIntrinsics& K, const BopIds& ids);

/// Writes bopResultsCsv atomically to `path`.
bool writeBopResults(const std::string& path, const RunResults& results, const PinholeIntrinsics& K,
                     const BopIds& ids, std::string* error);

}  // namespace geofusion
