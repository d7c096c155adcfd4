#include "geofusion/model/mesh.h"

extern "C" {
#include <libqhull_r/qhull_ra.h>
}
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <assimp/Exporter.hpp>
#include <assimp/Importer.hpp>

#if GEOFUSION_HAVE_MESHOPTIMIZER
#include <meshoptimizer.h>
#endif

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <random>
#include <sstream>

namespace geofusion {

double TriangleMesh::surfaceArea() const {
  double area = 0.0;
  for (const auto& t : triangles) {
    const Eigen::Vector3f a = vertices[t[0]], b = vertices[t[1]], c = vertices[t[2]];
    area += 0.5 * static_cast<double>((b - a).cross(c - a).norm());
  }
  return area;
}

void TriangleMesh::bounds(Eigen::Vector3f* min, Eigen::Vector3f* max) const {
  *min = Eigen::Vector3f::Constant(std::numeric_limits<float>::max());
  *max = Eigen::Vector3f::Constant(-std::numeric_limits<float>::max());
  for (const auto& v : vertices) {
    *min = min->cwiseMin(v);
    *max = max->cwiseMax(v);
  }
}

Eigen::Vector3f TriangleMesh::extents() const {
  if (vertices.empty()) return Eigen::Vector3f::Zero();
  Eigen::Vector3f lo, hi;
  bounds(&lo, &hi);
  return hi - lo;
}

TriangleMesh makeBox(const Eigen::Vector3d& size) {
  TriangleMesh m;
  const Eigen::Vector3f h = (0.5 * size).cast<float>();
  // One quad (two triangles) per face, own vertices so each face can carry its own uvs.
  for (int axis = 0; axis < 3; ++axis) {
    for (int sign : {-1, 1}) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      const int base = static_cast<int>(m.vertices.size());
      const float corners[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
      for (const auto& c : corners) {
        Eigen::Vector3f p;
        p[axis] = sign * h[axis];
        p[u] = c[0] * h[u];
        p[v] = c[1] * h[v];
        m.vertices.push_back(p);
        m.uvs.emplace_back(0.5f * (c[0] + 1), 0.5f * (c[1] + 1));
      }
      // (u, v, axis) is right-handed: counter-clockwise in (u, v) faces +axis.
      if (sign > 0) {
        m.triangles.emplace_back(base, base + 1, base + 2);
        m.triangles.emplace_back(base, base + 2, base + 3);
      } else {
        m.triangles.emplace_back(base, base + 2, base + 1);
        m.triangles.emplace_back(base, base + 3, base + 2);
      }
    }
  }
  return m;
}

TriangleMesh makeCylinder(double radius, double height, int segments) {
  TriangleMesh m;
  segments = std::max(segments, 3);
  const float r = static_cast<float>(radius), hz = static_cast<float>(0.5 * height);
  for (int i = 0; i < segments; ++i) {
    const double a = 2.0 * M_PI * i / segments;
    const float x = r * static_cast<float>(std::cos(a)), y = r * static_cast<float>(std::sin(a));
    m.vertices.emplace_back(x, y, -hz);  // 2i
    m.vertices.emplace_back(x, y, hz);   // 2i + 1
    m.uvs.emplace_back(static_cast<float>(i) / segments, 0.f);
    m.uvs.emplace_back(static_cast<float>(i) / segments, 1.f);
  }
  const int bottom = static_cast<int>(m.vertices.size());
  m.vertices.emplace_back(0.f, 0.f, -hz);
  const int top = bottom + 1;
  m.vertices.emplace_back(0.f, 0.f, hz);
  m.uvs.emplace_back(0.5f, 0.5f);
  m.uvs.emplace_back(0.5f, 0.5f);
  for (int i = 0; i < segments; ++i) {
    const int j = (i + 1) % segments;
    const int b0 = 2 * i, t0 = 2 * i + 1, b1 = 2 * j, t1 = 2 * j + 1;
    m.triangles.emplace_back(b0, b1, t1);
    m.triangles.emplace_back(b0, t1, t0);
    m.triangles.emplace_back(bottom, b1, b0);
    m.triangles.emplace_back(top, t0, t1);
  }
  return m;
}

void scaleMesh(double scale, TriangleMesh* mesh) {
  for (auto& v : mesh->vertices) v *= static_cast<float>(scale);
}

bool saveMesh(const std::string& path, const TriangleMesh& mesh, const std::string& format,
              std::string* error) {
  if (mesh.empty()) {
    *error = "mesh for '" + path + "' has no triangles";
    return false;
  }
  // One mesh, one default material, one node: the scene owns (and frees) every array.
  aiScene scene;
  scene.mRootNode = new aiNode();
  scene.mRootNode->mMeshes = new unsigned int[1]{0};
  scene.mRootNode->mNumMeshes = 1;
  scene.mMaterials = new aiMaterial* [1] { new aiMaterial() };
  scene.mNumMaterials = 1;
  aiMesh* out = new aiMesh();
  scene.mMeshes = new aiMesh* [1] { out };
  scene.mNumMeshes = 1;
  out->mMaterialIndex = 0;
  out->mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
  out->mNumVertices = static_cast<unsigned int>(mesh.vertices.size());
  out->mVertices = new aiVector3D[mesh.vertices.size()];
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
    out->mVertices[i] =
        aiVector3D(mesh.vertices[i].x(), mesh.vertices[i].y(), mesh.vertices[i].z());
  out->mNumFaces = static_cast<unsigned int>(mesh.triangles.size());
  out->mFaces = new aiFace[mesh.triangles.size()];
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    aiFace& face = out->mFaces[f];
    face.mNumIndices = 3;
    face.mIndices = new unsigned int[3];
    for (int k = 0; k < 3; ++k) face.mIndices[k] = static_cast<unsigned int>(mesh.triangles[f][k]);
  }
  Assimp::Exporter exporter;
  if (exporter.Export(&scene, format, path) != AI_SUCCESS) {
    *error = "mesh file '" + path + "' could not be written (" + format +
             "): " + exporter.GetErrorString();
    return false;
  }
  return true;
}

bool loadMesh(const std::string& path, TriangleMesh* mesh, std::string* error) {
  std::ifstream probe(path);
  if (!probe) {
    *error = "mesh file '" + path + "' does not exist or cannot be read";
    return false;
  }
  Assimp::Importer importer;
  const aiScene* scene =
      importer.ReadFile(path, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                                  aiProcess_PreTransformVertices | aiProcess_FindInvalidData);
  if (!scene || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) || scene->mNumMeshes == 0) {
    *error = "mesh file '" + path + "' could not be parsed: " + importer.GetErrorString();
    return false;
  }
  TriangleMesh out;
  for (unsigned mi = 0; mi < scene->mNumMeshes; ++mi) {
    const aiMesh* am = scene->mMeshes[mi];
    const int base = static_cast<int>(out.vertices.size());
    for (unsigned v = 0; v < am->mNumVertices; ++v) {
      const aiVector3D& p = am->mVertices[v];
      out.vertices.emplace_back(p.x, p.y, p.z);
      if (am->HasTextureCoords(0)) {
        out.uvs.emplace_back(am->mTextureCoords[0][v].x, am->mTextureCoords[0][v].y);
      }
    }
    for (unsigned f = 0; f < am->mNumFaces; ++f) {
      const aiFace& face = am->mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines
      out.triangles.emplace_back(base + static_cast<int>(face.mIndices[0]),
                                 base + static_cast<int>(face.mIndices[1]),
                                 base + static_cast<int>(face.mIndices[2]));
    }
    if (out.texture_path.empty() && am->mMaterialIndex < scene->mNumMaterials) {
      aiString tex;
      if (scene->mMaterials[am->mMaterialIndex]->GetTexture(aiTextureType_DIFFUSE, 0, &tex) ==
          AI_SUCCESS) {
        const std::string dir = path.substr(0, path.find_last_of('/') + 1);
        // MTL files often carry trailing blanks after the file name (the YCB-Video ones do).
        std::string name = tex.C_Str();
        const auto first = name.find_first_not_of(" \t\r\n");
        const auto last = name.find_last_not_of(" \t\r\n");
        name = first == std::string::npos ? std::string() : name.substr(first, last - first + 1);
        if (!name.empty()) out.texture_path = dir + name;
      }
    }
  }
  if (out.uvs.size() != out.vertices.size()) out.uvs.clear();
  for (const auto& v : out.vertices) {
    if (!v.allFinite()) {
      *error = "mesh file '" + path + "' has non-finite vertex coordinates";
      return false;
    }
  }
  if (out.empty()) {
    *error = "mesh file '" + path + "' has no triangles";
    return false;
  }
  *mesh = std::move(out);
  return true;
}

namespace {

#if GEOFUSION_HAVE_MESHOPTIMIZER
// Edge collapses on the welded index buffer: the number of indices kept. meshoptimizer 0.16 and
// later take the error bound relative to meshopt_simplifyScale and report the error reached;
// 0.15 (Debian 11) takes the relative bound only, so the bound is what is reported there
// (docs/platforms.md).
std::size_t collapseEdges(unsigned int* destination, const unsigned int* welded,
                          std::size_t index_count, const Eigen::Vector3f* vertices,
                          std::size_t vertex_count, std::size_t target_index_count,
                          double max_error_m, double* achieved_error_m) {
  const float* positions = reinterpret_cast<const float*>(vertices);
#if GEOFUSION_MESHOPT_ERROR_OUTPUT
  const float scale = meshopt_simplifyScale(positions, vertex_count, sizeof(Eigen::Vector3f));
  float relative_error = 0.f;
  const std::size_t kept = meshopt_simplify(
      destination, welded, index_count, positions, vertex_count, sizeof(Eigen::Vector3f),
      target_index_count, static_cast<float>(max_error_m / std::max(scale, 1e-9f)), 0,
      &relative_error);
  if (achieved_error_m) *achieved_error_m = static_cast<double>(relative_error * scale);
#else
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::max());
  Eigen::Vector3f hi = -lo;
  for (std::size_t i = 0; i < vertex_count; ++i) {
    lo = lo.cwiseMin(vertices[i]);
    hi = hi.cwiseMax(vertices[i]);
  }
  const float scale = vertex_count > 0 ? (hi - lo).maxCoeff() : 0.f;  // as meshopt_simplifyScale
  const std::size_t kept = meshopt_simplify(
      destination, welded, index_count, positions, vertex_count, sizeof(Eigen::Vector3f),
      target_index_count, static_cast<float>(max_error_m / std::max(scale, 1e-9f)));
  if (achieved_error_m) *achieved_error_m = max_error_m;
#endif
  return kept;
}
#endif

}  // namespace

#if GEOFUSION_HAVE_MESHOPTIMIZER
TriangleMesh simplifyMesh(const TriangleMesh& mesh, std::size_t target_triangles,
                          double max_error_m, double* achieved_error_m) {
  if (achieved_error_m) *achieved_error_m = 0.0;
  if (mesh.empty()) return TriangleMesh();
  static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float), "packed vertices");
  static_assert(sizeof(Eigen::Vector3i) == 3 * sizeof(unsigned int), "packed triangles");
  const std::size_t index_count = mesh.triangles.size() * 3;
  const auto* indices = reinterpret_cast<const unsigned int*>(mesh.triangles.data());
  // Weld by position so texture seams do not become borders the simplifier must keep.
  std::vector<unsigned int> remap(mesh.vertices.size());
  const std::size_t unique =
      meshopt_generateVertexRemap(remap.data(), indices, index_count, mesh.vertices.data(),
                                  mesh.vertices.size(), sizeof(Eigen::Vector3f));
  TriangleMesh out;
  out.vertices.resize(unique);
  meshopt_remapVertexBuffer(out.vertices.data(), mesh.vertices.data(), mesh.vertices.size(),
                            sizeof(Eigen::Vector3f), remap.data());
  std::vector<unsigned int> welded(index_count);
  meshopt_remapIndexBuffer(welded.data(), indices, index_count, remap.data());

  std::vector<unsigned int> simplified(index_count);
  std::size_t kept = index_count;
  if (mesh.triangles.size() > target_triangles) {
    kept = collapseEdges(simplified.data(), welded.data(), index_count, out.vertices.data(), unique,
                         target_triangles * 3, max_error_m, achieved_error_m);
  } else {
    simplified = welded;
  }
  simplified.resize(kept);
  // Drop the vertices no triangle uses any more.
  const std::size_t used =
      meshopt_optimizeVertexFetch(out.vertices.data(), simplified.data(), kept, out.vertices.data(),
                                  unique, sizeof(Eigen::Vector3f));
  out.vertices.resize(used);
  out.triangles.resize(kept / 3);
  std::copy(simplified.begin(), simplified.end(),
            reinterpret_cast<unsigned int*>(out.triangles.data()));
  return out;
}
#else
// Without meshoptimizer (Ubuntu 20.04 packages none): the mesh is welded by position and kept
// whole, so rendering costs its full triangle count (docs/platforms.md has the figures).
TriangleMesh simplifyMesh(const TriangleMesh& mesh, std::size_t /*target_triangles*/,
                          double /*max_error_m*/, double* achieved_error_m) {
  if (achieved_error_m) *achieved_error_m = 0.0;
  TriangleMesh out;
  std::map<std::array<float, 3>, int> index_of;
  std::vector<int> remap(mesh.vertices.size(), -1);
  out.triangles.reserve(mesh.triangles.size());
  for (const Eigen::Vector3i& t : mesh.triangles) {
    Eigen::Vector3i welded;
    for (int k = 0; k < 3; ++k) {
      int& r = remap[static_cast<std::size_t>(t[k])];
      if (r < 0) {
        const Eigen::Vector3f& v = mesh.vertices[static_cast<std::size_t>(t[k])];
        const auto inserted =
            index_of.emplace(std::array<float, 3>{v.x(), v.y(), v.z()}, int(out.vertices.size()));
        if (inserted.second) out.vertices.push_back(v);
        r = inserted.first->second;
      }
      welded[k] = r;
    }
    out.triangles.push_back(welded);
  }
  return out;
}
#endif

double enclosedVolume(const TriangleMesh& mesh) {
  double six_v = 0.0;
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d a = mesh.vertices[t[0]].cast<double>(),
                          b = mesh.vertices[t[1]].cast<double>(),
                          c = mesh.vertices[t[2]].cast<double>();
    six_v += a.dot(b.cross(c));
  }
  return six_v / 6.0;
}

namespace {

// qhull's reentrant library called as PCL 1.13's ConvexHull calls it ("qhull " then
// qh_triangulate; vertices in qhull's order, each facet's in its own), so the hulls are those
// PCL gives on Debian 12. PCL itself is not used for this: Debian 11's PCL 1.11 crashes in
// ConvexHull (built against another qhull than it runs with; PCL pull request 4510).
bool qhullTriangles(const std::vector<Eigen::Vector3f>& points,
                    std::vector<Eigen::Vector3f>* vertices,
                    std::vector<std::array<int, 3>>* facets) {
  const int dimension = 3;
  auto* coords = static_cast<coordT*>(calloc(points.size() * dimension, sizeof(coordT)));
  if (!coords) return false;
  for (std::size_t i = 0; i < points.size(); ++i)
    for (int d = 0; d < dimension; ++d) coords[i * dimension + d] = points[i][d];
  qhT qh_qh;
  qhT* qh = &qh_qh;
  qh_zero(qh, stderr);
  char flags[] = "qhull ";
  // ismalloc True: qhull frees the coordinates.
  const int exitcode = qh_new_qhull(qh, dimension, static_cast<int>(points.size()), coords, True,
                                    flags, nullptr, stderr);
  if (exitcode == 0) {
    qh_triangulate(qh);
    std::map<unsigned int, int> index_of;  // qhull's vertex id -> our index
    vertexT* vertex;
    FORALLvertices {
      index_of[vertex->id] = static_cast<int>(vertices->size());
      vertices->push_back(points[static_cast<std::size_t>(qh_pointid(qh, vertex->point))]);
    }
    facetT* facet;
    FORALLfacets {
      std::array<int, 3> f{{-1, -1, -1}};
      int vertex_n, vertex_i;
      FOREACHvertex_i_(qh, facet->vertices) if (vertex_i < 3) f[vertex_i] = index_of[vertex->id];
      facets->push_back(f);
    }
  }
  qh_freeqhull(qh, !qh_ALL);
  int curlong, totlong;
  qh_memfreeshort(qh, &curlong, &totlong);
  return exitcode == 0;
}

}  // namespace

Eigen::Matrix3d scatterMatrix(const std::vector<Eigen::Vector3f>& points) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3f& p : points) mean += p.cast<double>();
  mean /= static_cast<double>(points.size());
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3f& p : points)
    scatter += (p.cast<double>() - mean) * (p.cast<double>() - mean).transpose();
  return scatter;
}

namespace {

/// Whether the points span a volume: a flat, collinear or coincident set has no 3-D hull, and
/// qhull, given one, prints an internal error (QH6421 or QH6154) on stderr before failing.
bool spansAVolume(const std::vector<Eigen::Vector3f>& points) {
  const Eigen::Matrix3d covariance = scatterMatrix(points);
  if (!covariance.allFinite()) return false;
  const Eigen::Vector3d spread =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(covariance, Eigen::EigenvaluesOnly)
          .eigenvalues();  // ascending
  return spread[2] > 0.0 && spread[0] > 1e-12 * spread[2];
}

}  // namespace

TriangleMesh convexHull(const std::vector<Eigen::Vector3f>& points) {
  TriangleMesh out;
  if (points.size() < 4 || !spansAVolume(points)) return out;
  std::vector<std::array<int, 3>> facets;
  if (!qhullTriangles(points, &out.vertices, &facets) || out.vertices.size() < 4 || facets.empty())
    return TriangleMesh();
  Eigen::Vector3f centroid = Eigen::Vector3f::Zero();
  for (const auto& v : out.vertices) centroid += v;
  centroid /= static_cast<float>(out.vertices.size());
  for (const auto& f : facets) {
    if (f[0] < 0 || f[1] < 0 || f[2] < 0) continue;
    Eigen::Vector3i t(f[0], f[1], f[2]);
    const Eigen::Vector3f a = out.vertices[t[0]], b = out.vertices[t[1]], c = out.vertices[t[2]];
    const Eigen::Vector3f n = (b - a).cross(c - a);
    if (n.squaredNorm() < 1e-24f) continue;
    if (n.dot((a + b + c) / 3.f - centroid) < 0.f) std::swap(t[1], t[2]);  // outward
    out.triangles.push_back(t);
  }
  return out;
}

std::vector<Eigen::Vector3f> sampleSurfacePoints(const TriangleMesh& mesh, std::size_t count,
                                                 std::uint32_t seed,
                                                 std::vector<Eigen::Vector3f>* normals,
                                                 std::vector<Eigen::Vector2f>* uvs) {
  if (normals) normals->clear();
  if (uvs) uvs->clear();
  std::vector<Eigen::Vector3f> out;
  if (mesh.empty() || count == 0) return out;
  std::vector<double> cumulative;
  cumulative.reserve(mesh.triangles.size());
  double total = 0.0;
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3f a = mesh.vertices[t[0]], b = mesh.vertices[t[1]], c = mesh.vertices[t[2]];
    total += 0.5 * static_cast<double>((b - a).cross(c - a).norm());
    cumulative.push_back(total);
  }
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  out.reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    const double pick = uni(rng) * total;
    const std::size_t ti = static_cast<std::size_t>(
        std::lower_bound(cumulative.begin(), cumulative.end(), pick) - cumulative.begin());
    const auto& t = mesh.triangles[std::min(ti, mesh.triangles.size() - 1)];
    double s = uni(rng), r = uni(rng);
    if (s + r > 1.0) {
      s = 1.0 - s;
      r = 1.0 - r;
    }
    const Eigen::Vector3f a = mesh.vertices[t[0]], b = mesh.vertices[t[1]], c = mesh.vertices[t[2]];
    out.push_back(a + static_cast<float>(s) * (b - a) + static_cast<float>(r) * (c - a));
    if (normals) normals->push_back((b - a).cross(c - a).normalized());
    if (uvs && mesh.uvs.size() == mesh.vertices.size()) {
      const Eigen::Vector2f ua = mesh.uvs[t[0]], ub = mesh.uvs[t[1]], uc = mesh.uvs[t[2]];
      uvs->push_back(ua + static_cast<float>(s) * (ub - ua) + static_cast<float>(r) * (uc - ua));
    }
  }
  return out;
}

bool loadPointsXyz(const std::string& path, std::vector<Eigen::Vector3f>* points,
                   std::string* error) {
  std::ifstream in(path);
  if (!in) {
    *error = "points file '" + path + "' does not exist or cannot be read";
    return false;
  }
  std::vector<Eigen::Vector3f> out;
  std::string line;
  std::size_t line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ls(line);
    float x, y, z;
    if (!(ls >> x >> y >> z) || !std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) {
      *error = "points file '" + path + "' line " + std::to_string(line_no) +
               " is not three finite numbers";
      return false;
    }
    out.emplace_back(x, y, z);
  }
  if (out.empty()) {
    *error = "points file '" + path + "' holds no points";
    return false;
  }
  *points = std::move(out);
  return true;
}

}  // namespace geofusion
