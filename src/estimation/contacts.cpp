#include "geofusion/estimation/contacts.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace geofusion {

const char* toString(ContactType type) {
  switch (type) {
    case ContactType::kPlanePlane: return "plane-plane";
    case ContactType::kPlaneCurve: return "plane-curve";
    case ContactType::kCurveCurve: return "curve-curve";
    case ContactType::kPlaneEdge: return "plane-edge";
  }
  return "?";
}

const char* toString(ContactKind kind) {
  switch (kind) {
    case ContactKind::kSupport: return "support";
    case ContactKind::kLeaning: return "leaning";
    case ContactKind::kSide: return "side";
  }
  return "?";
}

ContactKind contactKindOfName(const std::string& name) {
  for (ContactKind k : {ContactKind::kSupport, ContactKind::kLeaning, ContactKind::kSide}) {
    if (name == toString(k)) return k;
  }
  throw std::runtime_error("unknown contact kind '" + name + "'");
}

const char* shortName(ContactType type) {
  switch (type) {
    case ContactType::kPlanePlane: return "P2P";
    case ContactType::kPlaneCurve: return "P2C";
    case ContactType::kPlaneEdge: return "P2E";
    default: return "C2C";
  }
}

ContactType contactTypeOfShortName(const std::string& name) {
  for (ContactType t : {ContactType::kPlanePlane, ContactType::kPlaneCurve,
                        ContactType::kCurveCurve, ContactType::kPlaneEdge}) {
    if (name == shortName(t)) return t;
  }
  throw std::runtime_error("unknown contact type '" + name + "'");
}

namespace {

using Point2 = Eigen::Vector2d;

double cross2(const Point2& o, const Point2& a, const Point2& b) {
  return (a - o).x() * (b - o).y() - (a - o).y() * (b - o).x();
}

// Convex hull (Andrew's monotone chain), counter-clockwise; fewer than 3 points come back as is.
std::vector<Point2> hull2d(std::vector<Point2> p) {
  std::sort(p.begin(), p.end(), [](const Point2& a, const Point2& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  p.erase(std::unique(p.begin(), p.end(),
                      [](const Point2& a, const Point2& b) { return (a - b).norm() < 1e-9; }),
          p.end());
  if (p.size() < 3) return p;
  std::vector<Point2> h(2 * p.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    while (k >= 2 && cross2(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  for (std::size_t i = p.size() - 1, t = k + 1; i > 0; --i) {
    while (k >= t && cross2(h[k - 2], h[k - 1], p[i - 1]) <= 0) --k;
    h[k++] = p[i - 1];
  }
  h.resize(k - 1);
  if (h.size() < 3) {  // collinear: keep the two extremes
    return {p.front(), p.back()};
  }
  return h;
}

void addAxes(const std::vector<Point2>& poly, std::vector<Point2>* axes) {
  if (poly.size() == 2) {
    const Point2 d = (poly[1] - poly[0]).normalized();
    axes->push_back(d);
    axes->emplace_back(-d.y(), d.x());
    return;
  }
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const Point2 e = poly[(i + 1) % poly.size()] - poly[i];
    if (e.norm() < 1e-12) continue;
    axes->push_back(Point2(-e.y(), e.x()).normalized());
  }
}

struct WorldPlane {
  Eigen::Vector3d center, normal;
  std::vector<Eigen::Vector3d> boundary;
};
struct WorldCurve {
  Eigen::Vector3d center, axis, end_a, end_b;
  double radius;
};

std::vector<WorldPlane> worldPlanes(const PosedModel& m) {
  std::vector<WorldPlane> out;
  for (const auto& p : m.model->features.planes) {
    WorldPlane w{m.T_world_obj * p.center, m.T_world_obj.linear() * p.normal, {}};
    for (const auto& b : p.boundary) w.boundary.push_back(m.T_world_obj * b);
    out.push_back(std::move(w));
  }
  return out;
}

std::vector<WorldCurve> worldCurves(const PosedModel& m) {
  std::vector<WorldCurve> out;
  for (const auto& c : m.model->features.curves) {
    out.push_back({m.T_world_obj * c.center, m.T_world_obj.linear() * c.axis,
                   m.T_world_obj * c.end_a, m.T_world_obj * c.end_b, c.radius_m});
  }
  return out;
}

// The points of m's hull nearest to the plane (centre c, outward normal n), in m's model frame:
// those within `tolerance` of the nearest; `distance` receives the nearest's signed distance.
std::vector<Eigen::Vector3d> nearestHullPoints(const PosedModel& m, const Eigen::Vector3d& c,
                                               const Eigen::Vector3d& n, double tolerance,
                                               double* distance) {
  const TriangleMesh& hull =
      m.model->collision_hull.vertices.empty() ? m.model->mesh : m.model->collision_hull;
  const Eigen::Vector3d n_model = m.T_world_obj.linear().transpose() * n;
  const double offset = n.dot(m.T_world_obj.translation() - c);
  double nearest = std::numeric_limits<double>::max();
  for (const auto& v : hull.vertices) nearest = std::min(nearest, n_model.dot(v.cast<double>()));
  std::vector<Eigen::Vector3d> out;
  for (const auto& v : hull.vertices) {
    if (n_model.dot(v.cast<double>()) < nearest + tolerance) out.push_back(v.cast<double>());
  }
  *distance = nearest + offset;
  return out;
}

}  // namespace

ContactConfig heldContactConfig(const ContactConfig& config) {
  ContactConfig held = config;
  const double h = std::max(1.0, config.hysteresis);
  for (double* eps : {&held.eps_n_pp, &held.eps_c_pp, &held.eps_n_pc, &held.eps_c_pc,
                      &held.eps_c_cc, &held.eps_c_pe, &held.max_penetration_m})
    *eps *= h;
  return held;
}

bool projectionsOverlap(const std::vector<Eigen::Vector3d>& a,
                        const std::vector<Eigen::Vector3d>& b, const Eigen::Vector3d& direction,
                        double min_overlap, double line_tolerance) {
  if (a.empty() || b.empty() || direction.norm() < 1e-12) return false;
  const Eigen::Vector3d n = direction.normalized();
  const Eigen::Vector3d u = n.unitOrthogonal(), w = n.cross(u);
  auto project = [&](const std::vector<Eigen::Vector3d>& pts) {
    std::vector<Point2> out;
    out.reserve(pts.size());
    for (const auto& p : pts) out.emplace_back(p.dot(u), p.dot(w));
    return hull2d(out);
  };
  const std::vector<Point2> pa = project(a), pb = project(b);
  std::vector<Point2> axes;
  addAxes(pa, &axes);
  addAxes(pb, &axes);
  if (axes.empty()) axes = {Point2::UnitX(), Point2::UnitY()};
  // Smallest separating push over all axes (SAT penetration depth); it is the overlap. Along an
  // axis across which both outlines have no width (two parallel line features, e.g. cans lying
  // side by side seen along their contact normal), there is no area to overlap: the outlines need
  // only meet within line_tolerance there.
  double depth = std::numeric_limits<double>::max();
  for (const Point2& ax : axes) {
    double lo_a = std::numeric_limits<double>::max(), hi_a = -lo_a, lo_b = lo_a, hi_b = -lo_a;
    for (const auto& p : pa) lo_a = std::min(lo_a, p.dot(ax)), hi_a = std::max(hi_a, p.dot(ax));
    for (const auto& p : pb) lo_b = std::min(lo_b, p.dot(ax)), hi_b = std::max(hi_b, p.dot(ax));
    const double d = std::min(hi_a - lo_b, hi_b - lo_a);
    if (std::max(hi_a - lo_a, hi_b - lo_b) < 1e-6) {
      if (d < -line_tolerance) return false;
    } else {
      depth = std::min(depth, d);
    }
  }
  return depth >= min_overlap;
}

namespace {

// The paper's contact tests between two posed objects, type by type (plane-plane first, then
// plane-curve, curve-curve, plane-edge: the first type that finds contacts gives them).
class ContactFinder {
 public:
  ContactFinder(const std::vector<PosedModel>& objects, const Eigen::Vector3d& gravity,
                const ContactConfig& cfg)
      : objects_(objects), up_(-gravity.normalized()), cfg_(cfg) {}

  std::vector<FeatureContact> find(int a, int b) {
    out_.clear();
    const auto planes_a = worldPlanes(objects_[a]), planes_b = worldPlanes(objects_[b]);
    const auto curves_a = worldCurves(objects_[a]), curves_b = worldCurves(objects_[b]);
    planePlane(planes_a, a, planes_b, b);
    if (!out_.empty()) return out_;
    planeCurve(planes_a, a, curves_b, b);
    planeCurve(planes_b, b, curves_a, a);
    if (!out_.empty()) return out_;
    curveCurve(curves_a, a, curves_b, b);
    if (!out_.empty()) return out_;
    planeEdge(planes_a, a, b);
    planeEdge(planes_b, b, a);
    return out_;
  }

 private:
  // A distance term within the thresholds: a small gap or an interpenetration of estimates.
  bool near(double dist, double eps) const { return dist < eps && dist > -cfg_.max_penetration_m; }

  // Makes a candidate between objects i and j (normal from i to j), applies the support and
  // projection checks, and keeps it. Returns whether it was kept.
  bool accept(int i, int j, ContactType type, FeatureRef fi, FeatureRef fj,
              const Eigen::Vector3d& normal, double dir, double dist,
              const std::vector<Eigen::Vector3d>& outline_i,
              const std::vector<Eigen::Vector3d>& outline_j) {
    FeatureContact c;
    c.object_a = i;
    c.object_b = j;
    c.type = type;
    c.feature_a = fi;
    c.feature_b = fj;
    c.normal = normal;
    c.direction_residual = dir;
    c.distance_residual = dist;
    const double vertical = c.normal.dot(up_);
    const bool side = std::abs(vertical) < std::sin(cfg_.side_max_tilt_deg * M_PI / 180.0);
    c.kind = std::abs(vertical) > cfg_.eps_g ? ContactKind::kSupport
             : side                          ? ContactKind::kSide
                                             : ContactKind::kLeaning;
    if (cfg_.support_only && !c.support()) return false;
    // Project along gravity for support contacts (the paper), along the normal otherwise.
    const Eigen::Vector3d along = c.support() ? up_ : c.normal;
    if (!projectionsOverlap(outline_i, outline_j, along, cfg_.min_overlap_m, cfg_.line_tolerance_m))
      return false;
    if (c.support() && vertical < 0) {  // the supporter comes first
      std::swap(c.object_a, c.object_b);
      std::swap(c.feature_a, c.feature_b);
      c.normal = -c.normal;
    }
    out_.push_back(c);
    return true;
  }

  void planePlane(const std::vector<WorldPlane>& planes_a, int a,
                  const std::vector<WorldPlane>& planes_b, int b) {
    for (std::size_t u = 0; u < planes_a.size(); ++u) {
      for (std::size_t v = 0; v < planes_b.size(); ++v) {
        const WorldPlane &pu = planes_a[u], &pv = planes_b[v];
        const double dir = std::abs(pu.normal.dot(pv.normal) + 1.0);
        const double dist = pu.normal.dot(pv.center - pu.center);
        if (dir >= cfg_.eps_n_pp || !near(dist, cfg_.eps_c_pp)) continue;
        accept(a, b, ContactType::kPlanePlane, {true, static_cast<int>(u)},
               {true, static_cast<int>(v)}, pu.normal, dir, dist, pu.boundary, pv.boundary);
      }
    }
  }

  void planeCurve(const std::vector<WorldPlane>& planes, int plane_obj,
                  const std::vector<WorldCurve>& curves, int curve_obj) {
    for (std::size_t u = 0; u < planes.size(); ++u) {
      for (std::size_t v = 0; v < curves.size(); ++v) {
        const WorldPlane& p = planes[u];
        const WorldCurve& k = curves[v];
        const double dir = std::abs(p.normal.dot(k.axis));
        const double dist = p.normal.dot(k.center - p.center) - k.radius;
        if (dir >= cfg_.eps_n_pc || !near(dist, cfg_.eps_c_pc)) continue;
        accept(plane_obj, curve_obj, ContactType::kPlaneCurve, {true, static_cast<int>(u)},
               {false, static_cast<int>(v)}, p.normal, dir, dist, p.boundary, {k.end_a, k.end_b});
      }
    }
  }

  void curveCurve(const std::vector<WorldCurve>& curves_a, int a,
                  const std::vector<WorldCurve>& curves_b, int b) {
    for (std::size_t u = 0; u < curves_a.size(); ++u) {
      for (std::size_t v = 0; v < curves_b.size(); ++v) {
        const WorldCurve &cu = curves_a[u], &cv = curves_b[v];
        const Eigen::Vector3d d = cv.center - cu.center;
        Eigen::Vector3d n = cu.axis.cross(cv.axis);
        if (n.norm() > 0.1) {
          n.normalize();
        } else {  // (nearly) parallel axes: the perpendicular from one axis to the other
          n = d - d.dot(cu.axis) * cu.axis;
          if (n.norm() < 1e-9) continue;
          n.normalize();
        }
        if (n.dot(d) < 0) n = -n;
        const double dist = n.dot(d) - (cu.radius + cv.radius);
        if (!near(dist, cfg_.eps_c_cc)) continue;
        accept(a, b, ContactType::kCurveCurve, {false, static_cast<int>(u)},
               {false, static_cast<int>(v)}, n, 0.0, dist, {cu.end_a, cu.end_b},
               {cv.end_a, cv.end_b});
      }
    }
  }

  // A plane against the other hull's nearest points (an edge or a corner), which must lie within
  // the plane's outline.
  void planeEdge(const std::vector<WorldPlane>& planes, int plane_obj, int edge_obj) {
    const PosedModel& edge_model = objects_[static_cast<std::size_t>(edge_obj)];
    for (std::size_t u = 0; u < planes.size(); ++u) {
      const WorldPlane& p = planes[u];
      double dist = 0.0;
      const std::vector<Eigen::Vector3d> touching =
          nearestHullPoints(edge_model, p.center, p.normal, cfg_.edge_tolerance_m, &dist);
      if (touching.empty() || !near(dist, cfg_.eps_c_pe)) continue;
      std::vector<Eigen::Vector3d> world;
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      for (const auto& t : touching) world.push_back(edge_model.T_world_obj * t), mean += t;
      if (!accept(plane_obj, edge_obj, ContactType::kPlaneEdge, {true, static_cast<int>(u)},
                  {false, -1}, p.normal, 0.0, dist, p.boundary, world))
        continue;
      // Their centroid, moved along the normal to the nearest one's level: on the plane when
      // the contact holds (the centroid of a polygonal rim lies inside it).
      const Eigen::Vector3d n_model = edge_model.T_world_obj.linear().transpose() * p.normal;
      const Eigen::Vector3d centroid = mean / static_cast<double>(touching.size());
      double level = std::numeric_limits<double>::max();
      for (const auto& t : touching) level = std::min(level, n_model.dot(t));
      out_.back().edge_point = centroid + n_model * (level - n_model.dot(centroid));
    }
  }

  const std::vector<PosedModel>& objects_;
  const Eigen::Vector3d up_;
  const ContactConfig& cfg_;
  std::vector<FeatureContact> out_;
};

}  // namespace

std::vector<FeatureContact> findContacts(const std::vector<PosedModel>& objects, int a, int b,
                                         const Eigen::Vector3d& gravity, const ContactConfig& cfg) {
  const int n = static_cast<int>(objects.size());
  if (a == b || a < 0 || b < 0 || a >= n || b >= n || !objects[a].model || !objects[b].model)
    return {};
  return ContactFinder(objects, gravity, cfg).find(a, b);
}

std::vector<FeatureContact> findAllContacts(const std::vector<PosedModel>& objects,
                                            const Eigen::Vector3d& gravity,
                                            const ContactConfig& config,
                                            const std::vector<ObjectPair>& held) {
  const ContactConfig held_config = heldContactConfig(config);
  std::vector<Eigen::Vector3d> centre(objects.size());
  std::vector<double> radius(objects.size(), 0.0);
  for (std::size_t i = 0; i < objects.size(); ++i) {
    if (!objects[i].model) continue;
    const Eigen::AlignedBox3f box = boxOf(*objects[i].model);
    centre[i] = objects[i].T_world_obj * box.center().cast<double>();
    radius[i] = 0.5 * static_cast<double>(box.diagonal().norm());
  }
  std::vector<FeatureContact> out;
  const double reach = std::max(
      {held_config.eps_c_pp, held_config.eps_c_pc, held_config.eps_c_cc, held_config.eps_c_pe});
  for (std::size_t i = 0; i < objects.size(); ++i) {
    for (std::size_t j = i + 1; j < objects.size(); ++j) {
      if (!objects[i].model || !objects[j].model) continue;
      if ((centre[i] - centre[j]).norm() > radius[i] + radius[j] + reach) continue;
      const bool was_held =
          std::find(held.begin(), held.end(),
                    ObjectPair(static_cast<int>(i), static_cast<int>(j))) != held.end();
      auto c = findContacts(objects, static_cast<int>(i), static_cast<int>(j), gravity, config);
      if (c.empty() && was_held) {
        c = findContacts(objects, static_cast<int>(i), static_cast<int>(j), gravity, held_config);
        for (FeatureContact& h : c) h.held = true;
      }
      out.insert(out.end(), c.begin(), c.end());
    }
  }
  markLeaning(objects, &out);
  return out;
}

void markLeaning(const std::vector<PosedModel>& objects, std::vector<FeatureContact>* contacts) {
  constexpr double kRound = 0.005;  // a curve of this radius or more is a round side, not an edge
  auto radius = [&](int object, const FeatureRef& f) {
    if (object < 0 || f.plane || f.index < 0) return 0.0;
    const auto& curves = objects[static_cast<std::size_t>(object)].model->features.curves;
    return f.index < static_cast<int>(curves.size())
               ? curves[static_cast<std::size_t>(f.index)].radius_m
               : 0.0;
  };
  std::vector<char> stable(objects.size(), 0);
  for (const FeatureContact& c : *contacts) {
    if (!c.support() || c.object_b < 0) continue;
    const bool on_own_face_or_side =
        c.type == ContactType::kPlanePlane ||
        (c.type == ContactType::kPlaneCurve && !c.feature_b.plane &&
         radius(c.object_b, c.feature_b) >= kRound) ||
        (c.type == ContactType::kCurveCurve && radius(c.object_b, c.feature_b) >= kRound &&
         radius(c.object_a, c.feature_a) >= kRound);
    if (on_own_face_or_side) stable[static_cast<std::size_t>(c.object_b)] = 1;
  }
  auto tipped = [&](int i) { return i >= 0 && !stable[static_cast<std::size_t>(i)]; };
  for (FeatureContact& c : *contacts) {
    if (c.kind == ContactKind::kSide && (tipped(c.object_a) || tipped(c.object_b)))
      c.kind = ContactKind::kLeaning;
  }
}

std::vector<FeatureContact> onePerPairAndType(const std::vector<FeatureContact>& contacts) {
  std::vector<FeatureContact> out;
  for (const FeatureContact& c : contacts) {
    const auto same = std::find_if(out.begin(), out.end(), [&](const FeatureContact& o) {
      return o.type == c.type &&
             std::min(o.object_a, o.object_b) == std::min(c.object_a, c.object_b) &&
             std::max(o.object_a, o.object_b) == std::max(c.object_a, c.object_b);
    });
    if (same == out.end())
      out.push_back(c);
    else if (std::abs(c.distance_residual) < std::abs(same->distance_residual))
      *same = c;
  }
  return out;
}

}  // namespace geofusion
