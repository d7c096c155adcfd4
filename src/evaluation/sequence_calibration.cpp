#include "geofusion/evaluation/sequence_calibration.h"

#include "geofusion/evaluation/metrics.h"

#include <cmath>
#include <cstdio>
#include <sstream>

namespace geofusion {

void SequenceCalibration::add(const ClutterScene& scene, const Eigen::Isometry3d& T_map_optical,
                              const SequenceFrame& frame) {
  std::vector<bool> detected(scene.objects.size(), false);
  for (std::size_t k = 0; k < frame.detections.size(); ++k) {
    ++detections_;
    const int truth = frame.detection_truth[k];
    if (truth < 0) {
      ++false_positives_;
      continue;
    }
    const SceneObject& o = scene.objects[static_cast<std::size_t>(truth)];
    const RawDetection& d = frame.detections[k];
    detected[static_cast<std::size_t>(truth)] = true;
    if (d.class_name != o.model->name) {
      ++swaps_;
      continue;
    }
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = d.orientation_cam.normalized().toRotationMatrix();
    T.translation() = d.position_cam;
    const Eigen::Isometry3d T_true = T_map_optical.inverse() * o.T_world_obj;
    adds_[o.model->name].push_back(addsError(o.model->points, T, T_true));
  }
  for (std::size_t i = 0; i < scene.objects.size(); ++i) {
    if (frame.visible_pixels[i] < min_visible_pixels_) continue;
    ++detectable_;
    if (!detected[i]) ++missed_;
  }
  for (std::size_t p = 0; p < frame.clean_depth.size() && p < frame.images.depth.size(); ++p) {
    const float clean = frame.clean_depth[p];
    if (clean <= 0.f || clean > max_depth_m_) continue;
    if (frame.images.depth[p] <= 0.f) {
      ++depth_holes_;
      continue;
    }
    ++depth_valid_;
    depth_sq_sum_ += std::pow(static_cast<double>(frame.images.depth[p]) - clean, 2);
  }
}

double SequenceCalibration::depthNoiseRms() const {
  return depth_valid_ > 0 ? std::sqrt(depth_sq_sum_ / static_cast<double>(depth_valid_)) : 0.0;
}

double SequenceCalibration::holeShare() const {
  const long all = depth_valid_ + depth_holes_;
  return all > 0 ? static_cast<double>(depth_holes_) / static_cast<double>(all) : 0.0;
}

std::map<std::string, SequenceCalibration::ClassStats> SequenceCalibration::perClass() const {
  std::map<std::string, ClassStats> out;
  for (const auto& kv : adds_) {
    ClassStats s;
    s.detections = static_cast<int>(kv.second.size());
    s.auc = accuracyAuc(kv.second);
    s.below_2cm = shareBelow(kv.second, 0.02);
    out[kv.first] = s;
  }
  return out;
}

std::vector<double> SequenceCalibration::errors() const {
  std::vector<double> all;
  for (const auto& kv : adds_) all.insert(all.end(), kv.second.begin(), kv.second.end());
  return all;
}

SequenceCalibration::ClassStats SequenceCalibration::overall() const {
  const std::vector<double> all = errors();
  ClassStats s;
  s.detections = static_cast<int>(all.size());
  s.auc = accuracyAuc(all);
  s.below_2cm = shareBelow(all, 0.02);
  return s;
}

std::string SequenceCalibration::report() const {
  std::ostringstream out;
  char line[200];
  std::snprintf(line, sizeof(line), "  %-24s %6s %9s %8s\n", "class", "dets", "ADD-S AUC",
                "< 2 cm");
  out << line;
  for (const auto& kv : perClass()) {
    std::snprintf(line, sizeof(line), "  %-24s %6d %9.1f %7.1f%%\n", kv.first.c_str(),
                  kv.second.detections, kv.second.auc, 100.0 * kv.second.below_2cm);
    out << line;
  }
  const ClassStats all = overall();
  std::snprintf(line, sizeof(line), "  %-24s %6d %9.1f %7.1f%%\n", "all (true class)",
                all.detections, all.auc, 100.0 * all.below_2cm);
  out << line;
  std::snprintf(line, sizeof(line),
                "  detections %d: false positives %d, class swaps %d; missed %d of %d detectable "
                "objects (%.1f%%)\n",
                detections_, false_positives_, swaps_, missed_, detectable_,
                detectable_ > 0 ? 100.0 * missed_ / detectable_ : 0.0);
  out << line;
  std::snprintf(line, sizeof(line), "  depth noise rms %.2f mm, holes %.1f%% (table top)\n",
                1000.0 * depthNoiseRms(), 100.0 * holeShare());
  out << line;
  return out.str();
}

}  // namespace geofusion
