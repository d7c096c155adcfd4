#include "geofusion/simulation/box_scene.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace geofusion {

namespace {

Eigen::Isometry3d placed(double x, double y, double z, double yaw_deg, double roll_deg = 0.0) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = (Eigen::AngleAxisd(yaw_deg * M_PI / 180.0, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(roll_deg * M_PI / 180.0, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  T.translation() = Eigen::Vector3d(x, y, z);
  return T;
}

// Ray / oriented box intersection (slab test in the box frame). Returns the ray parameter of the
// entry point and the entry face normal in the world frame, or +inf.
double intersectBox(const BoxObject& box, const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                    Eigen::Vector3d* normal) {
  const Eigen::Matrix3d R = box.T_world_obj.linear();
  const Eigen::Vector3d o = R.transpose() * (origin - box.T_world_obj.translation());
  const Eigen::Vector3d d = R.transpose() * dir;
  const Eigen::Vector3d half = 0.5 * box.size;
  double t_near = -std::numeric_limits<double>::infinity();
  double t_far = std::numeric_limits<double>::infinity();
  int axis = -1;
  double sign = 1.0;
  for (int i = 0; i < 3; ++i) {
    if (std::abs(d[i]) < 1e-12) {
      if (std::abs(o[i]) > half[i]) return std::numeric_limits<double>::infinity();
      continue;
    }
    double t1 = (-half[i] - o[i]) / d[i];
    double t2 = (half[i] - o[i]) / d[i];
    double s = -1.0;  // entering through the -half face
    if (t1 > t2) {
      std::swap(t1, t2);
      s = 1.0;
    }
    if (t1 > t_near) {
      t_near = t1;
      axis = i;
      sign = s;
    }
    t_far = std::min(t_far, t2);
    if (t_near > t_far) return std::numeric_limits<double>::infinity();
  }
  if (t_near <= 1e-9 || axis < 0) return std::numeric_limits<double>::infinity();
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  n[axis] = sign;
  *normal = R * n;
  return t_near;
}

std::uint8_t toByte(double v) {
  return static_cast<std::uint8_t>(std::clamp(v, 0.0, 1.0) * 255.0 + 0.5);
}

}  // namespace

BoxScene BoxScene::demoScene() {
  BoxScene s;
  const double h = s.table_height_m;
  auto add = [&s](const char* name, int id, double sx, double sy, double sz,
                  const Eigen::Isometry3d& T) {
    s.objects.push_back(BoxObject{name, id, Eigen::Vector3d(sx, sy, sz), T});
  };
  // Sizes are the YCB-Video extents of these objects (x y z, metres).
  add("003_cracker_box", 2, 0.072948, 0.167432, 0.223122, placed(0.00, 0.06, h + 0.111561, 20));
  add("004_sugar_box", 3, 0.051228, 0.097062, 0.184740, placed(-0.16, -0.06, h + 0.092370, -30));
  add("008_pudding_box", 7, 0.140458, 0.136312, 0.044982, placed(0.17, -0.12, h + 0.022491, 40));
  // Gelatin box stacked on the pudding box.
  add("009_gelatin_box", 8, 0.092226, 0.102030, 0.037278,
      placed(0.17, -0.12, h + 0.044982 + 0.018639, 10));
  add("061_foam_brick", 21, 0.052900, 0.077960, 0.067918, placed(-0.04, -0.19, h + 0.033959, 70));
  // Wood block lying on its side (rolled 90 degrees about x): its y edge is vertical.
  add("036_wood_block", 16, 0.106668, 0.108480, 0.240242,
      placed(0.16, 0.17, h + 0.054240, -15, 90));
  return s;
}

RenderedFrame BoxScene::render(const PinholeIntrinsics& K,
                               const Eigen::Isometry3d& T_world_cam) const {
  RenderedFrame f;
  f.width = K.width;
  f.height = K.height;
  const std::size_t n = static_cast<std::size_t>(K.width) * static_cast<std::size_t>(K.height);
  f.depth.assign(n, 0.f);
  f.rgb.assign(3 * n, 0);
  f.instance.assign(n, RenderedFrame::kBackground);

  const Eigen::Matrix3d R = T_world_cam.linear();
  const Eigen::Vector3d origin = T_world_cam.translation();
  const Eigen::Vector3d z_cam_world = R.col(2);
  std::vector<Rgb> colors;
  colors.reserve(objects.size());
  for (const BoxObject& b : objects) colors.push_back(classColor(b.class_name));

  for (int v = 0; v < K.height; ++v) {
    for (int u = 0; u < K.width; ++u) {
      const Eigen::Vector3d ray_cam((u - K.cx) / K.fx, (v - K.cy) / K.fy, 1.0);
      const Eigen::Vector3d dir = (R * ray_cam).normalized();
      double best_t = std::numeric_limits<double>::infinity();
      int best_id = RenderedFrame::kBackground;
      Eigen::Vector3d best_n = Eigen::Vector3d::UnitZ();
      Rgb base{0.55f, 0.55f, 0.58f};
      for (std::size_t i = 0; i < objects.size(); ++i) {
        Eigen::Vector3d nrm = Eigen::Vector3d::UnitZ();
        const double t = intersectBox(objects[i], origin, dir, &nrm);
        if (t < best_t) {
          best_t = t;
          best_id = static_cast<int>(i);
          best_n = nrm;
          base = colors[i];
        }
      }
      // Horizontal planes: the table top, then the floor.
      for (double plane_z : {table_height_m, 0.0}) {
        if (std::abs(dir.z()) < 1e-9) continue;
        const double t = (plane_z - origin.z()) / dir.z();
        if (t <= 0 || t >= best_t) continue;
        const Eigen::Vector3d p = origin + t * dir;
        const bool on_table = plane_z > 0.0;
        if (on_table && (std::abs(p.x()) > table_half_x_m || std::abs(p.y()) > table_half_y_m)) {
          continue;
        }
        best_t = t;
        best_n = Eigen::Vector3d::UnitZ();
        best_id = on_table ? RenderedFrame::kTable : RenderedFrame::kBackground;
        base = on_table ? Rgb{0.62f, 0.45f, 0.28f} : Rgb{0.35f, 0.35f, 0.38f};
      }
      if (!std::isfinite(best_t)) continue;
      const double z = best_t * dir.dot(z_cam_world);
      if (z > max_range_m) continue;
      const std::size_t idx = static_cast<std::size_t>(v) * K.width + u;
      f.depth[idx] = static_cast<float>(z);
      f.instance[idx] = best_id;
      const double shade = 0.35 + 0.65 * std::abs(best_n.dot(dir));
      f.rgb[3 * idx + 0] = toByte(base.r * shade);
      f.rgb[3 * idx + 1] = toByte(base.g * shade);
      f.rgb[3 * idx + 2] = toByte(base.b * shade);
    }
  }
  return f;
}

std::vector<int> visiblePixelCounts(const RenderedFrame& frame, std::size_t num_objects) {
  std::vector<int> counts(num_objects, 0);
  for (int id : frame.instance) {
    if (id >= 0 && static_cast<std::size_t>(id) < num_objects) ++counts[id];
  }
  return counts;
}

std::vector<RawDetection> synthesizeDetections(const BoxScene& scene, const RenderedFrame& frame,
                                               const Eigen::Isometry3d& T_world_cam,
                                               const DetectionNoise& noise, std::mt19937& rng) {
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(noise.min_score, noise.max_score);
  const std::size_t n = scene.objects.size();
  std::vector<int> u_min(n, frame.width), v_min(n, frame.height), u_max(n, -1), v_max(n, -1);
  std::vector<int> count(n, 0);
  for (int v = 0; v < frame.height; ++v) {
    for (int u = 0; u < frame.width; ++u) {
      const int id = frame.instance[static_cast<std::size_t>(v) * frame.width + u];
      if (id < 0) continue;
      ++count[id];
      u_min[id] = std::min(u_min[id], u);
      u_max[id] = std::max(u_max[id], u);
      v_min[id] = std::min(v_min[id], v);
      v_max[id] = std::max(v_max[id], v);
    }
  }
  std::vector<RawDetection> out;
  const Eigen::Isometry3d T_cam_world = T_world_cam.inverse();
  for (std::size_t i = 0; i < n; ++i) {
    if (count[i] < noise.min_visible_pixels) continue;
    const BoxObject& obj = scene.objects[i];
    const Eigen::Isometry3d T_cam_obj = T_cam_world * obj.T_world_obj;
    const Eigen::Vector3d dt(gauss(rng), gauss(rng), gauss(rng));
    const Eigen::Vector3d dr(gauss(rng), gauss(rng), gauss(rng));
    const Eigen::Vector3d rotvec = noise.rotation_sigma_rad * dr;
    const Eigen::Quaterniond dq =
        rotvec.norm() > 0
            ? Eigen::Quaterniond(Eigen::AngleAxisd(rotvec.norm(), rotvec.normalized()))
            : Eigen::Quaterniond::Identity();
    RawDetection d;
    d.class_name = obj.class_name;
    d.class_id = obj.class_id;
    d.score = uniform(rng);
    d.position_cam = T_cam_obj.translation() + noise.translation_sigma_m * dt;
    d.orientation_cam = (Eigen::Quaterniond(T_cam_obj.linear()) * dq).normalized();
    d.box = PixelBox{u_min[i], v_min[i], u_max[i] - u_min[i] + 1, v_max[i] - v_min[i] + 1};
    out.push_back(d);
  }
  return out;
}

}  // namespace geofusion
