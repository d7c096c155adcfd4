#include "geofusion/evaluation/evaluation.h"

#include "geofusion/estimation/frame_by_frame.h"
#include "geofusion/evaluation/metrics.h"

namespace geofusion {

Keyframe makeKeyframe(const FramePose& pose, const SequenceFrame& frame,
                      const PinholeIntrinsics& K) {
  Keyframe kf;
  kf.stamp_s = pose.stamp_s;
  kf.K = K;
  kf.T_odom_cam = pose.T_odom_base * pose.T_base_link * RobotGeometry::cameraLinkToOptical();
  if (frame.images.depth.size() == static_cast<std::size_t>(K.width) * K.height) {
    kf.depth = DepthImageView{frame.images.depth.data(), K.width, K.height};
  }
  const FrameByFrame checker;
  for (const RawDetection& raw : frame.detections) {
    ObjectMeasurement m;
    SkipReason why;
    if (checker.check(raw, &m, &why)) kf.detections.push_back(m);
  }
  return kf;
}

MapScore scoreMap(const ClutterScene& scene, const std::vector<ObjectEstimate>& objects,
                  double max_adds_m) {
  MapScore sc;
  std::vector<bool> taken(scene.objects.size(), false);
  for (const ObjectEstimate& o : objects) {
    ++sc.objects;
    double best = 1e9;
    int best_i = -1;
    for (std::size_t i = 0; i < scene.objects.size(); ++i) {
      if (taken[i] || !o.model || !scene.objects[i].presentAtTheEnd() ||
          scene.objects[i].model->name != o.model->name)
        continue;
      const double e = addsError(o.model->points, o.T_map_obj, scene.objects[i].T_world_obj);
      if (e < best) best = e, best_i = static_cast<int>(i);
    }
    if (best_i >= 0 && best < max_adds_m) {
      taken[static_cast<std::size_t>(best_i)] = true;
      sc.match.push_back(best_i);
      ++sc.true_positives;
      sc.adds_m.push_back(best);
      sc.mean_adds_m += best;
    } else {
      ++sc.false_positives;
      sc.match.push_back(-1);
    }
  }
  if (sc.true_positives) sc.mean_adds_m /= sc.true_positives;
  return sc;
}

int objectsDetectedInFrames(const ClutterScene& scene, const std::vector<SequenceFrame>& frames,
                            int min_frames) {
  int n = 0;
  for (std::size_t i = 0; i < scene.objects.size(); ++i) {
    int seen = 0;
    for (const auto& f : frames) {
      for (std::size_t d = 0; d < f.detection_truth.size(); ++d) {
        seen += f.detection_truth[d] == static_cast<int>(i) &&
                f.detections[d].class_name == scene.objects[i].model->name;
      }
    }
    n += seen >= min_frames;
  }
  return n;
}

}  // namespace geofusion
