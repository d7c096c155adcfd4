// Geometric relations between objects (paper, "Geometric Feature Relationship Inference" and
// "Physical Relationship Check"): plane-plane, plane-curve and curve-curve contacts between the
// surface features of posed object models, with the support-direction and the projection-overlap
// checks. One implementation, used by the scene estimator (stage II) and by the data generator
// (ground-truth contact graph).
#pragma once

#include "geofusion/model/object_model.h"

#include <Eigen/Geometry>

#include <string>
#include <vector>

namespace geofusion {

enum class ContactType { kPlanePlane, kPlaneCurve, kCurveCurve };
const char* toString(ContactType type);   ///< "plane-plane", "plane-curve", "curve-curve"
const char* shortName(ContactType type);  ///< "P2P", "P2C", "C2C" (the files' spelling)
/// The contact type of its short name (P2P, P2C, C2C); throws std::runtime_error for anything else.
ContactType contactTypeOfShortName(const std::string& name);

struct FeatureRef {
  bool plane = true;  ///< index into SurfaceFeatures::planes, else ::curves
  int index = -1;
};

struct FeatureContact {
  int object_a = -1;  ///< indices into the caller's list; for support contacts a supports b
  int object_b = -1;
  ContactType type = ContactType::kPlanePlane;
  FeatureRef feature_a;
  FeatureRef feature_b;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< world, unit, from a towards b
  double direction_residual = 0.0;  ///< the paper's direction term (0 = perfectly aligned)
  double distance_residual = 0.0;   ///< the paper's distance term, metres (signed: > 0 apart)
  bool support = false;             ///< normal within the support cone about -gravity
};

struct ContactConfig {
  double eps_n_pp = 0.03;   ///< |N_u . N_v + 1| below this (about 14 degrees)
  double eps_c_pp = 0.006;  ///< |N_u . (C_v - C_u)| below this, metres
  double eps_n_pc = 0.1;    ///< |N_p . N_c| below this (axis within about 6 degrees of the plane)
  double eps_c_pc = 0.006;  ///< |N_p . (C_c - C_p) - r| below this, metres
  double eps_c_cc = 0.006;  ///< axis distance minus (r_i + r_j) below this, metres
  double eps_g = 0.8;       ///< support check: N . (-gravity) above this (about 37 degrees)
  /// Projection-overlap check: the features' 2D outlines must overlap by at least this, metres
  /// (negative tolerates a gap).
  double min_overlap_m = 0.002;
  /// ... except across two parallel line outlines (no width to overlap), which need only meet
  /// within this distance (two cans lying side by side), metres.
  double line_tolerance_m = 0.004;
  /// Keep only support contacts (the paper's stage II); false also reports side contacts.
  bool support_only = true;
};

struct PosedModel {
  const ObjectModel* model = nullptr;
  Eigen::Isometry3d T_world_obj = Eigen::Isometry3d::Identity();
};

/// Contacts between the features of two posed models; for each pair of objects the
/// highest-order type found is kept (plane-plane over plane-curve over curve-curve).
std::vector<FeatureContact> findContacts(const std::vector<PosedModel>& objects, int a, int b,
                                         const Eigen::Vector3d& gravity,
                                         const ContactConfig& config = ContactConfig());

/// Contacts between every pair of objects whose bounding spheres are within reach.
std::vector<FeatureContact> findAllContacts(const std::vector<PosedModel>& objects,
                                            const Eigen::Vector3d& gravity,
                                            const ContactConfig& config = ContactConfig());

/// The contacts a user sees (results, markers, map messages): one per object pair and contact
/// type, the one whose distance residual is smallest in magnitude. Stage II keeps every feature
/// pair; two planar facets of a clamp on the table are one contact to the user.
std::vector<FeatureContact> onePerPairAndType(const std::vector<FeatureContact>& contacts);

/// Whether the convex outlines of two point sets, projected along `direction`, overlap by at
/// least `min_overlap` (separating axis theorem; two points make a segment, one a point). Along
/// an axis across which both outlines have no width, they need only meet within `line_tolerance`.
bool projectionsOverlap(const std::vector<Eigen::Vector3d>& a,
                        const std::vector<Eigen::Vector3d>& b, const Eigen::Vector3d& direction,
                        double min_overlap, double line_tolerance = 0.004);

}  // namespace geofusion
