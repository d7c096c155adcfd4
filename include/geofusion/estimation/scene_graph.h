// The support graph as a plan (issue 50): per object what supports it, what it supports, what it
// leans on and what stands beside it, whether it stands, whether it is free to pick (nothing
// rests or leans on it), and a removal order (top first: a topological order of the "rests or
// leans on" graph, ties broken by what the robot sees best). Built from the map's contacts; one
// implementation for run_offline's results, the Python API, the ROS service and the benchmark's
// ground truth.
#pragma once

#include "geofusion/estimation/contacts.h"

#include <Eigen/Geometry>

#include <string>
#include <vector>

namespace geofusion {

/// One object the graph is built over.
struct SupportGraphObject {
  int id = -1;  ///< the map's object id (>= 0; the support plane is kSupportPlaneId)
  std::string class_name;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();  ///< map frame: the height tie-break
  /// How well the robot sees it (the map's existence score): the removal order's tie-break.
  double visibility = 0.0;
  /// -1: not checked; 0 / 1: the stability check moved it / left it standing.
  int stable = -1;
  /// Its box in the map frame (the model's bounding box at its pose: the box's centre and axes,
  /// its edge lengths): which objects lie over it where no contact between them was found. A
  /// zero size: not known, no such relation.
  Eigen::Isometry3d box_pose = Eigen::Isometry3d::Identity();
  Eigen::Vector3d box_size = Eigen::Vector3d::Zero();
};

/// "Over" without a contact (buildSupportGraph; the `scene_graph` settings).
struct SupportGraphConfig {
  double over_share = 0.2;     ///< the share of the smaller footprint the two overlap, at least
  double over_above_m = 0.01;  ///< the upper one's centre and top higher by at least this
  double over_gap_m = 0.03;    ///< its bottom at most this far above the lower one's top
};

struct SupportGraphNode {
  int id = -1;
  std::string class_name;
  /// Ids; SupportGraph::kSupportPlaneId (-1) is the support plane (the table; messages: 0).
  std::vector<int> supported_by, supports;
  std::vector<int> leans_on, leaned_on_by;
  std::vector<int> beside;  ///< side-by-side contacts
  /// No contact found between them, but one lies over the other (their footprints across
  /// gravity overlap, the upper one higher and close above): a contact the map may have missed,
  /// so the order and free_to_pick treat "covered by" as "supports".
  std::vector<int> over, covered_by;
  int stable = -1;  ///< as SupportGraphObject::stable
  /// Nothing rests, leans or lies on it: taking it disturbs no other object.
  bool free_to_pick = true;
  int removal_step = -1;  ///< its place in SupportGraph::removal_order (0 first)
};

struct SupportGraph {
  static constexpr int kSupportPlaneId = -1;
  std::vector<SupportGraphNode> nodes;  ///< in the order of the objects given
  std::vector<int> removal_order;       ///< object ids, the first to take first
  /// Cycles of "rests or leans on" (two estimates each on the other): broken by taking the
  /// highest object of the cycle first, each one said here.
  std::vector<std::string> warnings;
  /// The node of an object id, or null.
  const SupportGraphNode* find(int id) const;
};

/// The graph of `objects` from `contacts` (object_a / object_b index `objects`, -1 the support
/// plane). A support contact: a supports b. A leaning contact: the object above (along
/// -gravity, by the contact normal; by the centres when the normal is level) leans on the other.
/// A side contact: beside each other. Contacts naming an object outside the list are skipped.
/// Pairs of objects with boxes and no support or leaning contact between them: one is over the
/// other when their footprints across gravity overlap by over_share of the smaller one, the upper
/// one's centre and top higher by over_above_m and its bottom at most over_gap_m above the lower
/// one's top (`config`).
SupportGraph buildSupportGraph(const std::vector<SupportGraphObject>& objects,
                               const std::vector<FeatureContact>& contacts,
                               const Eigen::Vector3d& gravity,
                               const SupportGraphConfig& config = SupportGraphConfig());

/// "class #id" of an object of the graph ("table" for the support plane, "#id" when unknown).
std::string supportGraphName(const SupportGraph& graph, int id);

}  // namespace geofusion
