#include "geofusion/render/consistency.h"

#include "geofusion/model/object_model.h"

#include <algorithm>
#include <cmath>

namespace geofusion {

namespace {
double logistic(double x) {
  return 1.0 / (1.0 + std::exp(-x));
}
}  // namespace

double ModifiedSigmoid::operator()(double x) const {
  x = std::clamp(x, 0.0, 1.0);
  const double lo = logistic(-steepness * centre);
  const double hi = logistic(steepness * (1.0 - centre));
  if (hi - lo <= 1e-12) return x;  // degenerate (zero steepness): identity
  return std::clamp((logistic(steepness * (x - centre)) - lo) / (hi - lo), 0.0, 1.0);
}

ConsistencyResult undeterminedResult(const ConsistencyConfig& config) {
  ConsistencyResult r;
  r.score = config.undetermined_score;
  return r;
}

namespace {

// Classifies rendered points against the observation by their distance along the ray
// (distanceAlongRay), compared squared: no square root or division a pixel.
class PointClassifier {
 public:
  PointClassifier(const DepthImageView& observed, const PinholeIntrinsics& K,
                  const ConsistencyConfig& config)
      : observed_(observed),
        K_(K),
        inv_fx_(1.0 / K.fx),
        inv_fy_(1.0 / K.fy),
        eps_res2_(config.eps_res * config.eps_res),
        eps_out2_(config.eps_out * config.eps_out) {}

  // One rendered point at pixel (u, v), depth z_model, against the observation there.
  void classify(int u, int v, float z_model, ConsistencyResult* r) const {
    ++r->rendered;
    const float z_obs = observed_.at(u, v);
    if (!(z_obs > 0.f) || !std::isfinite(z_obs)) {
      ++r->missing;
      return;
    }
    const double rx = (u - K_.cx) * inv_fx_, ry = (v - K_.cy) * inv_fy_;
    const double dz = static_cast<double>(z_obs) - z_model;
    const double along2 = dz * dz * (1.0 + rx * rx + ry * ry);  // distanceAlongRay squared
    if (along2 <= eps_res2_) {
      ++r->inliers;
    } else if (dz < 0.0) {
      ++r->occluded;
    } else if (along2 > eps_out2_) {
      ++r->outliers;
    } else {
      ++r->uncertain;
    }
  }

 private:
  const DepthImageView& observed_;
  const PinholeIntrinsics& K_;
  const double inv_fx_, inv_fy_, eps_res2_, eps_out2_;
};

// The ratios and f_gc of the counted points.
ConsistencyResult scoreCounts(ConsistencyResult r, const ConsistencyConfig& config) {
  const int observed_points = r.rendered - r.missing;
  if (observed_points < std::max(1, config.min_points)) {
    r.score = config.undetermined_score;
    return r;
  }
  r.determined = true;
  // Occlusion over every observed point; inliers and outliers over the part not hidden, so that
  // occlusion is counted once (by S_occ) and not a second time as missing inliers.
  r.r_occ = static_cast<double>(r.occluded) / observed_points;
  const int visible = observed_points - r.occluded;
  r.r_in = visible > 0 ? static_cast<double>(r.inliers) / visible : 0.0;
  r.r_out = visible > 0 ? static_cast<double>(r.outliers) / visible : 0.0;
  r.score = config.inlier(r.r_in) * config.outlier(1.0 - r.r_out) * config.occlusion(1.0 - r.r_occ);
  return r;
}

}  // namespace

ConsistencyResult compareDepth(const RenderedImages& rendered, const DepthImageView& observed,
                               const PinholeIntrinsics& K, const ConsistencyConfig& config) {
  ConsistencyResult r;
  const PixelBox& box = rendered.region;
  const int stride = std::max(1, config.pixel_stride);
  const bool inside = observed.data && box.valid() && box.x >= 0 && box.y >= 0 &&
                      box.x + box.width <= observed.width &&
                      box.y + box.height <= observed.height &&
                      rendered.depth.size() == static_cast<std::size_t>(box.area());
  if (inside) {
    const PointClassifier classifier(observed, K, config);
    for (int y = 0; y < box.height; y += stride) {
      const float* row = rendered.depth.data() + static_cast<std::size_t>(y) * box.width;
      for (int x = 0; x < box.width; x += stride) {
        if (row[x] > 0.f) classifier.classify(box.x + x, box.y + y, row[x], &r);
      }
    }
  }
  return scoreCounts(r, config);
}

ConsistencyResult compareMovedDepth(const RenderedImages& rendered,
                                    const Eigen::Isometry3d& T_delta,
                                    const DepthImageView& observed, const PinholeIntrinsics& K,
                                    const ConsistencyConfig& config) {
  ConsistencyResult r;
  const PixelBox& box = rendered.region;
  const int stride = std::max(1, config.pixel_stride);
  if (!observed.data || !box.valid() ||
      rendered.depth.size() != static_cast<std::size_t>(box.area()))
    return scoreCounts(r, config);
  const PointClassifier classifier(observed, K, config);
  // The moved point of pixel (x, y) at depth z: z R ray(x, y) + t, with R ray linear in x.
  const Eigen::Matrix3d& R = T_delta.linear();
  const Eigen::Vector3d t = T_delta.translation();
  const Eigen::Vector3d along_row = R.col(0) / K.fx;
  for (int y = 0; y < box.height; y += stride) {
    const float* row = rendered.depth.data() + static_cast<std::size_t>(y) * box.width;
    const Eigen::Vector3d row_start =
        R.col(0) * ((box.x - K.cx) / K.fx) + R.col(1) * ((box.y + y - K.cy) / K.fy) + R.col(2);
    for (int x = 0; x < box.width; x += stride) {
      if (!(row[x] > 0.f)) continue;
      const Eigen::Vector3d p = static_cast<double>(row[x]) * (row_start + x * along_row) + t;
      if (!(p.z() > 0.0)) continue;
      const double inv_z = 1.0 / p.z();
      int u, v;
      if (!K.nearestPixel({K.fx * p.x() * inv_z + K.cx, K.fy * p.y() * inv_z + K.cy}, &u, &v) ||
          u >= observed.width || v >= observed.height)
        continue;
      classifier.classify(u, v, static_cast<float>(p.z()), &r);
    }
  }
  return scoreCounts(r, config);
}

ConsistencyScorer::ConsistencyScorer(std::shared_ptr<OffscreenRenderer> renderer,
                                     ConsistencyConfig config)
    : renderer_(std::move(renderer)), config_(config) {}

MeshHandle ConsistencyScorer::handleFor(const std::shared_ptr<const ObjectModel>& model) {
  const auto it = handles_.find(model);
  if (it != handles_.end()) return it->second;
  const MeshHandle h = renderer_->addMesh(simplifyMesh(
      model->mesh, static_cast<std::size_t>(std::max(1, config_.render_mesh_triangles)),
      config_.render_mesh_max_error_m));
  handles_.emplace(model, h);  // -1 is remembered too: a bad mesh is reported once
  return h;
}

const RenderedImages* ConsistencyScorer::render(const std::shared_ptr<const ObjectModel>& model,
                                                const Eigen::Isometry3d& T_cam_model,
                                                const PinholeIntrinsics& K) {
  if (!model || !renderer_ || !renderer_->ok() || !T_cam_model.matrix().allFinite()) return nullptr;
  const MeshHandle mesh = handleFor(model);
  if (mesh < 0) return nullptr;
  const PixelBox region = renderer_->projectedRegion(K, mesh, T_cam_model);
  if (!region.valid()) return nullptr;
  RenderItem item;
  item.mesh = mesh;
  item.T_cam_model = T_cam_model;
  if (!renderer_->render(K, {item}, &scratch_, region, OffscreenRenderer::kDepth)) return nullptr;
  return &scratch_;
}

ConsistencyResult ConsistencyScorer::score(const std::shared_ptr<const ObjectModel>& model,
                                           const Eigen::Isometry3d& T_cam_model,
                                           const DepthImageView& observed,
                                           const PinholeIntrinsics& K) {
  const RenderedImages* rendered = render(model, T_cam_model, K);
  return rendered ? compareDepth(*rendered, observed, K, config_) : undeterminedResult(config_);
}

}  // namespace geofusion
