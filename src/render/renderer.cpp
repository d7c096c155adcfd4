#include "geofusion/render/renderer.h"

#include "geofusion/model/model_import.h"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/gl.h>
#include <GL/glext.h>
#include <GL/osmesa.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <mutex>

namespace geofusion {

float RenderedImages::depthAt(int u, int v) const {
  const int x = u - region.x, y = v - region.y;
  if (x < 0 || y < 0 || x >= region.width || y >= region.height || depth.empty()) return 0.f;
  return depth[static_cast<std::size_t>(y) * region.width + x];
}

std::uint16_t RenderedImages::instanceAt(int u, int v) const {
  const int x = u - region.x, y = v - region.y;
  if (x < 0 || y < 0 || x >= region.width || y >= region.height || instance.empty()) return 0;
  return instance[static_cast<std::size_t>(y) * region.width + x];
}

namespace {

struct GpuMesh {
  GLuint buffers[4] = {0, 0, 0, 0};  // positions, normals, uvs, indices
  GLsizei index_count = 0;
  GLuint texture = 0;
  std::array<Eigen::Vector3d, 8> corners;  // bounding box, model frame
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double radius = 0.0;           // bounding sphere about `centre`
  bool cull_back_faces = false;  // closed and wound outward: back faces are never seen
};

std::vector<Eigen::Vector3f> vertexNormals(const TriangleMesh& mesh) {
  std::vector<Eigen::Vector3f> normals(mesh.vertices.size(), Eigen::Vector3f::Zero());
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3f n =
        (mesh.vertices[t[1]] - mesh.vertices[t[0]])
            .cross(mesh.vertices[t[2]] - mesh.vertices[t[0]]);  // area-weighted
    for (int k = 0; k < 3; ++k) normals[t[k]] += n;
  }
  for (auto& n : normals) {
    const float len = n.norm();
    n = len > 0.f ? Eigen::Vector3f(n / len) : Eigen::Vector3f::UnitZ();
  }
  return normals;
}

// Column-major OpenGL projection for pinhole K over `region`, with GL eye coordinates
// (x right, y up, looking down -z). Pixel centres sit at integer (u, v), see camera.h.
std::array<GLdouble, 16> projection(const PinholeIntrinsics& K, const PixelBox& region,
                                    double z_near, double z_far) {
  const double w = region.width, h = region.height;
  std::array<GLdouble, 16> p{};
  p[0] = 2.0 * K.fx / w;
  p[5] = 2.0 * K.fy / h;
  p[8] = 1.0 - 2.0 * (K.cx - region.x + 0.5) / w;
  p[9] = 2.0 * (K.cy - region.y + 0.5) / h - 1.0;
  p[10] = -(z_far + z_near) / (z_far - z_near);
  p[11] = -1.0;
  p[14] = -2.0 * z_far * z_near / (z_far - z_near);
  return p;
}

}  // namespace

struct OffscreenRenderer::Impl {
  Options options;
  OSMesaContext context = nullptr;
  std::vector<unsigned char> window;  // tiny OSMesa buffer; all drawing goes to the FBO
  GLuint fbo = 0, color_rb = 0, depth_rb = 0;
  std::vector<GpuMesh> meshes;
  std::vector<float> depth_rows;
  std::vector<std::uint8_t> color_rows;
  mutable std::mutex mutex;
  std::string error;

  bool makeCurrent() {
    if (!context) return false;
    if (OSMesaGetCurrentContext() == context) return true;
    return OSMesaMakeCurrent(context, window.data(), GL_UNSIGNED_BYTE, 16, 16) == GL_TRUE;
  }

  void drawItems(const std::vector<RenderItem>& items, bool instance_colours, bool textured) {
    for (const auto& item : items) {
      const GpuMesh& m = meshes[static_cast<std::size_t>(item.mesh)];
      // Optical frame -> GL eye frame: flip y and z.
      Eigen::Matrix4d modelview = item.T_cam_model.matrix();
      modelview.row(1) *= -1.0;
      modelview.row(2) *= -1.0;
      glLoadMatrixd(modelview.data());
      if (instance_colours) {
        glColor4ub(static_cast<GLubyte>(item.instance_id & 0xff),
                   static_cast<GLubyte>(item.instance_id >> 8), 0, 255);
      } else {
        glColor3f(item.color.x(), item.color.y(), item.color.z());
      }
      if (m.cull_back_faces)
        glEnable(GL_CULL_FACE);
      else
        glDisable(GL_CULL_FACE);
      const bool use_texture = textured && m.texture != 0;
      if (use_texture) {
        glEnable(GL_TEXTURE_2D);
        glBindTexture(GL_TEXTURE_2D, m.texture);
        glColor3f(1.f, 1.f, 1.f);
      }
      glBindBuffer(GL_ARRAY_BUFFER, m.buffers[0]);
      glVertexPointer(3, GL_FLOAT, 0, nullptr);
      if (!instance_colours) {
        glEnableClientState(GL_NORMAL_ARRAY);
        glBindBuffer(GL_ARRAY_BUFFER, m.buffers[1]);
        glNormalPointer(GL_FLOAT, 0, nullptr);
      }
      if (use_texture) {
        glEnableClientState(GL_TEXTURE_COORD_ARRAY);
        glBindBuffer(GL_ARRAY_BUFFER, m.buffers[2]);
        glTexCoordPointer(2, GL_FLOAT, 0, nullptr);
      }
      glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, m.buffers[3]);
      glDrawElements(GL_TRIANGLES, m.index_count, GL_UNSIGNED_INT, nullptr);
      glDisableClientState(GL_NORMAL_ARRAY);
      glDisableClientState(GL_TEXTURE_COORD_ARRAY);
      if (use_texture) glDisable(GL_TEXTURE_2D);
    }
    glBindBuffer(GL_ARRAY_BUFFER, 0);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, 0);
  }
};

OffscreenRenderer::OffscreenRenderer() : OffscreenRenderer(Options()) {}

OffscreenRenderer::OffscreenRenderer(const Options& options) : impl_(std::make_unique<Impl>()) {
  Impl& d = *impl_;
  d.options = options;
  d.options.max_width = std::max(1, options.max_width);
  d.options.max_height = std::max(1, options.max_height);
  d.window.assign(16 * 16 * 4, 0);
  if (options.single_threaded) setenv("LP_NUM_THREADS", "0", /*overwrite=*/0);
  d.context = OSMesaCreateContextExt(OSMESA_RGBA, 24, 0, 0, nullptr);
  if (!d.context) {
    d.error = "OSMesa: could not create an offscreen context (is libosmesa6 installed?)";
    return;
  }
  if (!d.makeCurrent()) {
    d.error = "OSMesa: could not make the offscreen context current";
    OSMesaDestroyContext(d.context);
    d.context = nullptr;
    return;
  }
  glGenFramebuffers(1, &d.fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, d.fbo);
  glGenRenderbuffers(1, &d.color_rb);
  glBindRenderbuffer(GL_RENDERBUFFER, d.color_rb);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, d.options.max_width, d.options.max_height);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, d.color_rb);
  glGenRenderbuffers(1, &d.depth_rb);
  glBindRenderbuffer(GL_RENDERBUFFER, d.depth_rb);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, d.options.max_width,
                        d.options.max_height);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, d.depth_rb);
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
    d.error = "OSMesa: offscreen framebuffer incomplete";
    OSMesaDestroyContext(d.context);
    d.context = nullptr;
    return;
  }
  glDisable(GL_DITHER);
  glDisable(GL_MULTISAMPLE);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glCullFace(GL_BACK);  // enabled for the meshes that are closed and wound outward
  glEnable(GL_SCISSOR_TEST);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glEnableClientState(GL_VERTEX_ARRAY);
  // A head light for the colour pass: textures and colours modulated by a Lambertian term.
  const GLfloat ambient[] = {0.45f, 0.45f, 0.45f, 1.f}, diffuse[] = {0.6f, 0.6f, 0.6f, 1.f};
  const GLfloat at_camera[] = {0.f, 0.f, 1.f, 0.f};
  glMatrixMode(GL_MODELVIEW);
  glLoadIdentity();
  glLightfv(GL_LIGHT0, GL_POSITION, at_camera);
  glLightfv(GL_LIGHT0, GL_AMBIENT, ambient);
  glLightfv(GL_LIGHT0, GL_DIFFUSE, diffuse);
  glEnable(GL_LIGHT0);
  glEnable(GL_COLOR_MATERIAL);
  glColorMaterial(GL_FRONT_AND_BACK, GL_AMBIENT_AND_DIFFUSE);
  glEnable(GL_NORMALIZE);
  glTexEnvi(GL_TEXTURE_ENV, GL_TEXTURE_ENV_MODE, GL_MODULATE);
}

OffscreenRenderer::~OffscreenRenderer() {
  Impl& d = *impl_;
  if (!d.context) return;
  if (d.makeCurrent()) {
    for (auto& m : d.meshes) {
      glDeleteBuffers(4, m.buffers);
      if (m.texture) glDeleteTextures(1, &m.texture);
    }
    glDeleteRenderbuffers(1, &d.color_rb);
    glDeleteRenderbuffers(1, &d.depth_rb);
    glDeleteFramebuffers(1, &d.fbo);
  }
  OSMesaDestroyContext(d.context);
}

bool OffscreenRenderer::ok() const {
  return impl_->context != nullptr;
}

std::string OffscreenRenderer::error() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->error;
}

std::size_t OffscreenRenderer::meshCount() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->meshes.size();
}

bool OffscreenRenderer::cullsBackFaces(MeshHandle mesh) const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return mesh >= 0 && static_cast<std::size_t>(mesh) < impl_->meshes.size() &&
         impl_->meshes[static_cast<std::size_t>(mesh)].cull_back_faces;
}

MeshHandle OffscreenRenderer::addMesh(const TriangleMesh& mesh) {
  Impl& d = *impl_;
  std::lock_guard<std::mutex> lock(d.mutex);
  if (!d.makeCurrent()) {
    d.error = "OSMesa: no context";
    return -1;
  }
  if (mesh.empty()) {
    d.error = "renderer: empty mesh";
    return -1;
  }
  const int n = static_cast<int>(mesh.vertices.size());
  for (const auto& t : mesh.triangles) {
    if (t.minCoeff() < 0 || t.maxCoeff() >= n) {
      d.error = "renderer: triangle index out of range";
      return -1;
    }
  }
  for (const auto& v : mesh.vertices) {
    if (!v.allFinite()) {
      d.error = "renderer: non-finite vertex";
      return -1;
    }
  }
  GpuMesh m;
  const std::vector<Eigen::Vector3f> normals = vertexNormals(mesh);
  glGenBuffers(4, m.buffers);
  glBindBuffer(GL_ARRAY_BUFFER, m.buffers[0]);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(n * sizeof(Eigen::Vector3f)),
               mesh.vertices.data(), GL_STATIC_DRAW);
  glBindBuffer(GL_ARRAY_BUFFER, m.buffers[1]);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(n * sizeof(Eigen::Vector3f)),
               normals.data(), GL_STATIC_DRAW);
  const bool has_uvs = mesh.uvs.size() == mesh.vertices.size();
  if (has_uvs) {
    glBindBuffer(GL_ARRAY_BUFFER, m.buffers[2]);
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(n * sizeof(Eigen::Vector2f)),
                 mesh.uvs.data(), GL_STATIC_DRAW);
  }
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, m.buffers[3]);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER,
               static_cast<GLsizeiptr>(mesh.triangles.size() * sizeof(Eigen::Vector3i)),
               mesh.triangles.data(), GL_STATIC_DRAW);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, 0);
  m.index_count = static_cast<GLsizei>(mesh.triangles.size() * 3);

  if (has_uvs && !mesh.texture_path.empty()) {
    cv::Mat image;
    if (std::ifstream(mesh.texture_path).good())
      image = cv::imread(mesh.texture_path, cv::IMREAD_COLOR);
    if (image.empty()) {
      d.error = "renderer: cannot read texture " + mesh.texture_path + "; mesh drawn untextured";
    } else {
      const int edge = std::max(image.cols, image.rows);
      if (edge > d.options.max_texture_size) {
        const double s = static_cast<double>(d.options.max_texture_size) / edge;
        cv::resize(image, image, cv::Size(), s, s, cv::INTER_AREA);
      }
      cv::cvtColor(image, image, cv::COLOR_BGR2RGB);
      cv::flip(image, image, 0);  // OBJ texture v runs bottom-up, OpenGL rows too
      if (!image.isContinuous()) image = image.clone();
      glGenTextures(1, &m.texture);
      glBindTexture(GL_TEXTURE_2D, m.texture);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
      glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB8, image.cols, image.rows, 0, GL_RGB, GL_UNSIGNED_BYTE,
                   image.data);
      glBindTexture(GL_TEXTURE_2D, 0);
    }
  }

  Eigen::Vector3f lo, hi;
  mesh.bounds(&lo, &hi);
  for (int i = 0; i < 8; ++i) {
    m.corners[i] = Eigen::Vector3d((i & 1) ? hi.x() : lo.x(), (i & 2) ? hi.y() : lo.y(),
                                   (i & 4) ? hi.z() : lo.z());
  }
  m.centre = (0.5f * (lo + hi)).cast<double>();
  m.radius = 0.5 * static_cast<double>((hi - lo).norm());
  m.cull_back_faces = checkWatertight(mesh).closedOutward();
  d.meshes.push_back(m);
  return static_cast<MeshHandle>(d.meshes.size() - 1);
}

PixelBox OffscreenRenderer::projectedRegion(const PinholeIntrinsics& K, MeshHandle mesh,
                                            const Eigen::Isometry3d& T_cam_model,
                                            int margin) const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  if (!K.valid() || mesh < 0 || static_cast<std::size_t>(mesh) >= impl_->meshes.size()) return {};
  const GpuMesh& m = impl_->meshes[static_cast<std::size_t>(mesh)];
  constexpr double kMinZ = 1e-3;
  double u0 = std::numeric_limits<double>::max(), v0 = u0, u1 = -u0, v1 = -u0;
  bool any_in_front = false, any_behind = false;
  for (const auto& c : m.corners) {
    const Eigen::Vector3d p = T_cam_model * c;
    if (!p.allFinite()) return {};
    if (p.z() <= kMinZ) {
      any_behind = true;
      continue;
    }
    any_in_front = true;
    const Eigen::Vector2d uv = K.project(p);
    u0 = std::min(u0, uv.x());
    v0 = std::min(v0, uv.y());
    u1 = std::max(u1, uv.x());
    v1 = std::max(v1, uv.y());
  }
  if (!any_in_front) return {};
  if (any_behind) return PixelBox{0, 0, K.width, K.height};  // straddles the camera plane
  const int x0 = std::max(0, static_cast<int>(std::floor(u0)) - margin);
  const int y0 = std::max(0, static_cast<int>(std::floor(v0)) - margin);
  const int x1 = std::min(K.width - 1, static_cast<int>(std::ceil(u1)) + margin);
  const int y1 = std::min(K.height - 1, static_cast<int>(std::ceil(v1)) + margin);
  if (x1 < x0 || y1 < y0) return {};
  return PixelBox{x0, y0, x1 - x0 + 1, y1 - y0 + 1};
}

bool OffscreenRenderer::render(const PinholeIntrinsics& K, const std::vector<RenderItem>& items,
                               RenderedImages* out, PixelBox region, int channels) {
  Impl& d = *impl_;
  std::lock_guard<std::mutex> lock(d.mutex);
  *out = RenderedImages();
  if (!K.valid()) {
    d.error = "renderer: invalid intrinsics";
    return false;
  }
  if (!region.valid()) region = PixelBox{0, 0, K.width, K.height};
  if (region.width > d.options.max_width || region.height > d.options.max_height) {
    d.error = "renderer: region larger than the framebuffer (raise Options::max_width/height)";
    return false;
  }
  if (!d.makeCurrent()) {
    d.error = "OSMesa: no context";
    return false;
  }
  // Depth range from the items' bounding spheres: tight near/far keeps depth precise.
  double z_near = std::numeric_limits<double>::max(), z_far = 0.0;
  for (const auto& item : items) {
    if (item.mesh < 0 || static_cast<std::size_t>(item.mesh) >= d.meshes.size()) {
      d.error = "renderer: unknown mesh handle";
      return false;
    }
    if (!item.T_cam_model.matrix().allFinite()) {
      d.error = "renderer: non-finite pose";
      return false;
    }
    const GpuMesh& m = d.meshes[static_cast<std::size_t>(item.mesh)];
    const double z = (item.T_cam_model * m.centre).z();
    z_near = std::min(z_near, z - m.radius);
    z_far = std::max(z_far, z + m.radius);
  }
  const std::size_t pixels = static_cast<std::size_t>(region.width) * region.height;
  out->region = region;
  if (channels & kDepth) out->depth.assign(pixels, 0.f);
  if (channels & kInstance) out->instance.assign(pixels, 0);
  if (channels & kColor) out->rgb.assign(pixels * 3, 0);
  if (items.empty() || z_far <= 1e-3) return true;  // nothing in front of the camera
  z_near = std::max(z_near * 0.99, 1e-3);
  z_far = std::max(z_far * 1.01, z_near * 1.01);

  glBindFramebuffer(GL_FRAMEBUFFER, d.fbo);
  glViewport(0, 0, region.width, region.height);
  glScissor(0, 0, region.width, region.height);
  glMatrixMode(GL_PROJECTION);
  glLoadMatrixd(projection(K, region, z_near, z_far).data());
  glMatrixMode(GL_MODELVIEW);

  // Reads a w x h block into `dst` row-major top row first (OpenGL rows are bottom-up).
  const int w = region.width, h = region.height;
  auto flip_rows = [w, h](const auto& src, auto* dst, int per_pixel) {
    const std::size_t row = static_cast<std::size_t>(w) * per_pixel;
    for (int y = 0; y < h; ++y)
      std::copy_n(src.data() + static_cast<std::size_t>(h - 1 - y) * row, row,
                  dst->data() + static_cast<std::size_t>(y) * row);
  };

  if (channels & kColor) {
    glClearColor(0.f, 0.f, 0.f, 1.f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glEnable(GL_LIGHTING);
    d.drawItems(items, false, true);
    glDisable(GL_LIGHTING);
    d.color_rows.resize(pixels * 3);
    glReadPixels(0, 0, w, h, GL_RGB, GL_UNSIGNED_BYTE, d.color_rows.data());
    flip_rows(d.color_rows, &out->rgb, 3);
  }
  if (channels & (kDepth | kInstance)) {
    const bool ids = (channels & kInstance) != 0;
    glClearColor(0.f, 0.f, 0.f, 0.f);
    glColorMask(ids, ids, ids, ids);  // depth alone writes no colour
    glClear(ids ? GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT : GL_DEPTH_BUFFER_BIT);
    d.drawItems(items, true, false);
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    if (channels & kInstance) {
      d.color_rows.resize(pixels * 4);
      glReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, d.color_rows.data());
      for (int y = 0; y < h; ++y) {
        const std::uint8_t* src = d.color_rows.data() + static_cast<std::size_t>(h - 1 - y) * w * 4;
        std::uint16_t* dst = out->instance.data() + static_cast<std::size_t>(y) * w;
        for (int x = 0; x < w; ++x)
          dst[x] = static_cast<std::uint16_t>(src[4 * x] | (src[4 * x + 1] << 8));
      }
    }
    if (channels & kDepth) {
      d.depth_rows.resize(pixels);
      glReadPixels(0, 0, w, h, GL_DEPTH_COMPONENT, GL_FLOAT, d.depth_rows.data());
      // Window depth d in [0,1] back to metric z: z = 2fn / ((f + n) - (2d - 1)(f - n)).
      const double a = 2.0 * z_far * z_near, b = z_far + z_near, c = z_far - z_near;
      for (int y = 0; y < h; ++y) {
        const float* src = d.depth_rows.data() + static_cast<std::size_t>(h - 1 - y) * w;
        float* dst = out->depth.data() + static_cast<std::size_t>(y) * w;
        for (int x = 0; x < w; ++x) {
          const float wd = src[x];
          dst[x] = wd >= 1.f ? 0.f : static_cast<float>(a / (b - (2.0 * wd - 1.0) * c));
        }
      }
    }
  }
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  return true;
}

}  // namespace geofusion
