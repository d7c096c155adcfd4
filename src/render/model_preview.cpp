#include "geofusion/render/model_preview.h"

#include "geofusion/render/renderer.h"

#include <Eigen/Geometry>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

namespace geofusion {
namespace {

constexpr int kViewSize = 480;

// The camera on the diagonal `direction` from the model's centre, looking at it (T_cam_model).
Eigen::Isometry3d cameraLookingAt(const Eigen::Vector3d& centre, const Eigen::Vector3d& direction,
                                  double distance) {
  return lookAt(centre + distance * direction.normalized(), centre).inverse();
}

class View {
 public:
  View(const PinholeIntrinsics& K, const Eigen::Isometry3d& T_cam_model, cv::Mat* image)
      : K_(K), T_(T_cam_model), image_(image) {}

  bool visible(const Eigen::Vector3d& p) const { return (T_ * p).z() > 1e-3; }
  cv::Point pixel(const Eigen::Vector3d& p) const {
    const Eigen::Vector2d uv = K_.project(T_ * p);
    return {static_cast<int>(std::lround(uv.x())), static_cast<int>(std::lround(uv.y()))};
  }
  void line(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const cv::Scalar& colour,
            int width = 2) {
    if (visible(a) && visible(b)) cv::line(*image_, pixel(a), pixel(b), colour, width, cv::LINE_AA);
  }
  void arrow(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const cv::Scalar& colour) {
    if (visible(a) && visible(b))
      cv::arrowedLine(*image_, pixel(a), pixel(b), colour, 2, cv::LINE_AA, 0, 0.2);
  }
  void circle(const Eigen::Vector3d& centre, const Eigen::Vector3d& axis, double radius,
              const cv::Scalar& colour) {
    const Eigen::Vector3d u = axis.unitOrthogonal(), v = axis.normalized().cross(u);
    for (int k = 0; k < 36; ++k) {
      const double a = 2 * M_PI * k / 36, b = 2 * M_PI * (k + 1) / 36;
      line(centre + radius * (std::cos(a) * u + std::sin(a) * v),
           centre + radius * (std::cos(b) * u + std::sin(b) * v), colour, 1);
    }
  }

 private:
  PinholeIntrinsics K_;
  Eigen::Isometry3d T_;
  cv::Mat* image_;
};

// The rendered mesh, shaded by how its depth changes (normals from the depth image).
cv::Mat shadedRender(const RenderedImages& images, const PinholeIntrinsics& K) {
  cv::Mat out(K.height, K.width, CV_8UC3, cv::Scalar(40, 40, 40));
  const auto depth = [&](int u, int v) { return images.depthAt(u, v); };
  for (int v = 1; v + 1 < K.height; ++v) {
    for (int u = 1; u + 1 < K.width; ++u) {
      const float z = depth(u, v);
      if (z <= 0.f) continue;
      const float zx = depth(u + 1, v) > 0.f ? depth(u + 1, v) - z : 0.f;
      const float zy = depth(u, v + 1) > 0.f ? depth(u, v + 1) - z : 0.f;
      const Eigen::Vector3f n(-zx * static_cast<float>(K.fx) / z,
                              -zy * static_cast<float>(K.fy) / z, 1.f);
      const float shade = 0.35f + 0.65f * std::abs(n.normalized().z());
      const std::size_t i = 3 * (static_cast<std::size_t>(v) * K.width + u);
      cv::Vec3b& px = out.at<cv::Vec3b>(v, u);
      for (int c = 0; c < 3; ++c)
        px[2 - c] = static_cast<std::uint8_t>(std::min(255.f, shade * images.rgb[i + c]));
    }
  }
  return out;
}

void drawFeatures(const SurfaceFeatures& features, double size, View* view) {
  const cv::Scalar plane(80, 220, 80), normal(0, 220, 255), side(255, 80, 255), edge(60, 60, 255);
  for (const auto& p : features.planes) {
    for (std::size_t i = 0; i < p.boundary.size(); ++i)
      view->line(p.boundary[i], p.boundary[(i + 1) % p.boundary.size()], plane);
    view->arrow(p.center, p.center + 0.25 * size * p.normal, normal);
  }
  for (const auto& c : features.curves) {
    if (c.radius_m > 0.0) {
      view->line(c.end_a, c.end_b, side);
      view->circle(c.end_a, c.axis, c.radius_m, side);
      view->circle(c.end_b, c.axis, c.radius_m, side);
    } else {
      view->line(c.end_a, c.end_b, edge, 3);
    }
  }
}

void drawSymmetry(const Symmetry& symmetry, const Eigen::Vector3d& centre, double size,
                  View* view) {
  const cv::Scalar colour(255, 255, 0);
  std::vector<Eigen::Vector3d> axes;
  if (symmetry.type == Symmetry::Type::kContinuous) axes.push_back(symmetry.axis);
  for (const auto& q : symmetry.rotations) axes.push_back(Eigen::AngleAxisd(q).axis());
  for (const auto& a : axes) {
    for (int k = -6; k < 6; k += 2)  // dashed, through the centre
      view->line(centre + a * (0.75 * size * k / 6), centre + a * (0.75 * size * (k + 1) / 6),
                 colour, 1);
  }
}

}  // namespace

bool writeModelPreview(const TriangleMesh& mesh, const SurfaceFeatures& features,
                       const Symmetry& symmetry, const Eigen::Vector3d& symmetry_centre,
                       const std::vector<std::string>& caption, const std::string& path,
                       std::string* error) {
  OffscreenRenderer renderer;
  const MeshHandle handle = renderer.ok() ? renderer.addMesh(mesh) : -1;
  if (handle < 0) {
    *error = "cannot render the mesh: " + renderer.error();
    return false;
  }
  PinholeIntrinsics K;
  K.width = K.height = kViewSize;
  K.fx = K.fy = 1.2 * kViewSize;
  K.cx = K.cy = 0.5 * kViewSize;
  Eigen::Vector3f lo, hi;
  mesh.bounds(&lo, &hi);
  const Eigen::Vector3d centre = (0.5f * (lo + hi)).cast<double>();
  const double size = static_cast<double>((hi - lo).norm());
  std::vector<cv::Mat> views;
  for (const Eigen::Vector3d& direction :
       {Eigen::Vector3d(1.0, -1.3, 0.9), Eigen::Vector3d(-1.0, 1.3, -0.9)}) {
    RenderItem item;
    item.mesh = handle;
    item.T_cam_model = cameraLookingAt(centre, direction, 1.5 * size);
    RenderedImages images;
    if (!renderer.render(K, {item}, &images, PixelBox{},
                         OffscreenRenderer::kDepth | OffscreenRenderer::kColor)) {
      *error = "cannot render the mesh: " + renderer.error();
      return false;
    }
    cv::Mat image = shadedRender(images, K);
    View view(K, item.T_cam_model, &image);
    drawFeatures(features, size, &view);
    drawSymmetry(symmetry, symmetry_centre, size, &view);
    views.push_back(image);
  }
  cv::Mat both;
  cv::hconcat(views, both);
  int y = 18;
  for (const auto& line : caption) {
    cv::putText(both, line, cv::Point(8, y), cv::FONT_HERSHEY_SIMPLEX, 0.5,
                cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
    y += 18;
  }
  try {
    if (!cv::imwrite(path, both)) {
      *error = "cannot write " + path;
      return false;
    }
  } catch (const cv::Exception& e) {
    *error = "cannot write " + path + ": " + e.what();
    return false;
  }
  return true;
}

}  // namespace geofusion
