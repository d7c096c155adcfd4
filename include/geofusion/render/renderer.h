// Offscreen rendering of object models with OSMesa (software OpenGL, no display): metric depth,
// instance ids and, when asked, textured colour, for a pinhole camera, over the whole image or
// over one region of it. No OpenGL header leaks out of this file.
#pragma once

#include "geofusion/common/camera.h"
#include "geofusion/model/mesh.h"

#include <Eigen/Geometry>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace geofusion {

/// A mesh uploaded to a renderer; valid for that renderer's lifetime.
using MeshHandle = int;

struct RenderItem {
  MeshHandle mesh = -1;
  Eigen::Isometry3d T_cam_model = Eigen::Isometry3d::Identity();  ///< model in optical frame
  std::uint16_t instance_id = 1;                                  ///< 0 is background
  Eigen::Vector3f color = Eigen::Vector3f::Constant(0.7f);        ///< RGB in [0,1] when untextured
};

/// Images of one render over `region` of the camera image, row-major, region.width per row.
struct RenderedImages {
  PixelBox region;
  std::vector<float> depth;             ///< metres along the optical axis; 0 = nothing drawn
  std::vector<std::uint16_t> instance;  ///< RenderItem::instance_id; 0 = nothing drawn
  std::vector<std::uint8_t> rgb;        ///< 3 bytes a pixel, only when colour was asked for

  /// Depth at full-image pixel (u, v); 0 outside the region.
  float depthAt(int u, int v) const;
  std::uint16_t instanceAt(int u, int v) const;
};

/// One OSMesa context, one framebuffer and the uploaded meshes, reused across calls. Calls are
/// serialised by an internal mutex; each call makes the context current on the calling thread.
class OffscreenRenderer {
 public:
  enum Channel : int { kDepth = 1, kInstance = 2, kColor = 4 };

  struct Options {
    int max_width = 1280;  ///< largest image/region that can be rendered
    int max_height = 1024;
    int max_texture_size = 1024;  ///< textures are downscaled to this edge length
    /// Rasterise in the calling thread (llvmpipe's LP_NUM_THREADS=0): for the small regions the
    /// consistency score renders, worker threads cost more than they give. Applied only when
    /// LP_NUM_THREADS is not already set, and only before the process's first OSMesa context.
    bool single_threaded = true;
  };

  OffscreenRenderer();
  explicit OffscreenRenderer(const Options& options);
  ~OffscreenRenderer();
  OffscreenRenderer(const OffscreenRenderer&) = delete;
  OffscreenRenderer& operator=(const OffscreenRenderer&) = delete;

  /// False when the OSMesa context could not be made; error() says why.
  bool ok() const;
  /// The last error (context creation, bad mesh, bad texture, bad request).
  std::string error() const;

  /// Uploads a mesh (and its texture, read with OpenCV, when it has one; a texture that cannot
  /// be read is reported in error() and the mesh renders untextured). Returns -1 for an empty or
  /// malformed mesh. A closed mesh wound counter-clockwise outside (checkWatertight) is drawn
  /// with its back faces skipped (the same images, fewer triangles rasterised); any other mesh
  /// is drawn two-sided.
  MeshHandle addMesh(const TriangleMesh& mesh);
  std::size_t meshCount() const;
  /// Whether the mesh's back faces are skipped (closed and wound outward).
  bool cullsBackFaces(MeshHandle mesh) const;

  /// The image region covered by the mesh's bounding box at this pose, grown by `margin` pixels
  /// and clipped to the image; invalid when the box is entirely behind the camera or outside.
  PixelBox projectedRegion(const PinholeIntrinsics& K, MeshHandle mesh,
                           const Eigen::Isometry3d& T_cam_model, int margin = 1) const;

  /// Renders `items` seen by camera K into `out`, over `region` of the image (invalid region:
  /// the whole image). `channels` is a mask of Channel. Returns false (and leaves `out` empty)
  /// for bad intrinsics, an unknown mesh handle or a region larger than the framebuffer.
  bool render(const PinholeIntrinsics& K, const std::vector<RenderItem>& items, RenderedImages* out,
              PixelBox region = PixelBox{}, int channels = kDepth | kInstance);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace geofusion
