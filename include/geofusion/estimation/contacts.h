// Geometric relations between objects (paper, "Geometric Feature Relationship Inference" and
// "Physical Relationship Check"): plane-plane, plane-curve and curve-curve contacts between the
// surface features of posed object models, with the support-direction and the projection-overlap
// checks. One implementation, used by the scene estimator (stage II) and by the data generator
// (ground-truth contact graph).
#pragma once

#include "geofusion/model/object_model.h"

#include <Eigen/Geometry>

#include <string>
#include <utility>
#include <vector>

namespace geofusion {

/// The feature pair of a contact. Plane-edge: a plane of one object against the other's hull
/// where it has no feature (an edge or a corner: a box leaning with its face on a can's rim).
enum class ContactType { kPlanePlane, kPlaneCurve, kCurveCurve, kPlaneEdge };
/// "plane-plane", "plane-curve", "curve-curve", "plane-edge"
const char* toString(ContactType type);
const char* shortName(ContactType type);  ///< "P2P", "P2C", "C2C", "P2E" (the files' spelling)
/// The contact type of its short name; throws std::runtime_error for anything else.
ContactType contactTypeOfShortName(const std::string& name);

/// What a contact does: support (its normal within the support cone about -gravity), leaning
/// (the normal between the cone and ContactConfig::side_max_tilt_deg of horizontal, or a contact
/// of an object that does not rest stably on its own: markLeaning) or side by side.
enum class ContactKind { kSupport, kLeaning, kSide };
const char* toString(ContactKind kind);  ///< "support", "leaning", "side"
/// The kind of its name; throws std::runtime_error for anything else.
ContactKind contactKindOfName(const std::string& name);

struct FeatureRef {
  bool plane = true;  ///< index into SurfaceFeatures::planes, else ::curves (-1: the hull, P2E)
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
  ContactKind kind = ContactKind::kSupport;
  /// Kept only by the hysteresis (a pair in contact at the last keyframe, beyond the thresholds
  /// of a new contact): reported, so that it does not blink, but no constraint for stage II.
  bool held = false;
  /// Plane-edge: the touching point of the hull of the object without the plane, in its model
  /// frame.
  Eigen::Vector3d edge_point = Eigen::Vector3d::Zero();
  bool support() const { return kind == ContactKind::kSupport; }
};

struct ContactConfig {
  /// |N_u . N_v + 1| below this (about 6 degrees). A face further off is no face contact: the
  /// object rests on an edge or a narrow strip of its hull that has no plane feature (a mustard
  /// bottle lying on its side rests 12.7 degrees off its nearest face), and a plane-plane factor
  /// would turn it onto that face; the plane-edge contact holds it at its own orientation. It was
  /// 0.03 (14 degrees) until the generator's v5: 30 % of the true plane-plane table contacts of
  /// the bench suites were 6-14 degrees off the pose the object rests in.
  double eps_n_pp = 0.0055;
  double eps_c_pp = 0.006;  ///< |N_u . (C_v - C_u)| below this, metres
  double eps_n_pc = 0.1;    ///< |N_p . N_c| below this (axis within about 6 degrees of the plane)
  double eps_c_pc = 0.006;  ///< |N_p . (C_c - C_p) - r| below this, metres
  double eps_c_cc = 0.006;  ///< axis distance minus (r_i + r_j) below this, metres
  /// Plane-edge: the other hull's nearest point within this of the plane, metres.
  double eps_c_pe = 0.006;
  /// Plane-edge: hull points within this of the nearest one make the touching edge, metres.
  double edge_tolerance_m = 0.003;
  /// Estimates interpenetrate (a mug 9 mm into the rim of its can in hand-annotated YCB-Video
  /// poses): distance terms down to minus this still make a contact, which stage II resolves.
  double max_penetration_m = 0.012;
  double eps_g = 0.8;  ///< support check: N . (-gravity) above this (about 37 degrees)
  /// A contact that is no support is side by side when its normal is within this of horizontal,
  /// degrees; leaning otherwise.
  double side_max_tilt_deg = 20.0;
  /// Hysteresis: a pair in contact at the previous keyframe keeps it with the distance and
  /// direction thresholds multiplied by this (>= 1), so a contact does not blink (such a contact
  /// is marked `held`: stage II leaves it out).
  double hysteresis = 1.5;
  /// Projection-overlap check: the features' 2D outlines must overlap by at least this, metres
  /// (negative tolerates a gap).
  double min_overlap_m = 0.002;
  /// ... except across two parallel line outlines (no width to overlap), which need only meet
  /// within this distance (two cans lying side by side), metres.
  double line_tolerance_m = 0.004;
  /// Keep only support contacts (the paper's stage II); false also finds leaning and side ones.
  bool support_only = false;
};

struct PosedModel {
  const ObjectModel* model = nullptr;
  Eigen::Isometry3d T_world_obj = Eigen::Isometry3d::Identity();
};

/// The thresholds a pair in contact at the previous keyframe is held to
/// (ContactConfig::hysteresis).
ContactConfig heldContactConfig(const ContactConfig& config);

/// Contacts between the features of two posed models; for each pair of objects the
/// highest-order type found is kept (plane-plane over plane-curve over curve-curve over
/// plane-edge).
std::vector<FeatureContact> findContacts(const std::vector<PosedModel>& objects, int a, int b,
                                         const Eigen::Vector3d& gravity,
                                         const ContactConfig& config = ContactConfig());

/// An object pair (indices as in findAllContacts' list, lower first).
using ObjectPair = std::pair<int, int>;

/// Contacts between every pair of objects whose bounding spheres are within reach; the pairs in
/// `held` (in contact at the previous keyframe) with heldContactConfig; markLeaning applied.
std::vector<FeatureContact> findAllContacts(const std::vector<PosedModel>& objects,
                                            const Eigen::Vector3d& gravity,
                                            const ContactConfig& config = ContactConfig(),
                                            const std::vector<ObjectPair>& held = {});

/// Non-support contacts of an object that rests on no face or round side of its own (only on an
/// edge or a corner: tipped) become leaning: that object leans on the other. `contacts` index
/// `objects`; -1 (the table) is stable.
void markLeaning(const std::vector<PosedModel>& objects, std::vector<FeatureContact>* contacts);

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
