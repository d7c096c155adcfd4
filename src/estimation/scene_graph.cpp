#include "geofusion/estimation/scene_graph.h"

// Boost 1.74's rescale policy trips GCC's -Wmaybe-uninitialized (a false positive in the
// header, fixed in later Boost).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <boost/geometry.hpp>
#pragma GCC diagnostic pop

#include <algorithm>
#include <limits>
#include <map>
#include <set>

namespace geofusion {

namespace {

void addOnce(std::vector<int>* list, int id) {
  if (std::find(list->begin(), list->end(), id) == list->end()) list->push_back(id);
}

// Below this |normal . up| a leaning contact's normal is level and the centres say which object
// is above.
constexpr double kLevelNormal = 0.05;

// One contact into the nodes' relations (indices into `objects`, -1 the plane).
void addRelation(const std::vector<SupportGraphObject>& objects, const FeatureContact& c,
                 const Eigen::Vector3d& up, std::vector<SupportGraphNode>* nodes) {
  const int n = static_cast<int>(objects.size());
  if (c.object_a >= n || c.object_b >= n || c.object_a < -1 || c.object_b < -1 ||
      c.object_a == c.object_b || (c.object_a < 0 && c.object_b < 0))
    return;
  auto idOf = [&](int i) { return i < 0 ? SupportGraph::kSupportPlaneId : objects[i].id; };
  auto node = [&](int i) { return i < 0 ? nullptr : &(*nodes)[static_cast<std::size_t>(i)]; };
  int lower = c.object_a, upper = c.object_b;  // a support contact: a supports b
  if (c.kind == ContactKind::kSide) {
    if (c.object_a < 0 || c.object_b < 0) return;
    addOnce(&node(c.object_a)->beside, idOf(c.object_b));
    addOnce(&node(c.object_b)->beside, idOf(c.object_a));
    return;
  }
  if (c.kind == ContactKind::kLeaning) {
    const double s = c.normal.dot(up);  // the normal runs from a towards b
    bool b_above = s > 0.0;
    if (std::abs(s) < kLevelNormal) {
      const double ha = c.object_a < 0 ? -1e9 : objects[c.object_a].centre.dot(up);
      const double hb = c.object_b < 0 ? -1e9 : objects[c.object_b].centre.dot(up);
      b_above = hb >= ha;
    }
    if (!b_above) std::swap(lower, upper);
    if (upper < 0) return;  // the plane leaning on an object: not a relation a plan uses
    addOnce(&node(upper)->leans_on, idOf(lower));
    if (lower >= 0) addOnce(&node(lower)->leaned_on_by, idOf(upper));
    return;
  }
  if (upper < 0) return;
  addOnce(&node(upper)->supported_by, idOf(lower));
  if (lower >= 0) addOnce(&node(lower)->supports, idOf(upper));
}

namespace bg = boost::geometry;
using Point2 = bg::model::d2::point_xy<double>;
using Polygon2 = bg::model::polygon<Point2>;

// An object's box seen along gravity: its outline on the plane across gravity (the convex hull of
// the box's corners, Boost.Geometry), and its bottom, centre and top along up.
struct Footprint {
  bool known = false;
  Polygon2 outline;
  double area = 0.0, bottom = 0.0, centre = 0.0, top = 0.0;
};

Footprint footprintOf(const SupportGraphObject& o, const Eigen::Vector3d& up) {
  Footprint f;
  if (!(o.box_size.array() > 0.0).all() || !o.box_pose.matrix().allFinite()) return f;
  const Eigen::Vector3d u = up.unitOrthogonal(), v = up.cross(u);
  bg::model::multi_point<Point2> corners;
  f.bottom = std::numeric_limits<double>::infinity();
  f.top = -f.bottom;
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3d corner((k & 1 ? 0.5 : -0.5) * o.box_size.x(),
                                 (k & 2 ? 0.5 : -0.5) * o.box_size.y(),
                                 (k & 4 ? 0.5 : -0.5) * o.box_size.z());
    const Eigen::Vector3d p = o.box_pose * corner;
    corners.push_back(Point2(p.dot(u), p.dot(v)));
    f.bottom = std::min(f.bottom, p.dot(up));
    f.top = std::max(f.top, p.dot(up));
  }
  bg::convex_hull(corners, f.outline);
  f.area = bg::area(f.outline);
  f.centre = o.box_pose.translation().dot(up);
  f.known = f.area > 0.0;
  return f;
}

// Whether `upper` lies over `lower` (buildSupportGraph's rule).
bool liesOver(const Footprint& upper, const Footprint& lower, const SupportGraphConfig& config) {
  if (!upper.known || !lower.known) return false;
  if (upper.centre < lower.centre + config.over_above_m ||
      upper.top < lower.top + config.over_above_m || upper.bottom > lower.top + config.over_gap_m)
    return false;
  std::vector<Polygon2> shared;
  bg::intersection(upper.outline, lower.outline, shared);
  double area = 0.0;
  for (const Polygon2& p : shared) area += bg::area(p);
  return area >= config.over_share * std::min(upper.area, lower.area);
}

// "Over" for the pairs with no support or leaning relation between them.
void addOverRelations(const std::vector<SupportGraphObject>& objects, const Eigen::Vector3d& up,
                      const SupportGraphConfig& config, std::vector<SupportGraphNode>* nodes) {
  std::vector<Footprint> feet;
  for (const SupportGraphObject& o : objects) feet.push_back(footprintOf(o, up));
  auto related = [&](const SupportGraphNode& n, int id) {
    for (const std::vector<int>* l : {&n.supported_by, &n.supports, &n.leans_on, &n.leaned_on_by})
      if (std::find(l->begin(), l->end(), id) != l->end()) return true;
    return false;
  };
  for (std::size_t i = 0; i < objects.size(); ++i)
    for (std::size_t j = 0; j < objects.size(); ++j) {
      if (i == j || !liesOver(feet[i], feet[j], config) || related((*nodes)[i], objects[j].id))
        continue;
      addOnce(&(*nodes)[i].over, objects[j].id);
      addOnce(&(*nodes)[j].covered_by, objects[i].id);
    }
}

// Whether object i goes before j among those free to take: seen better, then higher, then the
// lower id.
bool takenBefore(const SupportGraphObject& i, const SupportGraphObject& j,
                 const Eigen::Vector3d& up) {
  if (i.visibility != j.visibility) return i.visibility > j.visibility;
  const double hi = i.centre.dot(up), hj = j.centre.dot(up);
  if (hi != hj) return hi > hj;
  return i.id < j.id;
}

// The removal order: repeatedly the best-seen object that nothing left rests, leans or lies on; in
// a cycle, the highest object left.
void orderRemovals(const std::vector<SupportGraphObject>& objects, const Eigen::Vector3d& up,
                   SupportGraph* graph) {
  std::map<int, int> index_of;
  for (std::size_t i = 0; i < objects.size(); ++i) index_of[objects[i].id] = static_cast<int>(i);
  std::vector<bool> taken(objects.size(), false);
  auto blocked = [&](std::size_t i) {
    const SupportGraphNode& n = graph->nodes[i];
    for (const std::vector<int>* on : {&n.supports, &n.leaned_on_by, &n.covered_by})
      for (int id : *on)
        if (!taken[static_cast<std::size_t>(index_of.at(id))]) return true;
    return false;
  };
  for (std::size_t step = 0; step < objects.size(); ++step) {
    int best = -1;
    for (std::size_t i = 0; i < objects.size(); ++i) {
      if (taken[i] || blocked(i)) continue;
      if (best < 0 || takenBefore(objects[i], objects[static_cast<std::size_t>(best)], up))
        best = static_cast<int>(i);
    }
    if (best < 0) {  // a cycle: the highest object left
      for (std::size_t i = 0; i < objects.size(); ++i) {
        if (taken[i]) continue;
        if (best < 0 ||
            objects[i].centre.dot(up) > objects[static_cast<std::size_t>(best)].centre.dot(up))
          best = static_cast<int>(i);
      }
      graph->warnings.push_back(
          "objects rest or lean on each other in a cycle: " +
          supportGraphName(*graph, objects[static_cast<std::size_t>(best)].id) +
          ", the highest of them, is taken first");
    }
    taken[static_cast<std::size_t>(best)] = true;
    graph->nodes[static_cast<std::size_t>(best)].removal_step = static_cast<int>(step);
    graph->removal_order.push_back(objects[static_cast<std::size_t>(best)].id);
  }
}

}  // namespace

const SupportGraphNode* SupportGraph::find(int id) const {
  for (const SupportGraphNode& n : nodes)
    if (n.id == id) return &n;
  return nullptr;
}

std::string supportGraphName(const SupportGraph& graph, int id) {
  if (id == SupportGraph::kSupportPlaneId) return "table";
  const SupportGraphNode* n = graph.find(id);
  return (n && !n->class_name.empty() ? n->class_name + " " : std::string()) + "#" +
         std::to_string(id);
}

SupportGraph buildSupportGraph(const std::vector<SupportGraphObject>& objects,
                               const std::vector<FeatureContact>& contacts,
                               const Eigen::Vector3d& gravity, const SupportGraphConfig& config) {
  SupportGraph graph;
  const Eigen::Vector3d up =
      gravity.norm() > 0.0 ? Eigen::Vector3d(-gravity.normalized()) : Eigen::Vector3d::UnitZ();
  for (const SupportGraphObject& o : objects) {
    SupportGraphNode node;
    node.id = o.id;
    node.class_name = o.class_name;
    node.stable = o.stable;
    graph.nodes.push_back(node);
  }
  for (const FeatureContact& c : contacts) addRelation(objects, c, up, &graph.nodes);
  addOverRelations(objects, up, config, &graph.nodes);
  for (SupportGraphNode& n : graph.nodes)
    n.free_to_pick = n.supports.empty() && n.leaned_on_by.empty() && n.covered_by.empty();
  orderRemovals(objects, up, &graph);
  return graph;
}

}  // namespace geofusion
