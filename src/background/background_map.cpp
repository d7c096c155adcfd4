#include "geofusion/background/background_map.h"

#include "geofusion/background/octree_update.h"

#include "geofusion/render/renderer.h"

#include "geofusion/common/atomic_file.h"

#include <octomap/OcTree.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>

namespace geofusion {

struct BackgroundMap::Impl {
  explicit Impl(double resolution) : tree(resolution) {}
  octomap::OcTree tree;
  std::shared_ptr<OffscreenRenderer> renderer;
  std::map<std::shared_ptr<const ObjectModel>, MeshHandle> meshes;
  RenderedImages rendered;
  bool inserted_any = false;                                     ///< since the last clear()
  Eigen::Isometry3d T_map_last = Eigen::Isometry3d::Identity();  ///< camera of the last insert
  int passed_over = 0;                                           ///< keyframes not wanted since it
  int insertions = 0;  ///< since the last clear(): picks the free-space rays' phase
};

BackgroundMap::BackgroundMap(const BackgroundMapConfig& config,
                             std::shared_ptr<OffscreenRenderer> renderer)
    : config_(config), impl_(std::make_unique<Impl>(config.resolution_m)) {
  impl_->renderer = renderer ? std::move(renderer) : std::make_shared<OffscreenRenderer>();
  if (config.region_half_extent_m > 0) {
    const float e = static_cast<float>(config.region_half_extent_m);
    const float h = static_cast<float>(0.99 * 32767 * config.resolution_m);  // the tree's reach
    octomap::point3d lo(-e, -e, -h), hi(e, e, h);
    impl_->tree.setBBXMin(lo);
    impl_->tree.setBBXMax(hi);
    impl_->tree.useBBXLimit(true);
  }
}

BackgroundMap::~BackgroundMap() = default;

void BackgroundMap::clear() {
  impl_->tree.clear();
  impl_->inserted_any = false;
  impl_->insertions = 0;
  impl_->passed_over = 0;
}

bool BackgroundMap::wanted(const Eigen::Isometry3d& T_map_cam) {
  if (impl_->inserted_any && impl_->passed_over + 1 < std::max(1, config_.max_interval_keyframes)) {
    const Eigen::Isometry3d delta = impl_->T_map_last.inverse() * T_map_cam;
    const double turned = Eigen::AngleAxisd(delta.rotation()).angle() * 180.0 / M_PI;
    if (delta.translation().norm() < config_.min_translation_m &&
        turned < config_.min_rotation_deg) {
      ++impl_->passed_over;
      return false;
    }
  }
  return true;
}

std::size_t BackgroundMap::numLeaves() const {
  return impl_->tree.getNumLeafNodes();
}

void BackgroundMap::prepare(const ModelSet& models) {
  for (const auto& model : models.models()) meshFor(model);
}

MeshHandle BackgroundMap::meshFor(const std::shared_ptr<const ObjectModel>& model) {
  auto it = impl_->meshes.find(model);
  if (it == impl_->meshes.end()) {
    // The mask needs the silhouette and the depth to within a voxel's fraction: a light mesh.
    const MeshHandle h = impl_->renderer->addMesh(simplifyMesh(
        model->mesh, static_cast<std::size_t>(std::max(1, config_.mask_mesh_triangles)),
        0.25 * config_.resolution_m));
    it = impl_->meshes.emplace(model, h).first;  // -1 remembered: a bad mesh is tried once
  }
  return it->second;
}

namespace {

// Grows a mask by `m` cells in both directions (a square structuring element), two passes.
void dilate(std::vector<char>* mask, int w, int h, int m) {
  if (m <= 0) return;
  std::vector<char> rows(mask->size(), 0);
  for (int v = 0; v < h; ++v) {
    const char* in = mask->data() + static_cast<std::size_t>(v) * w;
    char* out = rows.data() + static_cast<std::size_t>(v) * w;
    for (int u = 0; u < w; ++u) {
      if (!in[u]) continue;
      for (int k = std::max(0, u - m); k <= std::min(w - 1, u + m); ++k) out[k] = 1;
    }
  }
  std::fill(mask->begin(), mask->end(), 0);
  for (int v = 0; v < h; ++v) {
    const char* in = rows.data() + static_cast<std::size_t>(v) * w;
    for (int u = 0; u < w; ++u) {
      if (!in[u]) continue;
      for (int k = std::max(0, v - m); k <= std::min(h - 1, v + m); ++k)
        (*mask)[static_cast<std::size_t>(k) * w + u] = 1;
    }
  }
}

}  // namespace

// The sampled pixels (every pixel_stride-th row and column) are a coarser camera of their own:
// the objects are rendered at that resolution only, and their masks grown in its cells.
int BackgroundMap::insert(const DepthImageView& depth, const PinholeIntrinsics& K,
                          const Eigen::Isometry3d& T_map_cam,
                          const std::vector<MaskObject>& objects) {
  if (!depth.data || depth.width != K.width || depth.height != K.height || !K.valid() ||
      !T_map_cam.matrix().allFinite()) {
    return 0;
  }
  const int s = std::max(1, config_.pixel_stride);
  PinholeIntrinsics Ks = K;  // pixel (i, j) of Ks is pixel (s i, s j) of K
  Ks.width = (K.width + s - 1) / s;
  Ks.height = (K.height + s - 1) / s;
  Ks.fx = K.fx / s, Ks.fy = K.fy / s, Ks.cx = K.cx / s, Ks.cy = K.cy / s;
  // The map's objects as the sampled pixels see them: their depth, and the pixels near them.
  std::vector<RenderItem> items;
  const Eigen::Isometry3d T_cam_map = T_map_cam.inverse();
  for (const MaskObject& o : objects) {
    if (!o.model) continue;
    RenderItem item;
    item.mesh = meshFor(o.model);
    if (item.mesh < 0) continue;
    item.T_cam_model = T_cam_map * o.T_map_obj;
    items.push_back(item);
  }
  const std::size_t n = static_cast<std::size_t>(Ks.width) * Ks.height;
  std::vector<float> object_depth(n, 0.f);
  std::vector<char> near_object(n, 0);
  if (!items.empty() && impl_->renderer->ok() &&
      impl_->renderer->render(Ks, items, &impl_->rendered, PixelBox{}, OffscreenRenderer::kDepth)) {
    for (int j = 0; j < Ks.height; ++j) {
      for (int i = 0; i < Ks.width; ++i) {
        const float z = impl_->rendered.depthAt(i, j);
        if (!(z > 0.f)) continue;
        object_depth[static_cast<std::size_t>(j) * Ks.width + i] = z;
        near_object[static_cast<std::size_t>(j) * Ks.width + i] = 1;
      }
    }
    dilate(&near_object, Ks.width, Ks.height, (std::max(0, config_.object_margin_px) + s - 1) / s);
  }
  std::vector<Eigen::Vector3d> points;  // map frame
  std::vector<char> casts;              // whether its ray clears free space
  // The free-space rays take every f-th sample in each direction, starting at a phase that
  // steps with each insertion: over f x f insertions every sampled direction clears once.
  const int f = std::max(1, config_.free_space_stride);
  const int phase = impl_->insertions++ % (f * f);
  const int phase_i = phase % f, phase_j = phase / f;
  for (int j = 0; j < Ks.height; ++j) {
    for (int i = 0; i < Ks.width; ++i) {
      const std::size_t c = static_cast<std::size_t>(j) * Ks.width + i;
      const float z = depth.at(s * i, s * j);
      if (!(z > 0.f) || !std::isfinite(z) || z > config_.max_range_m) continue;
      if (near_object[c]) {
        // On or behind an object (or at its rim): not background. Clearly in front of it:
        // something else, keep it.
        const float zo = object_depth[c];
        if (!(zo > 0.f) || z > zo - config_.object_margin_m) continue;
      }
      points.push_back(T_map_cam * K.backProject(s * i, s * j, z));
      casts.push_back(i % f == phase_i && j % f == phase_j);
    }
  }
  castRays(T_map_cam.translation(), points, casts);
  carve(objects);
  impl_->inserted_any = true;
  impl_->T_map_last = T_map_cam;
  impl_->passed_over = 0;
  return static_cast<int>(points.size());
}

// octomap's discretised scan insertion (insertPointCloud with discretize: each endpoint voxel
// once, rays cast to the voxels' centres, free voxels that are also endpoints left occupied,
// rays longer than max_range_m cut there with no endpoint), with the keys gathered in arrays of
// Morton codes sorted by a radix sort rather than octomap's hash sets (one allocation a key), the
// voxels updated a subtree at a time (octree_update.h: octomap's tree, each node visited once
// rather than once a key), and the free space cast from the `casts` points' voxels only: the
// endpoints stay dense where the rays, converging on the camera, need not be.
void BackgroundMap::castRays(const Eigen::Vector3d& origin,
                             const std::vector<Eigen::Vector3d>& points,
                             const std::vector<char>& casts) {
  octomap::OcTree& tree = impl_->tree;
  const bool bbx = tree.bbxSet();
  std::vector<std::uint64_t> occupied, rays, free;
  occupied.reserve(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    octomap::OcTreeKey key;
    const Eigen::Vector3d& p = points[i];
    if (!tree.coordToKeyChecked(
            octomap::point3d(static_cast<float>(p.x()), static_cast<float>(p.y()),
                             static_cast<float>(p.z())),
            key))
      continue;
    if ((p - origin).norm() <= config_.max_range_m) occupied.push_back(mortonCode(key));
    if (casts[i]) rays.push_back(mortonCode(key));
  }
  sortUnique(&occupied);
  sortUnique(&rays);
  const octomap::point3d o(static_cast<float>(origin.x()), static_cast<float>(origin.y()),
                           static_cast<float>(origin.z()));
  octomap::KeyRay ray;
  for (std::uint64_t r : rays) {
    octomap::point3d end = tree.keyToCoord(keyOfMortonCode(r));
    const octomap::point3d dir = end - o;
    if (dir.norm() > config_.max_range_m)
      end = o + dir.normalized() * static_cast<float>(config_.max_range_m);
    if (!tree.computeRayKeys(o, end, ray)) continue;
    for (const octomap::OcTreeKey& k : ray) free.push_back(mortonCode(k));
  }
  sortUnique(&free);
  std::vector<std::uint64_t> only_free;
  only_free.reserve(free.size());
  std::set_difference(free.begin(), free.end(), occupied.begin(), occupied.end(),
                      std::back_inserter(only_free));
  auto inside = [&](std::vector<std::uint64_t>* codes) {
    if (!bbx) return;
    codes->erase(std::remove_if(codes->begin(), codes->end(),
                                [&](std::uint64_t c) { return !tree.inBBX(keyOfMortonCode(c)); }),
                 codes->end());
  };
  inside(&only_free);
  inside(&occupied);
  updateSortedCodes(&tree, only_free, false);
  updateSortedCodes(&tree, occupied, true);
}

void BackgroundMap::carve(const std::vector<MaskObject>& objects) {
  // Objects confirmed after their surfaces went in (or seen where the mask missed them) must
  // not stay in the background: voxels inside their boxes (plus the margin) are set free. A
  // pruned leaf stands for all its finest-level children: each of them is set.
  std::vector<octomap::point3d> doomed;
  octomap::OcTree& tree = impl_->tree;
  for (const MaskObject& o : objects) {
    if (!o.model) continue;
    const Eigen::AlignedBox3f box = boxOf(*o.model);
    const Eigen::Vector3d centre = box.center().cast<double>();
    const Eigen::Vector3d half =
        (0.5f * box.diagonal()).cast<double>() + Eigen::Vector3d::Constant(config_.object_margin_m);
    Eigen::Vector3d box_lo = Eigen::Vector3d::Constant(1e9), box_hi = -box_lo;
    for (int k = 0; k < 8; ++k) {
      const Eigen::Vector3d corner(k & 1 ? half.x() : -half.x(), k & 2 ? half.y() : -half.y(),
                                   k & 4 ? half.z() : -half.z());
      const Eigen::Vector3d p = o.T_map_obj * (centre + corner);
      box_lo = box_lo.cwiseMin(p), box_hi = box_hi.cwiseMax(p);
    }
    const Eigen::Isometry3d T_obj_map = o.T_map_obj.inverse();
    for (auto it = tree.begin_leafs_bbx(
             octomap::point3d(static_cast<float>(box_lo.x()), static_cast<float>(box_lo.y()),
                              static_cast<float>(box_lo.z())),
             octomap::point3d(static_cast<float>(box_hi.x()), static_cast<float>(box_hi.y()),
                              static_cast<float>(box_hi.z())));
         it != tree.end_leafs_bbx(); ++it) {
      if (!tree.isNodeOccupied(*it)) continue;
      auto inside = [&](const Eigen::Vector3d& p) {
        const Eigen::Vector3d q = T_obj_map * p - centre;
        return std::abs(q.x()) <= half.x() && std::abs(q.y()) <= half.y() &&
               std::abs(q.z()) <= half.z();
      };
      const double size = it.getSize(), res = tree.getResolution();
      const int n = std::max(1, static_cast<int>(std::lround(size / res)));
      for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) {
          for (int k = 0; k < n; ++k) {
            const Eigen::Vector3d p(it.getX() - 0.5 * size + (i + 0.5) * res,
                                    it.getY() - 0.5 * size + (j + 0.5) * res,
                                    it.getZ() - 0.5 * size + (k + 0.5) * res);
            if (inside(p)) {
              doomed.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()),
                                  static_cast<float>(p.z()));
            }
          }
        }
      }
    }
  }
  for (const auto& p : doomed) tree.setNodeValue(p, tree.getClampingThresMinLog());
}

std::vector<Eigen::Vector3d> BackgroundMap::occupiedCentres() const {
  std::vector<Eigen::Vector3d> out;
  for (auto it = impl_->tree.begin_leafs(); it != impl_->tree.end_leafs(); ++it) {
    if (impl_->tree.isNodeOccupied(*it)) out.emplace_back(it.getX(), it.getY(), it.getZ());
  }
  return out;
}

std::vector<Eigen::Vector3d> BackgroundMap::occupiedVoxels() const {
  std::vector<Eigen::Vector3d> out;
  const octomap::OcTree& tree = impl_->tree;
  const double res = tree.getResolution();
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    if (!tree.isNodeOccupied(*it)) continue;
    const double size = it.getSize();
    const int n = std::max(1, static_cast<int>(std::lround(size / res)));
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j)
        for (int k = 0; k < n; ++k)
          out.emplace_back(it.getX() - 0.5 * size + (i + 0.5) * res,
                           it.getY() - 0.5 * size + (j + 0.5) * res,
                           it.getZ() - 0.5 * size + (k + 0.5) * res);
  }
  return out;
}

OccupiedAgreement compareOccupied(const BackgroundMap& a, const BackgroundMap& b) {
  OccupiedAgreement r;
  const std::vector<Eigen::Vector3d> va = a.occupiedVoxels(), vb = b.occupiedVoxels();
  r.a = va.size();
  r.b = vb.size();
  for (const Eigen::Vector3d& p : va) r.both += b.isOccupied(p);
  return r;
}

bool BackgroundMap::isOccupied(const Eigen::Vector3d& p) const {
  const octomap::OcTreeNode* node = impl_->tree.search(p.x(), p.y(), p.z());
  return node && impl_->tree.isNodeOccupied(node);
}

bool BackgroundMap::writeBinary(const std::string& path, std::string* error) const {
  return writeFileAtomically(
      path,
      [&](const std::string& tmp) {
        // Our own stream: a file that cannot be opened (a full disk, a read-only folder) fails
        // here with errno kept, not with OctoMap's unthrottled message on every attempt.
        std::ofstream file(tmp, std::ios::binary);
        if (!file) return false;
        octomap::OcTree copy(impl_->tree);  // writeBinary prunes: keep ours as it is
        return copy.writeBinary(file) && static_cast<bool>(file.flush());
      },
      error);
}

bool BackgroundMap::readBinary(const std::string& path, std::string* error) {
  octomap::OcTree loaded(config_.resolution_m);
  std::ifstream file(path, std::ios::binary);
  if (!file || !loaded.readBinary(file)) {
    if (error) *error = "cannot read the OctoMap " + path;
    return false;
  }
  if (std::abs(loaded.getResolution() - config_.resolution_m) > 1e-9) {
    if (error)
      *error = path + " has voxels of " + std::to_string(loaded.getResolution()) +
               " m, the background is configured for " + std::to_string(config_.resolution_m) +
               " m (background.resolution_m)";
    return false;
  }
  impl_->tree.swapContent(loaded);
  return true;
}

std::string BackgroundMap::binaryData() const {
  std::ostringstream out(std::ios::binary);
  octomap::OcTree copy(impl_->tree);  // writeBinaryData prunes: keep ours as it is
  copy.writeBinaryData(out);
  return out.str();
}

}  // namespace geofusion
