#include "geofusion/simulation/sequence.h"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>

namespace geofusion {

namespace {
constexpr std::uint16_t kTableId = 1000, kFloorId = 1001;

double yawOf(const Eigen::Isometry3d& T) {
  return std::atan2(T.linear()(1, 0), T.linear()(0, 0));
}

Eigen::Isometry3d planar(double x, double y, double yaw) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(x, y, 0.0);
  return T;
}
}  // namespace

Eigen::Isometry3d RobotGeometry::baseToCameraLink(double height_m, double pan_rad,
                                                  double tilt_rad) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(0.1, 0.0, height_m);
  T.linear() = (Eigen::AngleAxisd(pan_rad, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(tilt_rad, Eigen::Vector3d::UnitY()))
                   .toRotationMatrix();
  return T;
}

Eigen::Isometry3d RobotGeometry::cameraLinkToOptical() {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Quaterniond(0.5, -0.5, 0.5, -0.5).toRotationMatrix();
  return T;
}

std::vector<FramePose> makeTrajectory(const ClutterScene& scene, const TrajectoryConfig& cfg,
                                      unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  const int n = std::max(1, cfg.frames);
  Eigen::Vector3d centre(0.0, 0.0, scene.table.height_m + 0.05);
  if (!scene.objects.empty()) {
    Eigen::Vector2d xy = Eigen::Vector2d::Zero();
    for (const auto& o : scene.objects) xy += o.T_world_obj.translation().head<2>();
    centre.head<2>() = xy / static_cast<double>(scene.objects.size());
  }
  // Progress along the arc: moving frames advance, paused frames (a few windows) do not.
  std::vector<double> step(static_cast<std::size_t>(n), 1.0);
  const int paused = static_cast<int>(cfg.pause_fraction * n);
  for (int w = 0, left = paused; w < 3 && left > 0; ++w) {
    const int len = w == 2 ? left : std::max(1, static_cast<int>(left * (0.3 + 0.3 * uni(rng))));
    const int start = static_cast<int>(uni(rng) * std::max(1, n - len));
    for (int k = start; k < std::min(n, start + len); ++k) step[k] = 0.0;
    left -= len;
  }
  step[0] = 0.0;
  double total = 0.0;
  for (double s : step) total += s;
  const double start_angle = -M_PI / 2 - 0.5 * cfg.arc_rad + 0.4 * (uni(rng) - 0.5);
  const double phase_d = 2 * M_PI * uni(rng), phase_h = 2 * M_PI * uni(rng),
               phase_turn = 2 * M_PI * uni(rng);
  std::vector<FramePose> out;
  double progress = 0.0;
  for (int k = 0; k < n; ++k) {
    progress += total > 0 ? step[k] / total : 0.0;
    const double theta = start_angle + cfg.arc_rad * progress;
    const double d =
        cfg.min_distance_m + (cfg.max_distance_m - cfg.min_distance_m) *
                                 (0.5 + 0.5 * std::sin(2.3 * M_PI * progress + phase_d));
    const double h = cfg.min_height_m + (cfg.max_height_m - cfg.min_height_m) *
                                            (0.5 + 0.5 * std::sin(1.7 * M_PI * progress + phase_h));
    const Eigen::Vector2d base_xy =
        centre.head<2>() + d * Eigen::Vector2d(std::cos(theta), std::sin(theta));
    // The base faces the table, turning a little left and right as it goes.
    const Eigen::Vector2d to_centre = centre.head<2>() - base_xy;
    const double yaw = std::atan2(to_centre.y(), to_centre.x()) +
                       0.35 * std::sin(3.1 * M_PI * progress + phase_turn);
    FramePose f;
    f.stamp_s = k / cfg.rate_hz;
    f.T_map_base = planar(base_xy.x(), base_xy.y(), yaw);
    // Head: camera at height h looking at the clutter (pan and tilt from the look-at).
    const Eigen::Vector3d eye = f.T_map_base * Eigen::Vector3d(0.1, 0.0, h);
    const double look = cfg.look_rate * progress;
    const Eigen::Vector3d target =
        centre + Eigen::Vector3d(cfg.look_amplitude_m * std::sin(5.0 * look),
                                 cfg.look_amplitude_m * std::cos(4.0 * look), 0.0);
    const Eigen::Vector3d dir = (f.T_map_base.inverse().linear() * (target - eye)).normalized();
    const double pan = std::atan2(dir.y(), dir.x());
    const double tilt = std::atan2(-dir.z(), dir.head<2>().norm());
    f.T_base_link = RobotGeometry::baseToCameraLink(h, pan, tilt);
    f.T_map_optical = f.T_map_base * f.T_base_link * RobotGeometry::cameraLinkToOptical();
    f.T_odom_base = f.T_map_base;
    out.push_back(f);
  }
  return out;
}

void addOdometryDrift(std::vector<FramePose>* poses, const OdometryNoise& noise, unsigned seed) {
  if (poses->empty()) return;
  std::mt19937 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  // Systematic errors, as wheel odometry has: a scale error and a heading bias per metre, each
  // of a random sign and a magnitude between half and all of its configured value.
  std::uniform_real_distribution<double> half_to_one(0.5, 1.0);
  auto sign = [&]() { return gauss(rng) < 0.0 ? -1.0 : 1.0; };
  const double scale = 1.0 + sign() * half_to_one(rng) * noise.translation_fraction;
  const double yaw_bias = sign() * half_to_one(rng) * noise.yaw_rad_per_m;
  const Eigen::Isometry3d start = (*poses)[0].T_map_base;
  Eigen::Isometry3d odom = start;  // odom = map at the first frame
  (*poses)[0].T_odom_base = odom;
  for (std::size_t k = 1; k < poses->size(); ++k) {
    const Eigen::Isometry3d delta = (*poses)[k - 1].T_map_base.inverse() * (*poses)[k].T_map_base;
    const double dist = delta.translation().head<2>().norm();
    const double turn = yawOf(delta);
    const double yaw_error =
        yaw_bias * dist + noise.yaw_rad_per_sqrt_rad * std::sqrt(std::abs(turn)) * gauss(rng);
    const Eigen::Vector2d t =
        scale * delta.translation().head<2>() +
        noise.translation_m_per_sqrt_m * std::sqrt(dist) * Eigen::Vector2d(gauss(rng), gauss(rng));
    odom = odom * planar(t.x(), t.y(), turn + yaw_error);
    (*poses)[k].T_odom_base = odom;
  }
}

DriftStats measureDrift(const std::vector<FramePose>& poses) {
  DriftStats s;
  for (std::size_t k = 0; k < poses.size(); ++k) {
    const double e =
        (poses[k].T_odom_base.translation() - poses[k].T_map_base.translation()).norm();
    s.max_m = std::max(s.max_m, e);
    s.final_m = e;
    if (k > 0)
      s.path_length_m +=
          (poses[k].T_map_base.translation() - poses[k - 1].T_map_base.translation()).norm();
  }
  return s;
}

DetectorModel DetectorModel::denseFusionPersistent() {
  DetectorModel m;
  // DenseFusion's per-frame error (YCB-Video ADD-S AUC 93.1, about 7 mm) split into a bias that
  // persists per object over about 30 keyframes and a smaller per-frame part; the same total.
  m.translation_sigma_m = 0.003;
  m.rotation_sigma_rad = 0.035;
  m.persistence.bias_translation_m = 0.004;
  m.persistence.bias_rotation_rad = 0.05;
  m.persistence.bias_correlation_keyframes = 30;
  m.class_swap_rate = 0.005;  // most swaps come in stretches
  m.persistence.swap_stretch_rate = 0.004;
  m.persistence.miss_stretch_rate = 0.005;
  m.persistence.phantoms = 1;
  m.persistence.score_correctness = 0.5;
  return m;
}

DetectorModel DetectorModel::rgbOnly() {
  DetectorModel m;
  // Colour-only estimators (PoseCNN colour-only ADD-S AUC 75.9 vs 93.0 with ICP; MegaPose BOP AR
  // 0.601 RGB vs 0.758 RGB-D on YCB-V): the error is mostly along the viewing ray, 3 % of the
  // distance (2.1-3.6 cm at 0.7-1.2 m) with its sign held for about 120 keyframes; lateral and
  // rotation errors much smaller; look-alikes confused in stretches; persistent phantoms.
  m.translation_sigma_m = 0.003;
  m.rotation_sigma_rad = 0.04;
  m.gross_error_rate = 0.05;
  m.class_swap_rate = 0.005;
  m.miss_rate = 0.05;
  m.false_positives_per_frame = 0.5;
  m.persistence.bias_translation_m = 0.003;
  m.persistence.bias_rotation_rad = 0.06;
  m.persistence.bias_correlation_keyframes = 40;
  m.persistence.ray_depth_fraction = 0.03;
  m.persistence.ray_correlation_keyframes = 120;
  m.persistence.swap_stretch_rate = 0.01;
  m.persistence.miss_stretch_rate = 0.01;
  m.persistence.phantoms = 2;
  m.persistence.score_correctness = 0.3;
  return m;
}

const std::vector<std::string>& DetectorModel::names() {
  static const std::vector<std::string> names{"densefusion", "posecnn", "densefusion_persistent",
                                              "rgb"};
  return names;
}

bool DetectorModel::byName(const std::string& name, DetectorModel* model) {
  if (name == "densefusion")
    *model = denseFusion();
  else if (name == "posecnn")
    *model = posecnn();
  else if (name == "densefusion_persistent")
    *model = denseFusionPersistent();
  else if (name == "rgb")
    *model = rgbOnly();
  else
    return false;
  return true;
}

DetectorModel DetectorModel::posecnn() {
  DetectorModel m;
  // PoseCNN without ICP: YCB-Video ADD-S AUC 75.9, a mean clipped ADD-S of about 24 mm.
  m.translation_sigma_m = 0.017;
  m.rotation_sigma_rad = 0.18;
  m.gross_error_rate = 0.09;
  m.class_swap_rate = 0.04;
  m.miss_rate = 0.06;
  m.false_positives_per_frame = 0.6;
  return m;
}

std::pair<std::string, std::string> writeBackgroundTextures(const std::string& dir,
                                                            std::string* error) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  const int n = 1024;
  cv::RNG rng(20201102);
  // Sum of smooth random fields at several scales (value noise), in [0, 1].
  auto noise = [&](std::initializer_list<int> cells, double stretch_x) {
    cv::Mat sum = cv::Mat::zeros(n, n, CV_32F);
    double weight = 0.0, w = 1.0;
    for (int c : cells) {
      cv::Mat small(c, std::max(2, static_cast<int>(c * stretch_x)), CV_32F), big;
      rng.fill(small, cv::RNG::UNIFORM, 0.0, 1.0);
      cv::resize(small, big, cv::Size(n, n), 0, 0, cv::INTER_CUBIC);
      sum += w * big;
      weight += w;
      w *= 0.6;
    }
    return cv::Mat(sum / weight);
  };
  // Wood: grain stretched along x, knots and fine fibres.
  cv::Mat grain = noise({6, 24, 96, 256}, 0.15), fibres = noise({512}, 1.0);
  cv::Mat table(n, n, CV_8UC3), floor(n, n, CV_8UC3);
  for (int v = 0; v < n; ++v) {
    for (int u = 0; u < n; ++u) {
      const float g = grain.at<float>(v, u), f = fibres.at<float>(v, u);
      const float k = std::clamp(0.55f + 0.9f * (g - 0.5f) + 0.35f * (f - 0.5f), 0.f, 1.2f);
      table.at<cv::Vec3b>(v, u) =
          cv::Vec3b(cv::saturate_cast<uchar>(70 * k), cv::saturate_cast<uchar>(115 * k),
                    cv::saturate_cast<uchar>(158 * k));  // BGR
    }
  }
  // Floor: 40 cm tiles of speckled grey with dark joints.
  cv::Mat speckle = noise({32, 128, 512}, 1.0);
  for (int v = 0; v < n; ++v) {
    for (int u = 0; u < n; ++u) {
      const bool joint = (u % 51) < 2 || (v % 51) < 2;
      const float s = speckle.at<float>(v, u);
      const uchar c = joint ? 40 : cv::saturate_cast<uchar>(60 + 150 * s);
      floor.at<cv::Vec3b>(v, u) = cv::Vec3b(c, c, cv::saturate_cast<uchar>(c + 8));
    }
  }
  const std::string table_path = dir + "/table_wood.png", floor_path = dir + "/floor_tiles.png";
  if (!cv::imwrite(table_path, table) || !cv::imwrite(floor_path, floor)) {
    if (error) *error = "cannot write the background textures into " + dir;
    return {};
  }
  return {table_path, floor_path};
}

SequenceRenderer::SequenceRenderer(const ClutterScene& scene, const PinholeIntrinsics& K,
                                   const std::pair<std::string, std::string>& textures)
    : scene_(scene), K_(K) {
  for (const auto& o : scene.objects) object_meshes_.push_back(renderer_.addMesh(o.model->mesh));
  TriangleMesh table = scene.table.model().mesh;
  TriangleMesh floor = makeBox(Eigen::Vector3d(8.0, 8.0, 0.02));
  if (!textures.first.empty() && table.uvs.size() == table.vertices.size())
    table.texture_path = textures.first;
  if (!textures.second.empty()) floor.texture_path = textures.second;
  table_mesh_ = renderer_.addMesh(table);
  floor_mesh_ = renderer_.addMesh(floor);
}

namespace {

// The look-alike class of `name` in the model set ("" when it has none).
std::string lookAlikeOf(const DetectorModel& detector, const ModelSet& models,
                        const std::string& name) {
  std::string found;
  for (const auto& pair : detector.look_alikes) {
    const std::string other = pair.first == name    ? pair.second
                              : pair.second == name ? pair.first
                                                    : "";
    if (!other.empty() && models.find(other)) found = other;
  }
  return found;
}

}  // namespace

// The random draws of one frame's synthetic detections: one generator and one normal
// distribution shared by every draw (the normal distribution keeps a second value between calls,
// so the draws of a frame depend on their order, which is fixed).
struct SequenceRenderer::Draws {
  std::mt19937& rng;
  std::uniform_real_distribution<double> uni{0.0, 1.0};
  std::normal_distribution<double> gauss{0.0, 1.0};
  double u() { return uni(rng); }
  double g() { return gauss(rng); }
};

SequenceFrame SequenceRenderer::render(const FramePose& pose, const DepthNoise& depth_noise,
                                       const DetectorModel& detector, const ModelSet& models,
                                       std::mt19937& rng, int frame) {
  SequenceFrame f;
  const Eigen::Isometry3d T_cam_map = pose.T_map_optical.inverse();
  const std::vector<RenderItem> items = sceneItems(T_cam_map, frame);
  renderer_.render(
      K_, items, &f.images, PixelBox{},
      OffscreenRenderer::kDepth | OffscreenRenderer::kInstance | OffscreenRenderer::kColor);
  f.clean_depth = f.images.depth;
  std::vector<SurfaceMaterial> material_of(scene_.objects.size() + 1, SurfaceMaterial::kDiffuse);
  for (std::size_t i = 0; i < scene_.objects.size(); ++i)
    material_of[i + 1] = scene_.objects[i].model->material;
  applyDepthNoise(K_, depth_noise, rng, &f.images.depth, &f.images.instance, &material_of);
  const std::vector<PixelBox> boxes = measureVisibility(items, T_cam_map, frame, &f);
  stepPersistentErrors(detector, models, rng);
  Draws draws{rng};
  detectObjects(T_cam_map, boxes, detector, models, &draws, &f);
  addFalsePositives(pose, boxes, detector, models, &draws, &f);
  addPhantoms(T_cam_map, boxes, detector, models, &draws, &f);
  return f;
}

// The detector's persistent errors move on by one keyframe (started at the first frame; nothing
// is drawn for a detector without them, so the independent presets' data stay as they were).
void SequenceRenderer::stepPersistentErrors(const DetectorModel& detector, const ModelSet& models,
                                            std::mt19937& rng) {
  if (!detector.persistence.enabled()) return;
  if (!errors_) {
    std::vector<bool> has_look_alike;
    for (const SceneObject& o : scene_.objects)
      has_look_alike.push_back(!lookAlikeOf(detector, models, o.model->name).empty());
    errors_ = std::make_unique<PersistentErrors>(detector.persistence, has_look_alike, rng);
  }
  errors_->step(rng);
}

// What the camera sees: the table, the floor and the objects (instance ids: object index + 1).
std::vector<RenderItem> SequenceRenderer::sceneItems(const Eigen::Isometry3d& T_cam_map,
                                                     int frame) const {
  std::vector<RenderItem> items;
  RenderItem table;
  table.mesh = table_mesh_;
  table.T_cam_model = T_cam_map * scene_.table.pose();
  table.instance_id = kTableId;
  table.color = Eigen::Vector3f(0.62f, 0.45f, 0.28f);
  items.push_back(table);
  RenderItem floor;
  floor.mesh = floor_mesh_;
  floor.T_cam_model = T_cam_map * Eigen::Translation3d(0, 0, -0.01);
  floor.instance_id = kFloorId;
  floor.color = Eigen::Vector3f(0.45f, 0.45f, 0.48f);
  items.push_back(floor);
  for (std::size_t i = 0; i < scene_.objects.size(); ++i) {
    if (!scene_.objects[i].presentAt(frame)) continue;
    RenderItem it;
    it.mesh = object_meshes_[i];
    it.T_cam_model = T_cam_map * scene_.objects[i].T_world_obj;
    it.instance_id = static_cast<std::uint16_t>(i + 1);
    items.push_back(it);
  }
  return items;
}

// Visibility of each object: its pixels in the scene against its pixels alone (rendered again in
// its region); for an object taken away, how much of its old place the camera sees (its pixels
// alone at its old pose that nothing in the scene hides). Returns each object's box of visible
// pixels.
std::vector<PixelBox> SequenceRenderer::measureVisibility(const std::vector<RenderItem>& items,
                                                          const Eigen::Isometry3d& T_cam_map,
                                                          int frame_index, SequenceFrame* frame) {
  SequenceFrame& f = *frame;
  const std::size_t n = scene_.objects.size();
  f.visible_pixels.assign(n, 0);
  f.visible_fraction.assign(n, 0.0);
  f.place_visible_fraction.assign(n, -1.0);
  std::vector<PixelBox> boxes(n);
  std::vector<int> x0(n, K_.width), y0(n, K_.height), x1(n, -1), y1(n, -1);
  for (int v = 0; v < K_.height; ++v) {
    for (int u = 0; u < K_.width; ++u) {
      const int id = f.images.instance[static_cast<std::size_t>(v) * K_.width + u];
      if (id < 1 || id > static_cast<int>(n)) continue;
      const std::size_t i = static_cast<std::size_t>(id - 1);
      ++f.visible_pixels[i];
      x0[i] = std::min(x0[i], u), y0[i] = std::min(y0[i], v);
      x1[i] = std::max(x1[i], u), y1[i] = std::max(y1[i], v);
    }
  }
  // The render item of each object by its instance id (objects not there have none).
  std::vector<const RenderItem*> item_of(n, nullptr);
  for (const RenderItem& it : items)
    if (it.instance_id >= 1 && it.instance_id <= n) item_of[it.instance_id - 1u] = &it;
  RenderedImages alone;
  for (std::size_t i = 0; i < n; ++i) {
    const SceneObject& o = scene_.objects[i];
    const bool taken_away =
        !o.presentAt(frame_index) && frame_index >= o.present_until_frame && !o.presentAtTheEnd();
    if (f.visible_pixels[i] == 0 && !taken_away) continue;
    RenderItem it;
    if (item_of[i]) {
      it = *item_of[i];
    } else {
      it.mesh = object_meshes_[i];
      it.T_cam_model = T_cam_map * o.T_world_obj;
    }
    const PixelBox region = renderer_.projectedRegion(K_, it.mesh, it.T_cam_model);
    if (region.width <= 0 || region.height <= 0) continue;
    renderer_.render(K_, {it}, &alone, region, OffscreenRenderer::kDepth);
    int own = 0, unhidden = 0;
    for (int y = 0; y < region.height; ++y) {
      for (int x = 0; x < region.width; ++x) {
        const float z = alone.depth[static_cast<std::size_t>(y) * region.width + x];
        if (!(z > 0.f)) continue;
        ++own;
        const float scene_z =
            f.clean_depth[static_cast<std::size_t>(region.y + y) * K_.width + region.x + x];
        unhidden += !(scene_z > 0.f) || scene_z > z - 0.005f;
      }
    }
    if (taken_away) {
      f.place_visible_fraction[i] = own > 0 ? static_cast<double>(unhidden) / own : 0.0;
      continue;
    }
    boxes[i] = PixelBox{x0[i], y0[i], x1[i] - x0[i] + 1, y1[i] - y0[i] + 1};
    f.visible_fraction[i] =
        own > 0 ? std::min(1.0, static_cast<double>(f.visible_pixels[i]) / own) : 0.0;
  }
  f.visible_boxes = boxes;
  return boxes;
}

// True detections of the visible objects, with the detector model's misses (more when occluded),
// symmetric flips, gross errors, pose noise (per-class gain), look-alike class swaps and scores.
void SequenceRenderer::detectObjects(const Eigen::Isometry3d& T_cam_map,
                                     const std::vector<PixelBox>& boxes,
                                     const DetectorModel& detector, const ModelSet& models,
                                     Draws* draws, SequenceFrame* frame) const {
  SequenceFrame& f = *frame;
  const std::size_t n = scene_.objects.size();
  auto uni = [&](std::mt19937&) { return draws->u(); };
  auto gauss = [&](std::mt19937&) { return draws->g(); };
  std::mt19937& rng = draws->rng;
  auto random_rotation = [&]() {
    Eigen::Quaterniond q(gauss(rng), gauss(rng), gauss(rng), gauss(rng));
    return q.normalized().toRotationMatrix();
  };
  for (std::size_t i = 0; i < n; ++i) {
    const ObjectModel& model = *scene_.objects[i].model;
    if (f.visible_pixels[i] < detector.min_visible_pixels) continue;
    if (errors_ && errors_->missed(i)) continue;  // a missed stretch
    const double occluded = 1.0 - f.visible_fraction[i];
    if (uni(rng) < detector.miss_rate + detector.miss_occlusion_gain * occluded * occluded)
      continue;
    double gain = 1.0;
    for (const auto& g : detector.class_noise_gain)
      if (g.first == model.name) gain = g.second;
    Eigen::Isometry3d T = T_cam_map * scene_.objects[i].T_world_obj;
    // The detector reads the texture: it confuses only what looks alike (the appearance's
    // symmetries; a labelled can's angle about its axis it sees).
    const Symmetry& looks = model.appearance_symmetry;
    if (looks.type == Symmetry::Type::kDiscrete && !looks.rotations.empty() &&
        uni(rng) < detector.symmetric_flip_rate) {
      const auto& q = looks.rotations[static_cast<std::size_t>(uni(rng) * looks.rotations.size()) %
                                      looks.rotations.size()];
      T.linear() = T.linear() * q.toRotationMatrix();
    } else if (looks.type == Symmetry::Type::kContinuous) {
      T.linear() =
          T.linear() * Eigen::AngleAxisd(2 * M_PI * uni(rng), looks.axis).toRotationMatrix();
    }
    if (errors_) T = errors_->apply(i, T);  // the persistent bias, then the frame's own error
    if (uni(rng) < detector.gross_error_rate) {
      const Eigen::Vector3d dir = Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng)).normalized();
      T.translation() += (0.03 + 0.07 * uni(rng)) * dir;
      T.linear() = random_rotation();
    } else {
      T.translation() +=
          gain * detector.translation_sigma_m * Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng));
      const Eigen::Vector3d w =
          gain * detector.rotation_sigma_rad * Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng));
      T.linear() = Eigen::AngleAxisd(w.norm(), w.norm() > 0 ? Eigen::Vector3d(w.normalized())
                                                            : Eigen::Vector3d::UnitZ()) *
                   T.linear();
    }
    RawDetection d;
    d.class_name = model.name;
    d.class_id = model.id;
    const bool swap_stretch = errors_ && errors_->swapped(i);
    if (swap_stretch || uni(rng) < detector.class_swap_rate) {
      const std::string other = lookAlikeOf(detector, models, model.name);
      if (!other.empty()) {
        d.class_name = other;
        d.class_id = models.find(other)->id;
        f.swapped.push_back(static_cast<int>(i));
      }
    }
    const double c = detector.persistence.score_correctness;
    const double confident = c < 1.0 ? 0.6 + 0.38 * uni(rng) : 0.0;  // whatever the error
    d.score = std::clamp(
        c * (0.55 + 0.4 * (1.0 - occluded)) + (1.0 - c) * confident + 0.08 * gauss(rng), 0.05, 1.0);
    d.position_cam = T.translation();
    d.orientation_cam = Eigen::Quaterniond(T.linear());
    d.box = boxes[i];
    f.detections.push_back(d);
    f.detection_truth.push_back(static_cast<int>(i));
  }
}

// Phantoms (persistent false objects): each one that is on, beside its visible host, reported in
// `phantom_presence` of the keyframes, at the same place in the world every time.
PhantomObject SequenceRenderer::phantomOf(const PersistentErrors::Phantom& p,
                                          const ModelSet& models) const {
  PhantomObject o;
  o.host = p.host;
  const auto& m = models.models()[static_cast<std::size_t>(p.class_pick) % models.size()];
  o.class_name = m->name;
  o.T_world_obj = scene_.objects[static_cast<std::size_t>(p.host)].T_world_obj;
  o.T_world_obj.translation() += p.offset_world;
  o.T_world_obj.linear() =
      Eigen::AngleAxisd(p.yaw_rad, Eigen::Vector3d::UnitZ()) * o.T_world_obj.linear();
  return o;
}

std::vector<PhantomObject> SequenceRenderer::phantoms(const ModelSet& models) const {
  std::vector<PhantomObject> out;
  if (!errors_ || models.size() == 0) return out;
  for (const PersistentErrors::Phantom& p : errors_->phantoms())
    out.push_back(phantomOf(p, models));
  return out;
}

void SequenceRenderer::addPhantoms(const Eigen::Isometry3d& T_cam_map,
                                   const std::vector<PixelBox>& boxes,
                                   const DetectorModel& detector, const ModelSet& models,
                                   Draws* draws, SequenceFrame* frame) const {
  if (!errors_ || models.size() == 0) return;
  const std::vector<PersistentErrors::Phantom>& all = errors_->phantoms();
  for (std::size_t k = 0; k < all.size(); ++k) {
    const PersistentErrors::Phantom& p = all[k];
    const std::size_t host = static_cast<std::size_t>(p.host);
    if (!p.on || frame->visible_pixels[host] < detector.min_visible_pixels) continue;
    if (draws->u() >= detector.persistence.phantom_presence) continue;
    const PhantomObject phantom = phantomOf(p, models);
    const ObjectModel& m = *models.find(phantom.class_name);
    const Eigen::Isometry3d T = T_cam_map * phantom.T_world_obj;
    RawDetection d;
    d.class_name = m.name;
    d.class_id = m.id;
    d.score = std::clamp(0.75 + 0.1 * draws->g(), 0.05, 1.0);  // as confident as a true one
    d.position_cam = T.translation();
    d.orientation_cam = Eigen::Quaterniond(T.linear());
    d.box = boxes[host];
    frame->detections.push_back(d);
    frame->detection_truth.push_back(-2 - static_cast<int>(k));
  }
}

// False positives: on or beside a visible object, often a symmetric class.
void SequenceRenderer::addFalsePositives(const FramePose& pose, const std::vector<PixelBox>& boxes,
                                         const DetectorModel& detector, const ModelSet& models,
                                         Draws* draws, SequenceFrame* frame) const {
  SequenceFrame& f = *frame;
  const std::size_t n = scene_.objects.size();
  const Eigen::Isometry3d T_cam_map = pose.T_map_optical.inverse();
  auto uni = [&](std::mt19937&) { return draws->u(); };
  auto gauss = [&](std::mt19937&) { return draws->g(); };
  std::mt19937& rng = draws->rng;
  std::poisson_distribution<int> fp_count(detector.false_positives_per_frame);
  std::vector<std::size_t> visible;
  for (std::size_t i = 0; i < n; ++i)
    if (f.visible_pixels[i] >= detector.min_visible_pixels) visible.push_back(i);
  std::vector<std::shared_ptr<const ObjectModel>> symmetric;
  for (const auto& m : models.models())
    if (m->symmetry.type != Symmetry::Type::kNone) symmetric.push_back(m);
  for (int k = fp_count(rng); k > 0 && !visible.empty(); --k) {
    const std::size_t host =
        visible[static_cast<std::size_t>(uni(rng) * visible.size()) % visible.size()];
    const auto& pool = (!symmetric.empty() && uni(rng) < 0.6) ? symmetric : models.models();
    const auto& m = pool[static_cast<std::size_t>(uni(rng) * pool.size()) % pool.size()];
    Eigen::Isometry3d T = T_cam_map * scene_.objects[host].T_world_obj;
    const double a = 2 * M_PI * uni(rng);
    T.translation() += pose.T_map_optical.inverse().linear() *
                       ((0.03 + 0.05 * uni(rng)) * Eigen::Vector3d(std::cos(a), std::sin(a), 0.0));
    T.linear() =
        T.linear() *
        Eigen::AngleAxisd(2 * M_PI * uni(rng), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    RawDetection d;
    d.class_name = m->name;
    d.class_id = m->id;
    d.score = std::clamp(0.5 + 0.15 * gauss(rng), 0.05, 0.95);
    d.position_cam = T.translation();
    d.orientation_cam = Eigen::Quaterniond(T.linear());
    d.box = boxes[host];
    f.detections.push_back(d);
    f.detection_truth.push_back(-1);
  }
}

}  // namespace geofusion
