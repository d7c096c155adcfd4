// Geometric consistency score f_gc of a measurement (paper, "Data Association"): how well the
// object model rendered at the detected pose agrees with the observed depth image.
#pragma once

#include "geofusion/common/camera.h"
#include "geofusion/common/images.h"
#include "geofusion/render/renderer.h"

#include <Eigen/Geometry>

#include <cmath>
#include <cstdint>
#include <map>
#include <memory>

namespace geofusion {

struct ObjectModel;

/// The paper's "modified sigmoid": a logistic curve of given centre and steepness, rescaled so
/// that S(0) = 0 and S(1) = 1 on the ratio domain [0, 1] (inputs are clamped to it).
struct ModifiedSigmoid {
  double centre = 0.5;
  double steepness = 10.0;
  double operator()(double x) const;
};

struct ConsistencyConfig {
  /// Sensor resolution (metres along the ray): a rendered point whose observed point on the same
  /// ray is closer than this is an inlier.
  double eps_res = 0.01;
  /// A rendered point whose observed point lies farther behind it than this is an outlier.
  /// Points between eps_res and eps_out behind count in the total only.
  double eps_out = 0.02;
  /// f_gc = S_in(r_in) * S_out(1 - r_out) * S_occ(1 - r_occ).
  ModifiedSigmoid inlier{0.75, 15.0};
  ModifiedSigmoid outlier{0.85, 25.0};
  ModifiedSigmoid occlusion{0.2, 10.0};
  /// Fewer rendered points with an observed depth than this: the score is undetermined.
  int min_points = 30;
  /// Score given when undetermined (object outside the image, or no depth where it projects).
  double undetermined_score = 0.5;
  /// Use every n-th row and column of the rendered region (1 = every pixel).
  int pixel_stride = 1;
  /// Models are rendered from a simplified copy of their mesh (meshoptimizer): at most this many
  /// triangles, unless that would move the surface by more than render_mesh_max_error_m.
  int render_mesh_triangles = 1500;
  double render_mesh_max_error_m = 0.001;
  /// The estimator scores and refines a keyframe's detections in this many threads (its own and
  /// threads - 1 workers, each with its own OSMesa renderer); 1: all in the estimator's thread.
  /// The results do not depend on it.
  int threads = 1;
};

struct ConsistencyResult {
  int rendered = 0;   ///< rendered points visited
  int missing = 0;    ///< ... of which the observation has no depth: neither inlier nor outlier
  int inliers = 0;    ///< observed point within eps_res
  int outliers = 0;   ///< observed point more than eps_out behind the rendered one
  int occluded = 0;   ///< observed point more than eps_res in front (something hides the model)
  int uncertain = 0;  ///< observed point between eps_res and eps_out behind
  /// r_occ: occluded / (rendered - missing). r_in, r_out: inliers, outliers / (rendered -
  /// missing - occluded), i.e. fractions of the part of the model that should be visible.
  double r_in = 0.0;
  double r_out = 0.0;
  double r_occ = 0.0;
  double score = 0.0;       ///< f_gc in [0, 1]
  bool determined = false;  ///< false: too few observed points; score = undetermined_score
};

/// The result of a comparison that cannot be made (nothing rendered, no depth): undetermined,
/// scored config.undetermined_score.
ConsistencyResult undeterminedResult(const ConsistencyConfig& config);

/// Signed distance along the ray of pixel (u, v) from a model surface at depth z_model to the
/// observed surface at depth z_observed (depths along the optical axis; positive: the observed
/// surface is behind the model).
inline double distanceAlongRay(const PinholeIntrinsics& K, double u, double v, double z_observed,
                               double z_model) {
  const double rx = (u - K.cx) / K.fx, ry = (v - K.cy) / K.fy;
  return (z_observed - z_model) * std::sqrt(1.0 + rx * rx + ry * ry);
}

/// Compares a rendering of one model (depth > 0 where it was drawn) with the observed depth.
/// The rendered region must lie inside the observed image.
ConsistencyResult compareDepth(const RenderedImages& rendered, const DepthImageView& observed,
                               const PinholeIntrinsics& K, const ConsistencyConfig& config);

/// compareDepth() of the same model moved by `T_delta` (camera frame: new pose = T_delta x the
/// rendered one) without rendering it again: each rendered point is moved and projected, and
/// compared where it lands (the surface seen stays the one rendered: for the small corrections
/// of a depth refinement, a few millimetres to centimetres, self-occlusion hardly changes).
ConsistencyResult compareMovedDepth(const RenderedImages& rendered,
                                    const Eigen::Isometry3d& T_delta,
                                    const DepthImageView& observed, const PinholeIntrinsics& K,
                                    const ConsistencyConfig& config);

/// Renders models at measured poses (restricted to their image region) and scores them. Keeps
/// one mesh upload per model for its lifetime. Not for concurrent use from several threads.
class ConsistencyScorer {
 public:
  explicit ConsistencyScorer(std::shared_ptr<OffscreenRenderer> renderer,
                             ConsistencyConfig config = ConsistencyConfig());

  /// f_gc of `model` at pose T_cam_model against `observed` depth taken with camera K. A model
  /// whose mesh cannot be rendered, or a pose entirely outside the view, gives an undetermined
  /// result.
  ConsistencyResult score(const std::shared_ptr<const ObjectModel>& model,
                          const Eigen::Isometry3d& T_cam_model, const DepthImageView& observed,
                          const PinholeIntrinsics& K);

  /// The depth of `model` rendered alone at T_cam_model in its projected region (valid until the
  /// next call); null when it cannot be rendered or lies outside the view. score() is
  /// compareDepth() of this.
  const RenderedImages* render(const std::shared_ptr<const ObjectModel>& model,
                               const Eigen::Isometry3d& T_cam_model, const PinholeIntrinsics& K);

  const ConsistencyConfig& config() const { return config_; }
  void setConfig(const ConsistencyConfig& config) { config_ = config; }
  OffscreenRenderer& renderer() { return *renderer_; }

  /// Uploads the model's scoring mesh now (ModelSet's models at start: no first-use stall).
  void prepare(const std::shared_ptr<const ObjectModel>& model) { handleFor(model); }

 private:
  MeshHandle handleFor(const std::shared_ptr<const ObjectModel>& model);

  std::shared_ptr<OffscreenRenderer> renderer_;
  ConsistencyConfig config_;
  std::map<std::shared_ptr<const ObjectModel>, MeshHandle> handles_;
  RenderedImages scratch_;
};

}  // namespace geofusion
