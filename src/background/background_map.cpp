#include "geofusion/background/background_map.h"

#include "geofusion/render/renderer.h"

#include "geofusion/common/atomic_file.h"

#include <octomap/OcTree.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>

namespace geofusion {

struct BackgroundMap::Impl {
  explicit Impl(double resolution) : tree(resolution) {}
  octomap::OcTree tree;
  std::shared_ptr<OffscreenRenderer> renderer;
  std::map<std::shared_ptr<const ObjectModel>, MeshHandle> meshes;
  RenderedImages rendered;
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
}

std::size_t BackgroundMap::numLeaves() const {
  return impl_->tree.getNumLeafNodes();
}

int BackgroundMap::insert(const DepthImageView& depth, const PinholeIntrinsics& K,
                          const Eigen::Isometry3d& T_map_cam,
                          const std::vector<MaskObject>& objects) {
  if (!depth.data || depth.width != K.width || depth.height != K.height || !K.valid() ||
      !T_map_cam.matrix().allFinite()) {
    return 0;
  }
  // The map's objects as the camera sees them: their pixels and depth.
  std::vector<RenderItem> items;
  const Eigen::Isometry3d T_cam_map = T_map_cam.inverse();
  for (const MaskObject& o : objects) {
    if (!o.model) continue;
    auto it = impl_->meshes.find(o.model);
    if (it == impl_->meshes.end()) {
      it = impl_->meshes.emplace(o.model, impl_->renderer->addMesh(o.model->mesh)).first;
    }
    if (it->second < 0) continue;
    RenderItem item;
    item.mesh = it->second;
    item.T_cam_model = T_cam_map * o.T_map_obj;
    item.instance_id = 1;
    items.push_back(item);
  }
  const std::size_t n = static_cast<std::size_t>(K.width) * K.height;
  std::vector<float> object_depth(n, 0.f);
  std::vector<char> near_object(n, 0);
  if (!items.empty() && impl_->renderer->ok()) {
    impl_->renderer->render(K, items, &impl_->rendered, PixelBox{}, OffscreenRenderer::kDepth);
    const int m = std::max(0, config_.object_margin_px);
    for (int v = 0; v < K.height; ++v) {
      for (int u = 0; u < K.width; ++u) {
        const float z = impl_->rendered.depthAt(u, v);
        if (!(z > 0.f)) continue;
        object_depth[static_cast<std::size_t>(v) * K.width + u] = z;
        for (int dv = -m; dv <= m; ++dv) {
          for (int du = -m; du <= m; ++du) {
            const int uu = u + du, vv = v + dv;
            if (uu >= 0 && vv >= 0 && uu < K.width && vv < K.height)
              near_object[static_cast<std::size_t>(vv) * K.width + uu] = 1;
          }
        }
      }
    }
  }
  octomap::Pointcloud cloud;
  const int stride = std::max(1, config_.pixel_stride);
  for (int v = 0; v < K.height; v += stride) {
    for (int u = 0; u < K.width; u += stride) {
      const std::size_t i = static_cast<std::size_t>(v) * K.width + u;
      const float z = depth.at(u, v);
      if (!(z > 0.f) || !std::isfinite(z) || z > config_.max_range_m) continue;
      if (near_object[i]) {
        // On or behind an object (or at its rim): not background. Clearly in front of it:
        // something else, keep it.
        const float zo = object_depth[i];
        if (!(zo > 0.f) || z > zo - config_.object_margin_m) continue;
      }
      const Eigen::Vector3d p = T_map_cam * K.backProject(u, v, z);
      cloud.push_back(static_cast<float>(p.x()), static_cast<float>(p.y()),
                      static_cast<float>(p.z()));
    }
  }
  const Eigen::Vector3d o = T_map_cam.translation();
  impl_->tree.insertPointCloud(
      cloud,
      octomap::point3d(static_cast<float>(o.x()), static_cast<float>(o.y()),
                       static_cast<float>(o.z())),
      config_.max_range_m, false, true);
  carve(objects);
  return static_cast<int>(cloud.size());
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

bool BackgroundMap::isOccupied(const Eigen::Vector3d& p) const {
  const octomap::OcTreeNode* node = impl_->tree.search(p.x(), p.y(), p.z());
  return node && impl_->tree.isNodeOccupied(node);
}

bool BackgroundMap::writeBinary(const std::string& path, std::string* error) const {
  return writeFileAtomically(
      path,
      [&](const std::string& tmp) {
        octomap::OcTree copy(impl_->tree);  // writeBinary prunes: keep ours as it is
        return copy.writeBinary(tmp);
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
