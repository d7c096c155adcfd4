// Data association (paper, "Data Association", Algorithm 1): measurement-to-object likelihoods
// (label indicator x geometric consistency x Gaussian pose factor, symmetry-aware), the joint
// one-measurement-per-object assignment of a keyframe, the false-positive score and the
// oriented-box collision ratio used to merge overlapping objects.
#pragma once

#include "geofusion/model/object_model.h"

#include <Eigen/Geometry>

#include <vector>

namespace geofusion {

struct AssociationConfig {
  double sigma_position_m = 0.04;   ///< Q: pose factor translation std (per axis)
  double sigma_rotation_rad = 0.5;  ///< Q: pose factor rotation std
  /// Below this likelihood a measurement starts a new object (eps_new).
  double eps_new = 0.05;
  /// Objects whose false-positive score exceeds this are not in the map (eps_fp): they stay
  /// candidates, gathering measurements, and are deleted when not observed for
  /// candidate_timeout_keyframes keyframes.
  double eps_fp = 0.55;
  int candidate_timeout_keyframes = 10;
  /// Objects whose oriented boxes overlap by more than this collision ratio are merged, ...
  double merge_ratio = 0.4;
  /// ... when their convex hulls also interpenetrate by at least this (FCL), metres: the boxes
  /// of neighbours in clutter overlap, duplicates and false positives interpenetrate.
  double merge_min_penetration_m = 0.01;
  /// ... or at least this share of the thinner object's smallest extent, if less.
  double merge_thin_fraction = 0.3;
  /// Objects of two classes merge only when they interpenetrate by at least this share of the
  /// thinner object's smallest extent (a look-alike reported in place of the object): a real
  /// object differs from its mesh by millimetres, so real neighbours overlap a little.
  double merge_cross_class_fraction = 0.5;
  /// Objects of two classes that the depth supported together (both measured with f_gc > 0 at
  /// one keyframe) at this many keyframes or more are two real objects side by side, not a
  /// look-alike in place of one: they merge only past merge_min_penetration_m, however thin
  /// (a pair of scissors beside a pudding box, issue 45). 0: off.
  int merge_co_measured_keyframes = 5;
  /// The interpenetration measured on each model's convex parts (ObjectModel::collision_parts:
  /// a banana or a clamp in pieces, issue 45); false: on one convex hull per model (the paper's
  /// test as built before, for comparison: a hull spans the air inside a curve or a handle).
  bool merge_on_convex_parts = true;
  /// true: one Hungarian assignment per keyframe (all measurements jointly); false: the paper's
  /// greedy order (a later measurement that wants a taken object starts a new one).
  bool joint_assignment = true;
  /// Issue 51: a detection of another class that would be the same object as one of the map
  /// (the merge test: one object mapped twice) is the detector naming it otherwise, not a new
  /// object. Both models are scored against the keyframe's depth there (f_gc) and the object
  /// takes the class of larger support: its scores summed over the keyframes the classes
  /// competed, plus class_vote_weight per detection of it (the votes as a prior). false: a new
  /// object, which the merge settles later by the depth's support over its measurements.
  bool class_by_consistency = true;
  double class_vote_weight = 0.05;
};

/// Rotation angle between two orientations of a model, modulo its symmetry: for a continuous
/// symmetry the angle between the two images of the axis, for a discrete one the smallest angle
/// over the symmetric equivalents.
double symmetricRotationError(const Symmetry& symmetry, const Eigen::Matrix3d& R_a,
                              const Eigen::Matrix3d& R_b);

/// The symmetric equivalent of `R_measured` closest to `R_reference` (identity for no or
/// continuous symmetry: the caller handles the free axis).
Eigen::Matrix3d closestSymmetricEquivalent(const Symmetry& symmetry,
                                           const Eigen::Matrix3d& R_reference,
                                           const Eigen::Matrix3d& R_measured);

/// Gaussian pose factor N(x_t^-1 o_j, Q), 1 at a perfect match: exp(-0.5 * (|dt|^2 / sigma_p^2 +
/// angle^2 / sigma_q^2)).
double poseLikelihood(const Symmetry& symmetry, const Eigen::Isometry3d& T_predicted,
                      const Eigen::Isometry3d& T_measured, const AssociationConfig& config);

/// Optimal assignment of rows to columns minimising the summed cost (Hungarian / Kuhn-Munkres,
/// O(n^3)); rectangular matrices allowed. Returns for each row its column, or -1.
std::vector<int> solveAssignment(const Eigen::MatrixXd& cost);

/// Joint association of one keyframe: likelihood(k, j) of measurement k belonging to object j
/// (0 = impossible). Returns for each measurement its object, or -1 for a new object; no object
/// gets two measurements. Joint (Hungarian on -log likelihood with a "new object" option of cost
/// -log eps_new for each measurement) or greedy (the paper's order) per the config.
std::vector<int> associate(const Eigen::MatrixXd& likelihood, const AssociationConfig& config);

/// The paper's false-positive score f_j = 1 - R_j / (1 + exp(-n_j)): R_j the best geometric
/// consistency of the object's measurements, n_j their number.
double falsePositiveScore(double best_consistency, int num_measurements);

/// Collision ratio of two oriented boxes (centre and half sizes in the box frame, posed): 0 when
/// the separating axis theorem finds a separating axis among the 15 candidates, else the smallest
/// overlap along the six face axes divided by the smaller box's extent along that axis (1: one
/// box inside the other along every axis).
double boxCollisionRatio(const Eigen::Isometry3d& T_a, const Eigen::Vector3d& half_a,
                         const Eigen::Isometry3d& T_b, const Eigen::Vector3d& half_b);

}  // namespace geofusion
