#include "geofusion/evaluation/vsd.h"

#include "geofusion/render/renderer.h"

#include <algorithm>
#include <cmath>

namespace geofusion {

double distanceOfDepth(double depth, double u, double v, const PinholeIntrinsics& K) {
  const double x = (u - K.cx) / K.fx, y = (v - K.cy) / K.fy;
  return depth * std::sqrt(1.0 + x * x + y * y);
}

VsdScorer::VsdScorer(std::shared_ptr<OffscreenRenderer> renderer, const VsdConfig& config)
    : renderer_(std::move(renderer)), config_(config) {}

int VsdScorer::meshOf(const ObjectModel& model) {
  const auto it = meshes_.find(&model);
  if (it != meshes_.end()) return it->second;
  // A lighter copy (at most 1 mm off, a fifth of BOP's smallest tolerance on the YCB-Video
  // objects): the renders are most of the evaluation's time.
  const int handle =
      model.mesh.empty() ? -1 : renderer_->addMesh(simplifyMesh(model.mesh, 3000, 0.001));
  meshes_[&model] = handle;
  return handle;
}

bool VsdScorer::setScene(const PinholeIntrinsics& K, const std::vector<PosedObject>& scene) {
  K_ = K;
  scene_distance_.assign(static_cast<std::size_t>(K.width) * K.height, 0.0f);
  std::vector<RenderItem> items;
  for (const PosedObject& o : scene) {
    const int mesh = o.model ? meshOf(*o.model) : -1;
    if (mesh >= 0) items.push_back({mesh, o.T_cam_obj, 1, Eigen::Vector3f::Constant(0.7f)});
  }
  RenderedImages image;
  if (!renderer_->render(K, items, &image, PixelBox{}, OffscreenRenderer::kDepth)) return false;
  for (int v = 0; v < K.height; ++v)
    for (int u = 0; u < K.width; ++u) {
      const float d = image.depthAt(u, v);
      scene_distance_[static_cast<std::size_t>(v) * K.width + u] =
          d > 0.0f ? static_cast<float>(distanceOfDepth(d, u, v, K)) : 0.0f;
    }
  return true;
}

bool VsdScorer::renderAlone(int mesh, const Eigen::Isometry3d& T, const PixelBox& region,
                            std::vector<float>* distance) {
  RenderedImages image;
  if (!renderer_->render(K_, {{mesh, T, 1, Eigen::Vector3f::Constant(0.7f)}}, &image, region,
                         OffscreenRenderer::kDepth))
    return false;
  distance->assign(static_cast<std::size_t>(region.area()), 0.0f);
  for (int y = 0; y < region.height; ++y)
    for (int x = 0; x < region.width; ++x) {
      const float d = image.depthAt(region.x + x, region.y + y);
      (*distance)[static_cast<std::size_t>(y) * region.width + x] =
          d > 0.0f ? static_cast<float>(distanceOfDepth(d, region.x + x, region.y + y, K_)) : 0.0f;
    }
  return true;
}

namespace {

// The smallest box holding both (either may be invalid).
PixelBox unite(const PixelBox& a, const PixelBox& b) {
  if (!a.valid()) return b;
  if (!b.valid()) return a;
  const int x0 = std::min(a.x, b.x), y0 = std::min(a.y, b.y);
  const int x1 = std::max(a.x + a.width, b.x + b.width),
            y1 = std::max(a.y + a.height, b.y + b.height);
  return {x0, y0, x1 - x0, y1 - y0};
}

// BOP19's visibility: the model's surface where it is drawn and not behind the test surface by
// more than delta (or where the test image has no depth).
bool visible(float model, float test, double delta) {
  return model > 0.0f && (test == 0.0f || model - test <= delta);
}

}  // namespace

std::vector<double> VsdScorer::errors(const ObjectModel& model, const Eigen::Isometry3d& T_est,
                                      const Eigen::Isometry3d& T_true, double diameter_m) {
  const int mesh = meshOf(model);
  if (mesh < 0 || scene_distance_.empty() || !(diameter_m > 0.0)) return {};
  const PixelBox region = unite(renderer_->projectedRegion(K_, mesh, T_est),
                                renderer_->projectedRegion(K_, mesh, T_true));
  std::vector<double> out(config_.tau_fractions.size(), 1.0);
  if (!region.valid()) return out;  // neither in view: nothing visible, the worst error
  std::vector<float> est, gt;
  if (!renderAlone(mesh, T_est, region, &est) || !renderAlone(mesh, T_true, region, &gt)) return {};
  std::vector<double> dists;  // |d_gt - d_est| / diameter over the intersection
  int union_count = 0, inter_count = 0;
  for (int y = 0; y < region.height; ++y)
    for (int x = 0; x < region.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * region.width + x;
      const float test =
          scene_distance_[static_cast<std::size_t>(region.y + y) * K_.width + region.x + x];
      const bool vis_gt = visible(gt[i], test, config_.delta_m);
      // The estimate is also visible wherever the truth is and it is drawn (bop19).
      const bool vis_est = visible(est[i], test, config_.delta_m) || (vis_gt && est[i] > 0.0f);
      if (!vis_gt && !vis_est) continue;
      ++union_count;
      if (vis_gt && vis_est) {
        ++inter_count;
        dists.push_back(std::abs(gt[i] - est[i]) / diameter_m);
      }
    }
  if (union_count == 0) return out;
  for (std::size_t t = 0; t < out.size(); ++t) {
    const double tau = config_.tau_fractions[t];
    const auto costs =
        std::count_if(dists.begin(), dists.end(), [tau](double d) { return d >= tau; });
    out[t] = static_cast<double>(costs + (union_count - inter_count)) / union_count;
  }
  return out;
}

}  // namespace geofusion
