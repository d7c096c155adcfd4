// Glue between generated sequences and the estimator, and a quick map score against ground
// truth. Used by the estimator's tests and benchmark (the full benchmark metrics, COCO mAP
// included, are computed by the evaluator of the benchmark tool).
#pragma once

#include "geofusion/estimation/scene_estimator.h"
#include "geofusion/simulation/clutter_scene.h"
#include "geofusion/simulation/sequence.h"

#include <vector>

namespace geofusion {

/// The estimator's input for a rendered frame: noisy depth, the odometry camera pose (drifting
/// odometry chained with the head and optical transforms), the frame's detections that pass the
/// frame-by-frame checks. The keyframe points into `frame`'s depth: keep `frame` alive.
Keyframe makeKeyframe(const FramePose& pose, const SequenceFrame& frame,
                      const PinholeIntrinsics& K);

struct MapScore {
  int objects = 0;
  int true_positives = 0;      ///< matched to a true object of the same class within max_adds
  int false_positives = 0;     ///< everything else
  double mean_adds_m = 0.0;    ///< over true positives
  std::vector<double> adds_m;  ///< of each true positive
  std::vector<int> match;      ///< per estimated object: the scene object it matched, or -1
};

/// Greedy one-to-one matching of estimated objects (map frame = scene world frame) to the
/// scene's objects of the same class by ADD-S, accepted below `max_adds_m`.
MapScore scoreMap(const ClutterScene& scene, const std::vector<ObjectEstimate>& objects,
                  double max_adds_m = 0.05);

/// Where a part of the map lies against its scene: T_true_map brings the map's objects onto the
/// scene's objects (scene world frame) with no starting guess, so that a table the robot reached
/// after a long drive (odometry drift of metres and tens of degrees) is scored on its own.
struct SceneAlignment {
  Eigen::Isometry3d T_true_map = Eigen::Isometry3d::Identity();
  int inliers = 0;      ///< map objects within inlier_m of a scene object of their class
  double rmse_m = 0.0;  ///< over the inliers, after the alignment
};

/// Hypotheses from every two map objects paired with two scene objects of the same classes at the
/// same distance apart (a planar motion: a turn about z and a shift, the drift of a ground robot's
/// odometry); the one that brings most map objects within `inlier_m` of a scene object of their
/// class wins and is refined on them (least squares, planar too). Identity and 0 inliers when no
/// two objects agree.
SceneAlignment alignMapToScene(const ClutterScene& scene,
                               const std::vector<ObjectEstimate>& objects, double inlier_m = 0.05);

/// Number of scene objects that `frames` detect (true class) in at least `min_frames` frames.
int objectsDetectedInFrames(const ClutterScene& scene, const std::vector<SequenceFrame>& frames,
                            int min_frames);

}  // namespace geofusion
