#include "geofusion/estimation/bop_results.h"

#include "geofusion/common/atomic_file.h"
#include "geofusion/common/image_box.h"

#include <cstdio>
#include <sstream>

namespace geofusion {

int BopIds::imageOf(int keyframe) const {
  const auto it = image_of_keyframe.find(keyframe);
  return it == image_of_keyframe.end() ? keyframe : it->second;
}

int BopIds::objectOf(const ObjectModel& model) const {
  const auto it = object_of_class.find(model.name);
  return it == object_of_class.end() ? model.id : it->second;
}

std::vector<BopImage> keyframeMapImages(const RunResults& results) {
  std::vector<BopImage> images;
  for (const KeyframeResult& k : results.keyframes)
    images.push_back({k.keyframe, k.T_map_cam, k.timings.total_ms / 1000.0, &k.objects});
  return images;
}

std::vector<BopImage> finalMapImages(const RunResults& results) {
  std::vector<BopImage> images;
  for (std::size_t i = 0; i < results.trajectory.size(); ++i)
    images.push_back(
        {static_cast<int>(i), results.trajectory[i], -1.0, &results.final_map.objects});
  return images;
}

std::string bopResultsCsv(const std::vector<BopImage>& images, const PinholeIntrinsics& K,
                          const BopIds& ids) {
  std::ostringstream out;
  out << "scene_id,im_id,obj_id,score,R,t,time\n";
  char buffer[512];
  for (const BopImage& image : images) {
    if (!image.objects || !image.T_map_cam.matrix().allFinite()) continue;
    const Eigen::Isometry3d T_cam_map = image.T_map_cam.inverse();
    for (const ObjectEstimate& o : *image.objects) {
      if (!o.model) continue;
      Eigen::Isometry3d T = T_cam_map * o.T_map_obj;
      if (!T.matrix().allFinite() || projectedBox(o.model->points, T, K).empty()) continue;
      T = T * Eigen::Translation3d(o.model->bop_origin);
      const Eigen::Matrix3d& R = T.linear();
      const Eigen::Vector3d t = 1000.0 * T.translation();
      std::snprintf(buffer, sizeof(buffer),
                    "%d,%d,%d,%.6f,%.9f %.9f %.9f %.9f %.9f %.9f %.9f %.9f %.9f,%.4f %.4f %.4f,"
                    "%.6f\n",
                    ids.scene_id, ids.imageOf(image.keyframe), ids.objectOf(*o.model), o.existence,
                    R(0, 0), R(0, 1), R(0, 2), R(1, 0), R(1, 1), R(1, 2), R(2, 0), R(2, 1), R(2, 2),
                    t.x(), t.y(), t.z(), image.time_s);
      out << buffer;
    }
  }
  return out.str();
}

bool writeBopResults(const std::string& path, const std::vector<BopImage>& images,
                     const PinholeIntrinsics& K, const BopIds& ids, std::string* error) {
  return writeTextAtomically(path, bopResultsCsv(images, K, ids), error);
}

}  // namespace geofusion
