// A rendered tabletop test scene: a table with objects standing on it, seen by a Carmine-like
// camera 0.8 m away looking down 35 degrees, the observed depth with the benchmark's noise model.
// Shared by the consistency and depth refinement tests.
#pragma once

#include "geofusion/estimation/scene_estimator.h"
#include "geofusion/model/object_model.h"
#include "geofusion/render/consistency.h"
#include "geofusion/render/renderer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <vector>

namespace geofusion {
namespace test {

inline std::shared_ptr<OffscreenRenderer> sharedRenderer() {
  static auto renderer = std::make_shared<OffscreenRenderer>();
  return renderer;
}

inline Eigen::Isometry3d pose(const Eigen::Vector3d& t, double yaw = 0.0) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = t;
  return T;
}

struct PlacedObject {
  std::shared_ptr<const ObjectModel> model;
  Eigen::Isometry3d T_world_obj;
  bool hidden = false;  ///< taken away: not in the observed depth
};

/// A table (top at world z = 0) with objects standing on it, seen by a Carmine-like camera 0.8 m
/// away looking down 35 degrees; observed depth has axial noise growing with depth squared and
/// 1 mm quantisation (see docs on the benchmark's depth model).
class TableScene {
 public:
  explicit TableScene(const ModelSet& models) : models_(models), scorer_(sharedRenderer()) {
    table_.mesh = makeBox(Eigen::Vector3d(1.2, 0.8, 0.04));
    table_handle_ = sharedRenderer()->addMesh(table_.mesh);
    T_world_cam_ = lookAt(Eigen::Vector3d(0.0, -0.66, 0.46), Eigen::Vector3d(0.0, 0.0, 0.06));
  }

  /// A keyframe from the camera with the observed depth, the `detected` objects reported at
  /// their true poses (score 0.9), the odometry reading `T_odom_world` x the true camera.
  Keyframe keyframe(double stamp, const std::vector<int>& detected,
                    const Eigen::Isometry3d& T_odom_world = Eigen::Isometry3d::Identity()) const {
    Keyframe kf;
    kf.stamp_s = stamp;
    kf.T_odom_cam = T_odom_world * T_world_cam_;
    kf.K = K_;
    kf.depth = depth();
    for (int i : detected) {
      ObjectMeasurement m;
      m.class_name = objects_[static_cast<std::size_t>(i)].model->name;
      m.score = 0.9;
      m.T_cam_obj = cameraPose(i);
      kf.detections.push_back(m);
    }
    return kf;
  }

  std::shared_ptr<const ObjectModel> model(const std::string& name) const {
    for (const auto& m : models_.models())
      if (m->name == name) return m;
    ADD_FAILURE() << "no model " << name;
    return nullptr;
  }

  /// Stands `name` upright on the table at (x, y) with the given yaw; returns its index.
  int place(const std::string& name, double x, double y, double yaw = 0.0) {
    auto m = model(name);
    Eigen::Vector3f lo, hi;
    m->mesh.bounds(&lo, &hi);
    objects_.push_back({m, pose(Eigen::Vector3d(x, y, -lo.z()), yaw)});
    return static_cast<int>(objects_.size()) - 1;
  }

  void renderObserved(unsigned seed = 7) {
    std::vector<RenderItem> items;
    RenderItem table;
    table.mesh = table_handle_;
    table.T_cam_model = T_world_cam_.inverse() * pose(Eigen::Vector3d(0, 0.1, -0.02));
    table.instance_id = 1000;
    items.push_back(table);
    for (std::size_t i = 0; i < objects_.size(); ++i) {
      if (objects_[i].hidden) continue;
      RenderItem it;
      it.mesh = handle(objects_[i].model);
      it.T_cam_model = cameraPose(static_cast<int>(i));
      it.instance_id = static_cast<std::uint16_t>(i + 1);
      items.push_back(it);
    }
    ASSERT_TRUE(sharedRenderer()->render(K_, items, &observed_));
    std::mt19937 rng(seed);
    std::normal_distribution<float> unit(0.f, 1.f);
    for (float& z : observed_.depth) {
      if (z <= 0.f) continue;
      const float sigma = 0.0012f + 0.0019f * (z - 0.4f) * (z - 0.4f);
      z = std::round((z + sigma * unit(rng)) * 1000.f) / 1000.f;
    }
  }

  Eigen::Isometry3d cameraPose(int i) const {
    return T_world_cam_.inverse() * objects_[i].T_world_obj;
  }
  DepthImageView depth() const { return {observed_.depth.data(), K_.width, K_.height}; }

  ConsistencyResult score(const std::shared_ptr<const ObjectModel>& m,
                          const Eigen::Isometry3d& T_world_obj) {
    return scorer_.score(m, T_world_cam_.inverse() * T_world_obj, depth(), K_);
  }
  ConsistencyResult scoreTrue(int i) { return score(objects_[i].model, objects_[i].T_world_obj); }

  /// Fraction of object i's own silhouette that is visible in the scene.
  double visibleFraction(int i) {
    RenderItem it;
    it.mesh = handle(objects_[i].model);
    it.T_cam_model = cameraPose(i);
    RenderedImages alone;
    EXPECT_TRUE(sharedRenderer()->render(K_, {it}, &alone));
    int own = 0, visible = 0;
    for (std::size_t p = 0; p < alone.instance.size(); ++p) {
      if (alone.instance[p] == 0) continue;
      ++own;
      visible += observed_.instance[p] == i + 1;
    }
    return own ? static_cast<double>(visible) / own : 0.0;
  }

  const PlacedObject& object(int i) const { return objects_[i]; }
  /// Takes object i away (or puts it back); renderObserved() shows the change.
  void setHidden(int i, bool hidden) { objects_[i].hidden = hidden; }
  void move(int i, const Eigen::Isometry3d& T_world_obj) { objects_[i].T_world_obj = T_world_obj; }
  /// Moves the camera (renderObserved() shows the scene from there).
  void setCamera(const Eigen::Isometry3d& T_world_cam) { T_world_cam_ = T_world_cam; }
  RenderedImages& observed() { return observed_; }
  const PinholeIntrinsics& K() const { return K_; }
  const Eigen::Isometry3d& T_world_cam() const { return T_world_cam_; }
  ConsistencyScorer& scorer() { return scorer_; }
  void clear() { objects_.clear(); }

 private:
  MeshHandle handle(const std::shared_ptr<const ObjectModel>& m) {
    auto it = handles_.find(m);
    if (it == handles_.end()) it = handles_.emplace(m, sharedRenderer()->addMesh(m->mesh)).first;
    return it->second;
  }

  std::map<std::shared_ptr<const ObjectModel>, MeshHandle> handles_;
  const ModelSet& models_;
  ConsistencyScorer scorer_;
  ObjectModel table_;
  MeshHandle table_handle_ = -1;
  PinholeIntrinsics K_;
  Eigen::Isometry3d T_world_cam_;
  std::vector<PlacedObject> objects_;
  RenderedImages observed_;
};

}  // namespace test
}  // namespace geofusion
