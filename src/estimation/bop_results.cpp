#include "geofusion/estimation/bop_results.h"

#include "geofusion/common/atomic_file.h"

#include <cstdio>
#include <fstream>
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

bool cameraSees(const Eigen::Isometry3d& T_cam_obj, const PinholeIntrinsics& K) {
  const Eigen::Vector3d p = T_cam_obj.translation();
  if (!p.allFinite() || !(p.z() > 0.01)) return false;
  const Eigen::Vector2d uv = K.project(p);
  return uv.x() >= 0.0 && uv.y() >= 0.0 && uv.x() < K.width && uv.y() < K.height;
}

std::string bopResultsCsv(const RunResults& results, const PinholeIntrinsics& K,
                          const BopIds& ids) {
  std::ostringstream out;
  out << "scene_id,im_id,obj_id,score,R,t,time\n";
  char buffer[512];
  for (const KeyframeResult& k : results.keyframes) {
    const Eigen::Isometry3d T_cam_map = k.T_map_cam.inverse();
    const double time_s = k.timings.total_ms / 1000.0;
    for (const ObjectEstimate& o : k.objects) {
      if (!o.model) continue;
      Eigen::Isometry3d T = T_cam_map * o.T_map_obj;
      if (!T.matrix().allFinite() || !cameraSees(T, K)) continue;
      T = T * Eigen::Translation3d(o.model->bop_origin);
      const Eigen::Matrix3d& R = T.linear();
      const Eigen::Vector3d t = 1000.0 * T.translation();
      std::snprintf(buffer, sizeof(buffer),
                    "%d,%d,%d,%.6f,%.9f %.9f %.9f %.9f %.9f %.9f %.9f %.9f %.9f,%.4f %.4f %.4f,"
                    "%.6f\n",
                    ids.scene_id, ids.imageOf(k.keyframe), ids.objectOf(*o.model), o.existence,
                    R(0, 0), R(0, 1), R(0, 2), R(1, 0), R(1, 1), R(1, 2), R(2, 0), R(2, 1), R(2, 2),
                    t.x(), t.y(), t.z(), time_s);
      out << buffer;
    }
  }
  return out.str();
}

bool writeBopResults(const std::string& path, const RunResults& results, const PinholeIntrinsics& K,
                     const BopIds& ids, std::string* error) {
  const std::string text = bopResultsCsv(results, K, ids);
  return writeFileAtomically(
      path,
      [&text](const std::string& tmp) {
        std::ofstream f(tmp);
        f << text;
        return static_cast<bool>(f.flush());
      },
      error);
}

}  // namespace geofusion
