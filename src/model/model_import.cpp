#include "geofusion/model/model_import.h"

#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_types.h>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <map>
#include <sstream>
#include <tuple>

namespace geofusion {

UnitsCheck checkUnits(const TriangleMesh& mesh, double min_object_m, double max_object_m) {
  UnitsCheck check;
  check.largest_extent = static_cast<double>(mesh.extents().maxCoeff());
  std::ostringstream why;
  if (check.largest_extent > max_object_m && check.largest_extent * 1e-3 >= min_object_m) {
    check.scale = 1e-3;
    why << "largest extent " << check.largest_extent << " is more than " << max_object_m
        << " m: read as millimetres, scaled by 0.001 to " << check.largest_extent * 1e-3 << " m";
  } else if (check.largest_extent > max_object_m) {
    why << "largest extent " << check.largest_extent
        << " is implausible in metres and in millimetres: check the file's units";
  } else if (check.largest_extent < min_object_m) {
    why << "largest extent " << check.largest_extent << " m is below " << min_object_m
        << " m: check the file's units";
  }
  check.message = why.str();
  return check;
}

namespace {

// Vertex indices after welding vertices at the same position (within `tolerance`).
std::vector<int> weldedIndices(const TriangleMesh& mesh, double tolerance) {
  std::map<std::tuple<long, long, long>, int> cells;
  std::vector<int> index(mesh.vertices.size());
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    const Eigen::Vector3d v = mesh.vertices[i].cast<double>() / tolerance;
    const auto key = std::make_tuple(std::lround(v.x()), std::lround(v.y()), std::lround(v.z()));
    index[i] = cells.emplace(key, static_cast<int>(cells.size())).first->second;
  }
  return index;
}

}  // namespace

WatertightCheck checkWatertight(const TriangleMesh& mesh) {
  const double tolerance = std::max(1e-7, 1e-5 * static_cast<double>(mesh.extents().norm()));
  const std::vector<int> welded = weldedIndices(mesh, tolerance);
  std::map<std::pair<int, int>, std::pair<int, int>> uses;  // edge -> (uses a->b, uses b->a)
  WatertightCheck check;
  for (const auto& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      const int a = welded[t[k]], b = welded[t[(k + 1) % 3]];
      if (a == b) continue;
      auto& use = uses[std::minmax(a, b)];
      ++(a < b ? use.first : use.second);
    }
    const Eigen::Vector3d p0 = mesh.vertices[t[0]].cast<double>(),
                          p1 = mesh.vertices[t[1]].cast<double>(),
                          p2 = mesh.vertices[t[2]].cast<double>();
    check.signed_volume_m3 += p0.dot(p1.cross(p2)) / 6.0;
  }
  check.edges = uses.size();
  for (const auto& [edge, use] : uses) {
    const int n = use.first + use.second;
    if (n == 1) ++check.boundary_edges;
    if (n > 2) ++check.non_manifold_edges;
    if (n == 2 && use.first != 1) ++check.misoriented_edges;
  }
  return check;
}

namespace {

// Texture colours (RGB in [0, 1]) at texture coordinates (OBJ convention: v up).
std::vector<Eigen::Vector3f> colours(const cv::Mat& texture,
                                     const std::vector<Eigen::Vector2f>& uvs) {
  std::vector<Eigen::Vector3f> out;
  out.reserve(uvs.size());
  for (const auto& uv : uvs) {
    const float u = uv.x() - std::floor(uv.x()), v = uv.y() - std::floor(uv.y());
    const int col = std::clamp(static_cast<int>(u * texture.cols), 0, texture.cols - 1);
    const int row = std::clamp(static_cast<int>((1.f - v) * texture.rows), 0, texture.rows - 1);
    const cv::Vec3b bgr = texture.at<cv::Vec3b>(row, col);
    out.emplace_back(bgr[2] / 255.f, bgr[1] / 255.f, bgr[0] / 255.f);
  }
  return out;
}

// The mesh's surface as dense samples with normals, to measure how far a rotation moves sparse
// samples off it.
class SurfaceDistance {
 public:
  SurfaceDistance(const TriangleMesh& mesh, const SymmetryDetectionConfig& config)
      : config_(config) {
    std::vector<Eigen::Vector3f> normals;
    std::vector<Eigen::Vector2f> dense_uvs, query_uvs;
    const auto dense = sampleSurfacePoints(mesh, 10 * config.samples, 7, &normals, &dense_uvs);
    cloud_.reset(new pcl::PointCloud<pcl::PointXYZ>);
    for (const auto& p : dense) cloud_->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
    normals_ = std::move(normals);
    tree_.setInputCloud(cloud_);
    queries_ = sampleSurfacePoints(mesh, config.samples, 11, nullptr, &query_uvs);
    if (!mesh.texture_path.empty() && !dense_uvs.empty()) {
      const cv::Mat texture = cv::imread(mesh.texture_path, cv::IMREAD_COLOR);
      if (!texture.empty()) {
        dense_colours_ = colours(texture, dense_uvs);
        query_colours_ = colours(texture, query_uvs);
      }
    }
    const double diagonal = static_cast<double>(mesh.extents().norm());
    Eigen::Vector3f lo, hi;
    mesh.bounds(&lo, &hi);
    centre_ = 0.5f * (lo + hi);
    tolerance_m_ = std::max(config.min_tolerance_m, config.tolerance_fraction * diagonal);
    spacing_m_ = std::sqrt(mesh.surfaceArea() / static_cast<double>(dense.size()));
  }

  double tolerance() const { return tolerance_m_; }
  bool textured() const { return !query_colours_.empty(); }
  const Eigen::Vector3f& centre() const { return centre_; }
  const std::vector<Eigen::Vector3f>& queries() const { return queries_; }

  // The configured quantile of the distances from the rotated samples to the surface: to the
  // tangent plane of the nearest dense sample when it is within a few sample spacings (no
  // sampling noise on smooth parts), else to the sample itself.
  double after(const Eigen::Matrix3f& R, double* colour_mismatch = nullptr) const {
    std::size_t mismatched = 0;
    const Eigen::Vector3f shift = centre_ - R * centre_;
    std::vector<double> d;
    d.reserve(queries_.size());
    std::vector<int> index(1);
    std::vector<float> squared(1);
    for (const auto& q : queries_) {
      const Eigen::Vector3f x = R * q + shift;
      if (tree_.nearestKSearch(pcl::PointXYZ(x.x(), x.y(), x.z()), 1, index, squared) < 1) {
        d.push_back(1e9);
        continue;
      }
      const double point = std::sqrt(static_cast<double>(squared[0]));
      const auto& p = (*cloud_)[static_cast<std::size_t>(index[0])];
      const double plane = std::abs(static_cast<double>(
          normals_[static_cast<std::size_t>(index[0])].dot(x - Eigen::Vector3f(p.x, p.y, p.z))));
      d.push_back(point < 3.0 * spacing_m_ ? plane : point);
      if (textured()) {
        const Eigen::Vector3f diff =
            query_colours_[d.size() - 1] - dense_colours_[static_cast<std::size_t>(index[0])];
        if (diff.cwiseAbs().maxCoeff() > 0.2f) ++mismatched;
      }
    }
    if (colour_mismatch)
      *colour_mismatch = textured() ? static_cast<double>(mismatched) / queries_.size() : 0.0;
    const std::size_t k =
        std::min(d.size() - 1, static_cast<std::size_t>(config_.quantile * (d.size() - 1)));
    std::nth_element(d.begin(), d.begin() + static_cast<long>(k), d.end());
    return d[k];
  }

 private:
  SymmetryDetectionConfig config_;
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud_;
  std::vector<Eigen::Vector3f> normals_;
  pcl::KdTreeFLANN<pcl::PointXYZ> tree_;
  std::vector<Eigen::Vector3f> queries_;
  double tolerance_m_ = 0.0;
  double spacing_m_ = 0.0;
  std::vector<Eigen::Vector3f> dense_colours_, query_colours_;  // RGB in [0, 1]
  Eigen::Vector3f centre_ = Eigen::Vector3f::Zero();
};

// The model frame's axes, then the surface's principal axes that are well defined (their
// eigenvalue apart from the others), without repeats.
std::vector<Eigen::Vector3d> candidateAxes(const std::vector<Eigen::Vector3f>& points) {
  std::vector<Eigen::Vector3d> axes{Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(),
                                    Eigen::Vector3d::UnitZ()};
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(scatterMatrix(points));
  const Eigen::Vector3d values = eig.eigenvalues();
  for (int i = 0; i < 3; ++i) {
    bool distinct = true;
    for (int j = 0; j < 3; ++j)
      if (j != i && std::abs(values[i] - values[j]) < 0.05 * values.maxCoeff()) distinct = false;
    if (!distinct) continue;
    const Eigen::Vector3d a = eig.eigenvectors().col(i).normalized();
    const bool repeated = std::any_of(axes.begin(), axes.end(), [&](const Eigen::Vector3d& b) {
      return std::abs(a.dot(b)) > std::cos(5.0 * M_PI / 180.0);
    });
    if (!repeated) axes.push_back(a);
  }
  return axes;
}

SymmetryTrial trial(const SurfaceDistance& surface, const Eigen::Vector3d& axis, double angle_deg,
                    bool discrete, const SymmetryDetectionConfig& config) {
  SymmetryTrial t;
  t.discrete = discrete;
  t.max_colour_mismatch = config.max_colour_mismatch;
  t.axis = axis;
  t.angle_deg = angle_deg;
  t.tolerance_m = surface.tolerance();
  t.distance_m = surface.after(
      Eigen::AngleAxisf(static_cast<float>(angle_deg * M_PI / 180.0), axis.cast<float>())
          .toRotationMatrix(),
      &t.colour_mismatch);
  return t;
}

}  // namespace

// The largest distance from the model origin to an axis of the symmetry through `centre`.
double axisOffset(const Symmetry& symmetry, const Eigen::Vector3d& centre) {
  std::vector<Eigen::Vector3d> axes;
  if (symmetry.type == Symmetry::Type::kContinuous) axes.push_back(symmetry.axis);
  for (const auto& q : symmetry.rotations) axes.push_back(Eigen::AngleAxisd(q).axis());
  double offset = 0.0;
  for (const auto& a : axes)
    offset = std::max(offset, (centre - centre.dot(a.normalized()) * a.normalized()).norm());
  return offset;
}

SymmetryDetection detectSymmetry(const TriangleMesh& mesh, const SymmetryDetectionConfig& config) {
  SymmetryDetection out;
  if (mesh.empty()) return out;
  const SurfaceDistance surface(mesh, config);
  out.centre = surface.centre().cast<double>();
  out.tolerance_m = surface.tolerance();
  surface.after(Eigen::Matrix3f::Identity(), &out.colour_baseline);
  const auto tried = [&](const SymmetryTrial& t) {
    out.trials.push_back(t);
    return t.maps_onto_itself();
  };
  const std::vector<Eigen::Vector3d> axes = candidateAxes(surface.queries());
  // Continuous: every test angle about the axis maps the surface onto itself.
  for (const auto& axis : axes) {
    bool all = true;
    for (double angle : config.continuous_angles_deg)
      all = tried(trial(surface, axis, angle, false, config)) && all;
    if (all) {
      out.symmetry.type = Symmetry::Type::kContinuous;
      out.symmetry.axis = axis;
      out.axis_offset_m = axisOffset(out.symmetry, out.centre);
      return out;
    }
  }
  // Discrete: per axis the largest order n whose rotations (every multiple of 360/n) all pass.
  Symmetry found;
  found.type = Symmetry::Type::kDiscrete;
  for (const auto& axis : axes) {
    for (int n = config.max_order; n >= 2; --n) {
      bool all = true;
      for (int k = 1; k < n && all; ++k)
        all = tried(trial(surface, axis, 360.0 * k / n, true, config));
      if (!all) continue;
      for (int k = 1; k < n; ++k) {
        const Eigen::Quaterniond q(Eigen::AngleAxisd(2.0 * M_PI * k / n, axis));
        const bool known = std::any_of(
            found.rotations.begin(), found.rotations.end(),
            [&](const Eigen::Quaterniond& r) { return r.angularDistance(q) < 3.0 * M_PI / 180.0; });
        if (!known) found.rotations.push_back(q);
      }
      break;
    }
  }
  if (!found.rotations.empty()) out.symmetry = found;
  out.axis_offset_m = axisOffset(out.symmetry, out.centre);
  return out;
}

namespace {

// The group the rotations generate (closed under composition), at most `limit` elements.
std::vector<Eigen::Quaterniond> closure(const std::vector<Eigen::Quaterniond>& generators,
                                        double tolerance_rad, std::size_t limit = 128) {
  std::vector<Eigen::Quaterniond> group{Eigen::Quaterniond::Identity()};
  const auto has = [&](const Eigen::Quaterniond& q) {
    return std::any_of(group.begin(), group.end(), [&](const Eigen::Quaterniond& g) {
      return g.angularDistance(q) < tolerance_rad;
    });
  };
  for (std::size_t i = 0; i < group.size() && group.size() < limit; ++i) {
    for (const auto& g : generators) {
      const Eigen::Quaterniond q = (group[i] * g).normalized();
      if (!has(q)) group.push_back(q);
    }
  }
  return group;
}

}  // namespace

bool sameSymmetry(const Symmetry& a, const Symmetry& b, double angle_tolerance_deg) {
  const double tolerance = angle_tolerance_deg * M_PI / 180.0;
  if (a.type != b.type) return false;
  if (a.type == Symmetry::Type::kNone) return true;
  if (a.type == Symmetry::Type::kContinuous)
    return std::abs(a.axis.normalized().dot(b.axis.normalized())) > std::cos(tolerance);
  const auto ga = closure(a.rotations, tolerance), gb = closure(b.rotations, tolerance);
  if (ga.size() != gb.size()) return false;
  for (const auto& q : ga) {
    const bool in_b = std::any_of(gb.begin(), gb.end(), [&](const Eigen::Quaterniond& r) {
      return r.angularDistance(q) < tolerance;
    });
    if (!in_b) return false;
  }
  return true;
}

namespace {

std::string vectorText(const Eigen::Vector3d& v) {
  std::ostringstream s;
  s << "[";
  for (int i = 0; i < 3; ++i) {
    const double x = std::abs(v[i]) < 5e-7 ? 0.0 : v[i];
    s << (i ? ", " : "") << std::setprecision(6) << x;
  }
  s << "]";
  return s.str();
}

// Axis and angle (0..360 degrees) of a rotation, the axis pointing to the positive side.
std::pair<Eigen::Vector3d, double> axisAngle(const Eigen::Quaterniond& q) {
  const Eigen::AngleAxisd aa(q);
  Eigen::Vector3d axis = aa.axis();
  double angle = aa.angle() * 180.0 / M_PI;
  int lead = 0;
  axis.cwiseAbs().maxCoeff(&lead);
  if (axis[lead] < 0) {
    axis = -axis;
    angle = 360.0 - angle;
  }
  return {axis, std::round(angle * 1000.0) / 1000.0};
}

std::string symmetryYaml(const Symmetry& s) {
  std::ostringstream out;
  if (s.type == Symmetry::Type::kNone) return "none";
  if (s.type == Symmetry::Type::kContinuous)
    return "{type: continuous, axis: " + vectorText(s.axis) + "}";
  out << "{type: discrete, rotations: [";
  for (std::size_t i = 0; i < s.rotations.size(); ++i) {
    const auto [axis, angle] = axisAngle(s.rotations[i]);
    out << (i ? ", " : "") << "{axis: " << vectorText(axis) << ", angle_deg: " << angle << "}";
  }
  out << "]}";
  return out.str();
}

}  // namespace

std::string describe(const Symmetry& s) {
  if (s.type == Symmetry::Type::kNone) return "none";
  if (s.type == Symmetry::Type::kContinuous) return "continuous about " + vectorText(s.axis);
  std::ostringstream out;
  out << "discrete:";
  for (std::size_t i = 0; i < s.rotations.size(); ++i) {
    const auto [axis, angle] = axisAngle(s.rotations[i]);
    out << (i ? "," : "") << " " << angle << " deg about " << vectorText(axis);
  }
  return out.str();
}

std::string modelSetYaml(const std::string& set_name, const std::vector<ModelSetEntry>& entries) {
  std::ostringstream out;
  out << "# Model set written by make_model_set (format: docs/model_sets.md). Symmetries were "
         "found\n"
         "# numerically on the meshes and surface features extracted from their convex hulls;\n"
         "# check them in the previews before use.\n";
  out << "name: " << set_name << "\nclasses:\n";
  for (const auto& e : entries) {
    for (const auto& note : e.notes) out << "  # " << note << "\n";
    out << "  - name: " << e.name << "\n    id: " << e.id << "\n    mesh: " << e.mesh << "\n";
    if (e.scale != 1.0) out << "    scale: " << e.scale << "\n";
    out << "    symmetry: " << symmetryYaml(e.symmetry) << "\n";
    out << "    features:\n      planes:";
    if (e.features.planes.empty()) out << " []";
    out << "\n";
    for (const auto& p : e.features.planes) {
      out << "        - {center: " << vectorText(p.center) << ", normal: " << vectorText(p.normal)
          << ", boundary: [";
      for (std::size_t i = 0; i < p.boundary.size(); ++i)
        out << (i ? ", " : "") << vectorText(p.boundary[i]);
      out << "]}\n";
    }
    out << "      curves:";
    if (e.features.curves.empty()) out << " []";
    out << "\n";
    for (const auto& c : e.features.curves) {
      out << "        - {end_a: " << vectorText(c.end_a) << ", end_b: " << vectorText(c.end_b)
          << ", radius: " << std::setprecision(6) << c.radius_m << "}\n";
    }
  }
  return out.str();
}

}  // namespace geofusion
