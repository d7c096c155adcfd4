#include "geofusion/model/surface_features.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>

namespace geofusion {

namespace {

constexpr double kDeg = M_PI / 180.0;

struct Facet {
  Eigen::Vector3d normal;
  Eigen::Vector3d centroid;
  double area = 0.0;
  int v[3];
  int plane = -1;
};

// Orders points lying on a plane as a convex polygon (angle around their centroid).
std::vector<Eigen::Vector3d> orderedBoundary(std::vector<Eigen::Vector3d> pts,
                                             const Eigen::Vector3d& normal) {
  if (pts.empty()) return pts;
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const auto& p : pts) c += p;
  c /= static_cast<double>(pts.size());
  const Eigen::Vector3d u = normal.unitOrthogonal();
  const Eigen::Vector3d w = normal.cross(u);
  std::sort(pts.begin(), pts.end(), [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return std::atan2((a - c).dot(w), (a - c).dot(u)) < std::atan2((b - c).dot(w), (b - c).dot(u));
  });
  return pts;
}

// Narrowest width of a set of in-plane points (minimum over directions of the extent).
double minWidth(const std::vector<Eigen::Vector3d>& pts, const Eigen::Vector3d& normal) {
  const Eigen::Vector3d u = normal.unitOrthogonal();
  const Eigen::Vector3d w = normal.cross(u);
  double best = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 90; ++k) {
    const double a = k * M_PI / 90.0;
    const Eigen::Vector3d d = std::cos(a) * u + std::sin(a) * w;
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const auto& p : pts) {
      lo = std::min(lo, p.dot(d));
      hi = std::max(hi, p.dot(d));
    }
    best = std::min(best, hi - lo);
  }
  return best;
}

// The hull's facets (outward, counter-clockwise), degenerate ones left out; their total area.
std::vector<Facet> hullFacets(const TriangleMesh& hull, const std::vector<Eigen::Vector3d>& hv,
                              double* total_area) {
  std::vector<Facet> facets;
  *total_area = 0.0;
  for (const auto& t : hull.triangles) {  // outward, counter-clockwise
    Facet f;
    f.v[0] = t[0];
    f.v[1] = t[1];
    f.v[2] = t[2];
    const Eigen::Vector3d a = hv[f.v[0]], b = hv[f.v[1]], c = hv[f.v[2]];
    const Eigen::Vector3d n = (b - a).cross(c - a);
    f.area = 0.5 * n.norm();
    if (f.area < 1e-12) continue;
    f.centroid = (a + b + c) / 3.0;
    f.normal = n.normalized();
    *total_area += f.area;
    facets.push_back(f);
  }
  return facets;
}

// Planes: greedy region growing from the largest unassigned facet; each facet gets its plane.
std::vector<PlaneFeature> growPlanes(std::vector<Facet>* facet_list,
                                     const std::vector<Eigen::Vector3d>& hv, double total_area,
                                     const SurfaceFeatureConfig& cfg) {
  std::vector<Facet>& facets = *facet_list;
  std::vector<PlaneFeature> planes;
  std::vector<std::size_t> order(facets.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return facets[a].area > facets[b].area; });
  const double cos_tol = std::cos(cfg.plane_angle_tolerance_deg * kDeg);
  int next_plane = 0;
  for (std::size_t seed : order) {
    if (facets[seed].plane >= 0) continue;
    const Eigen::Vector3d n0 = facets[seed].normal;
    const double d0 = n0.dot(facets[seed].centroid);
    std::vector<std::size_t> members;
    double area = 0.0;
    Eigen::Vector3d weighted_normal = Eigen::Vector3d::Zero(), weighted_center = weighted_normal;
    for (std::size_t i = 0; i < facets.size(); ++i) {
      const Facet& f = facets[i];
      if (f.plane >= 0 || f.normal.dot(n0) < cos_tol) continue;
      if (std::abs(n0.dot(f.centroid) - d0) > cfg.plane_distance_tolerance_m) continue;
      members.push_back(i);
      area += f.area;
      weighted_normal += f.area * f.normal;
      weighted_center += f.area * f.centroid;
    }
    if (area < cfg.min_plane_area_fraction * total_area) continue;
    PlaneFeature plane;
    plane.normal = weighted_normal.normalized();
    plane.center = weighted_center / area;
    plane.area_m2 = area;
    std::vector<int> vids;
    for (std::size_t i : members) vids.insert(vids.end(), facets[i].v, facets[i].v + 3);
    std::sort(vids.begin(), vids.end());
    vids.erase(std::unique(vids.begin(), vids.end()), vids.end());
    std::vector<Eigen::Vector3d> pts;
    for (int id : vids) {
      // Project onto the fitted plane so the boundary is exactly planar.
      pts.push_back(hv[id] - plane.normal.dot(hv[id] - plane.center) * plane.normal);
    }
    if (minWidth(pts, plane.normal) < cfg.min_plane_width_m) continue;
    plane.boundary = orderedBoundary(pts, plane.normal);
    for (std::size_t i : members) facets[i].plane = next_plane;
    ++next_plane;
    planes.push_back(std::move(plane));
  }
  return planes;
}

// Cylinder sides: two opposite planes (the caps) and the rest of the hull wrapping their axis.
std::vector<CurvedFeature> cylinderSides(const std::vector<Facet>& facets,
                                         const std::vector<Eigen::Vector3d>& hv,
                                         const std::vector<PlaneFeature>& planes, double total_area,
                                         const SurfaceFeatureConfig& cfg) {
  std::vector<CurvedFeature> sides;
  double rest_area = 0.0;
  for (const Facet& f : facets) rest_area += f.plane < 0 ? f.area : 0.0;
  if (rest_area >= cfg.min_curved_area_fraction * total_area) {
    const double max_axis_cos = std::sin(cfg.curved_normal_tolerance_deg * kDeg);
    for (std::size_t i = 0; i < planes.size(); ++i) {
      for (std::size_t j = i + 1; j < planes.size(); ++j) {
        const PlaneFeature &p = planes[i], &q = planes[j];
        if (p.normal.dot(q.normal) > -std::cos(5.0 * kDeg)) continue;
        const Eigen::Vector3d axis = (q.normal - p.normal).normalized();
        // Most of the remaining area must face sideways (rims and lips may not).
        double side_area = 0.0, rest = 0.0;
        std::vector<double> radii;
        const Eigen::Vector3d mid = 0.5 * (p.center + q.center);
        for (const Facet& f : facets) {
          if (f.plane >= 0) continue;
          rest += f.area;
          if (std::abs(f.normal.dot(axis)) > max_axis_cos) continue;
          side_area += f.area;
          for (int k = 0; k < 3; ++k) {
            const Eigen::Vector3d r = hv[f.v[k]] - mid;
            radii.push_back((r - r.dot(axis) * axis).norm());
          }
        }
        const bool wraps = side_area >= cfg.min_side_share * rest;
        if (!wraps || radii.empty()) continue;
        const double mean = std::accumulate(radii.begin(), radii.end(), 0.0) / radii.size();
        double var = 0.0;
        for (double r : radii) var += (r - mean) * (r - mean);
        const double spread = std::sqrt(var / radii.size()) / mean;
        if (spread > cfg.max_radius_spread) continue;
        CurvedFeature side;
        side.axis = axis;
        side.center = mid;
        side.end_a = p.center;
        side.end_b = q.center;
        side.radius_m = mean;  // the side's hull vertices lie on its rim circles
        sides.push_back(side);
      }
    }
  }
  return sides;
}

// Edges: non-parallel planes meeting along a line (hull vertices close to both planes).
std::vector<CurvedFeature> planeEdges(const std::vector<Eigen::Vector3d>& hv,
                                      const std::vector<PlaneFeature>& planes,
                                      const SurfaceFeatureConfig& cfg) {
  std::vector<CurvedFeature> edges;
  const double min_edge_cos = std::cos(cfg.min_edge_angle_deg * kDeg);
  for (std::size_t i = 0; i < planes.size(); ++i) {
    for (std::size_t j = i + 1; j < planes.size(); ++j) {
      const PlaneFeature &p = planes[i], &q = planes[j];
      if (std::abs(p.normal.dot(q.normal)) > min_edge_cos) continue;
      std::vector<Eigen::Vector3d> on_both;
      for (const auto& v : hv) {
        if (std::abs(p.normal.dot(v - p.center)) < cfg.edge_distance_tolerance_m &&
            std::abs(q.normal.dot(v - q.center)) < cfg.edge_distance_tolerance_m) {
          on_both.push_back(v);
        }
      }
      if (on_both.size() < 2) continue;
      const Eigen::Vector3d dir = p.normal.cross(q.normal).normalized();
      // The point of the planes' common line closest to the vertices' centroid.
      Eigen::Vector3d c = Eigen::Vector3d::Zero();
      for (const auto& v : on_both) c += v;
      c /= static_cast<double>(on_both.size());
      Eigen::Matrix2d A;
      A << p.normal.dot(p.normal), p.normal.dot(q.normal), q.normal.dot(p.normal),
          q.normal.dot(q.normal);
      const Eigen::Vector2d b(p.normal.dot(p.center - c), q.normal.dot(q.center - c));
      const Eigen::Vector2d ab = A.inverse() * b;
      const Eigen::Vector3d on_line = c + ab[0] * p.normal + ab[1] * q.normal;
      double lo = std::numeric_limits<double>::infinity(), hi = -lo;
      for (const auto& v : on_both) {
        lo = std::min(lo, (v - on_line).dot(dir));
        hi = std::max(hi, (v - on_line).dot(dir));
      }
      if (hi - lo < cfg.min_edge_length_m) continue;
      CurvedFeature edge;
      edge.axis = dir;
      edge.end_a = on_line + lo * dir;
      edge.end_b = on_line + hi * dir;
      edge.center = 0.5 * (edge.end_a + edge.end_b);
      edge.radius_m = 0.0;
      edges.push_back(edge);
    }
  }
  return edges;
}

}  // namespace

SurfaceFeatures extractSurfaceFeatures(const std::vector<Eigen::Vector3f>& points,
                                       const SurfaceFeatureConfig& cfg) {
  SurfaceFeatures out;
  if (points.size() < 4) return out;
  const TriangleMesh hull = convexHull(points);
  if (hull.vertices.size() < 4 || hull.triangles.empty()) return out;
  std::vector<Eigen::Vector3d> hv;
  hv.reserve(hull.vertices.size());
  for (const auto& p : hull.vertices) hv.push_back(p.cast<double>());
  double total_area = 0.0;
  std::vector<Facet> facets = hullFacets(hull, hv, &total_area);
  out.planes = growPlanes(&facets, hv, total_area, cfg);
  out.curves = cylinderSides(facets, hv, out.planes, total_area, cfg);
  const std::vector<CurvedFeature> edges = planeEdges(hv, out.planes, cfg);
  out.curves.insert(out.curves.end(), edges.begin(), edges.end());
  return out;
}

SurfaceFeatures extractSurfaceFeatures(const TriangleMesh& mesh, const SurfaceFeatureConfig& cfg) {
  return extractSurfaceFeatures(mesh.vertices, cfg);
}

std::string describe(const SurfaceFeatures& f) {
  std::size_t edges = 0;
  for (const auto& c : f.curves) edges += c.radius_m == 0.0;
  std::ostringstream os;
  os << f.planes.size() << " planes, " << f.curves.size() << " curves (" << edges << " edges)";
  return os.str();
}

}  // namespace geofusion
