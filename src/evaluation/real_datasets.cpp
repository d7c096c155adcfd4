// Readers of real RGB-D datasets (BOP / YCB-Video, 7-Scenes, TUM RGB-D) and detections made from
// their ground truth. See real_datasets.h and docs/dataset.md ("Real recordings").
#include "geofusion/evaluation/real_datasets.h"

#include "geofusion/model/object_model.h"
#include "geofusion/render/renderer.h"

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

namespace geofusion {
namespace {

namespace fs = std::filesystem;

std::string padded(int number) {
  char buf[16];
  std::snprintf(buf, sizeof(buf), "%06d", number);
  return buf;
}

std::string firstExisting(const std::vector<fs::path>& candidates) {
  for (const fs::path& p : candidates) {
    if (fs::is_regular_file(p)) return p.string();
  }
  return "";
}

nlohmann::json readJson(const fs::path& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path.string());
  try {
    return nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(path.string() + ": " + e.what());
  }
}

Eigen::Isometry3d poseOf(const nlohmann::json& R, const nlohmann::json& t, double t_scale,
                         const std::string& what) {
  if (!R.is_array() || R.size() != 9 || !t.is_array() || t.size() != 3) {
    throw std::runtime_error(what + ": R needs 9 numbers and t 3");
  }
  Eigen::Matrix3d rot;
  for (int k = 0; k < 9; ++k) rot(k / 3, k % 3) = R[k].get<double>();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  // Orthonormalise: the files keep 8-16 digits.
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(rot, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d ortho = svd.matrixU() * svd.matrixV().transpose();
  if (ortho.determinant() < 0.0 || (ortho - rot).norm() > 1e-3) {
    throw std::runtime_error(what + ": R is not a rotation");
  }
  T.linear() = ortho;
  for (int k = 0; k < 3; ++k) T.translation()[k] = t[k].get<double>() * t_scale;
  if (!T.matrix().allFinite()) throw std::runtime_error(what + ": not finite");
  return T;
}

PinholeIntrinsics intrinsicsOf(const nlohmann::json& cam_K, int width, int height) {
  if (!cam_K.is_array() || cam_K.size() != 9) throw std::runtime_error("cam_K needs 9 numbers");
  PinholeIntrinsics K;
  K.width = width;
  K.height = height;
  K.fx = cam_K[0].get<double>();
  K.cx = cam_K[2].get<double>();
  K.fy = cam_K[4].get<double>();
  K.cy = cam_K[5].get<double>();
  if (!K.valid()) throw std::runtime_error("cam_K: focal lengths must be positive");
  return K;
}

bool imageSize(const std::string& path, int* width, int* height, std::string* error) {
  const cv::Mat image = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (image.empty()) {
    *error = "cannot read image " + path;
    return false;
  }
  *width = image.cols;
  *height = image.rows;
  return true;
}

/// BOP's camera of one frame, from scene_camera.json's entry.
void readBopCamera(const nlohmann::json& cam, int width, int height, RealFrame* f) {
  f->K = intrinsicsOf(cam.at("cam_K"), width, height);
  f->depth_unit_m = cam.value("depth_scale", 1.0) * 1e-3;  // BOP: value x depth_scale = mm
  if (cam.contains("cam_R_w2c") && cam.contains("cam_t_w2c")) {
    f->T_world_cam =
        poseOf(cam["cam_R_w2c"], cam["cam_t_w2c"], 1e-3, "frame " + f->name + " cam_R_w2c")
            .inverse();
    f->has_camera_pose = true;
  } else if (cam.contains("ycbv_rotation_translation_matrix_3x4")) {
    // YCB-Video's meta.mat rotation_translation_matrix: world -> camera, metres.
    const nlohmann::json& m = cam["ycbv_rotation_translation_matrix_3x4"];
    nlohmann::json R = nlohmann::json::array(), t = nlohmann::json::array();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) R.push_back(m.at(r).at(c));
      t.push_back(m.at(r).at(3));
    }
    f->T_world_cam =
        poseOf(R, t, 1.0, "frame " + f->name + " rotation_translation_matrix").inverse();
    f->has_camera_pose = true;
  }
}

void readBopObjects(const nlohmann::json& gt, const nlohmann::json* info, RealFrame* f) {
  for (std::size_t k = 0; k < gt.size(); ++k) {
    RealObjectTruth o;
    o.obj_id = gt[k].at("obj_id").get<int>();
    o.T_cam_obj = poseOf(gt[k].at("cam_R_m2c"), gt[k].at("cam_t_m2c"), 1e-3,
                         "frame " + f->name + " object " + std::to_string(k));
    if (info && k < info->size()) {
      const nlohmann::json& in = (*info)[k];
      o.visible_pixels = in.value("px_count_visib", -1);
      o.visible_fraction = in.value("visib_fract", -1.0);
      if (in.contains("bbox_visib") && in["bbox_visib"].size() == 4) {
        const nlohmann::json& b = in["bbox_visib"];
        o.visible_box =
            PixelBox{b[0].get<int>(), b[1].get<int>(), b[2].get<int>(), b[3].get<int>()};
      }
    }
    f->objects.push_back(o);
  }
}

}  // namespace

bool readBopScene(const std::string& dir, double fps, RealSequence* sequence, std::string* error) {
  try {
    const fs::path root(dir);
    const nlohmann::json cameras = readJson(root / "scene_camera.json");
    const fs::path gt_path = root / "scene_gt.json";
    const nlohmann::json gt = fs::exists(gt_path) ? readJson(gt_path) : nlohmann::json::object();
    const fs::path info_path = root / "scene_gt_info.json";
    const nlohmann::json info =
        fs::exists(info_path) ? readJson(info_path) : nlohmann::json::object();
    std::vector<int> ids;
    for (auto it = cameras.begin(); it != cameras.end(); ++it) ids.push_back(std::stoi(it.key()));
    std::sort(ids.begin(), ids.end());
    if (ids.empty()) throw std::runtime_error("scene_camera.json lists no frame");
    if (!(fps > 0.0)) throw std::runtime_error("the frame rate must be positive");
    RealSequence s;
    s.dir = dir;
    s.name = fs::absolute(root).lexically_normal().filename().string();
    if (s.name.empty()) s.name = fs::absolute(root).parent_path().filename().string();
    int width = 0, height = 0;
    for (int id : ids) {
      const std::string key = std::to_string(id), stem = padded(id);
      RealFrame f;
      f.index = static_cast<int>(s.frames.size());
      f.name = key;
      f.stamp_s = id / fps;
      f.rgb_path = firstExisting({root / "rgb" / (stem + ".png"), root / "rgb" / (stem + ".jpg"),
                                  root / (stem + "-color.png"), root / (stem + "-color.jpg")});
      f.depth_path =
          firstExisting({root / "depth" / (stem + ".png"), root / (stem + "-depth.png")});
      f.label_path = firstExisting({root / (stem + "-label.png")});
      if (f.rgb_path.empty() || f.depth_path.empty()) {
        throw std::runtime_error("frame " + key + ": no colour or depth image (rgb/" + stem +
                                 ".png, depth/" + stem + ".png or " + stem + "-color.png, " + stem +
                                 "-depth.png)");
      }
      if (s.frames.empty()) {
        s.format = f.depth_path.find("-depth.png") != std::string::npos ? "ycbv" : "bop";
        std::string size_error;
        if (!imageSize(f.depth_path, &width, &height, &size_error)) {
          throw std::runtime_error(size_error);
        }
      }
      readBopCamera(cameras.at(key), width, height, &f);
      if (gt.contains(key)) readBopObjects(gt[key], info.contains(key) ? &info[key] : nullptr, &f);
      s.frames.push_back(f);
    }
    *sequence = std::move(s);
    return true;
  } catch (const std::exception& e) {
    *error = "BOP scene " + dir + ": " + e.what();
    return false;
  }
}

namespace {

Eigen::Isometry3d readMatrix4(const fs::path& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path.string());
  Eigen::Matrix4d m;
  for (int k = 0; k < 16; ++k) {
    if (!(in >> m(k / 4, k % 4))) throw std::runtime_error(path.string() + ": needs 16 numbers");
  }
  if (!m.allFinite()) throw std::runtime_error(path.string() + ": not finite");
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(m.topLeftCorner<3, 3>(),
                                        Eigen::ComputeFullU | Eigen::ComputeFullV);
  T.linear() = svd.matrixU() * svd.matrixV().transpose();
  T.translation() = m.topRightCorner<3, 1>();
  return T;
}

}  // namespace

bool readSevenScenes(const std::string& dir, RealSequence* sequence, std::string* error) {
  try {
    const fs::path root(dir);
    std::ifstream kin(root / "camera-intrinsics.txt");
    Eigen::Matrix3d Km = Eigen::Matrix3d::Zero();
    bool have_k = static_cast<bool>(kin);
    for (int k = 0; have_k && k < 9; ++k) have_k = static_cast<bool>(kin >> Km(k / 3, k % 3));
    RealSequence s;
    s.format = "7scenes";
    s.dir = dir;
    s.name = fs::absolute(root).lexically_normal().filename().string();
    std::vector<int> numbers;
    for (const auto& entry : fs::directory_iterator(root)) {
      const std::string name = entry.path().filename().string();
      int n = 0;
      char tail[32] = {0};
      if (std::sscanf(name.c_str(), "frame-%d.%31s", &n, tail) == 2 &&
          std::string(tail) == "depth.png") {
        numbers.push_back(n);
      }
    }
    std::sort(numbers.begin(), numbers.end());
    if (numbers.empty()) throw std::runtime_error("no frame-NNNNNN.depth.png");
    int width = 0, height = 0;
    for (int n : numbers) {
      const std::string stem = "frame-" + padded(n);
      RealFrame f;
      f.index = static_cast<int>(s.frames.size());
      f.name = padded(n);
      f.stamp_s = n / 30.0;  // the Kinect's 30 Hz
      f.depth_path = (root / (stem + ".depth.png")).string();
      f.rgb_path = firstExisting({root / (stem + ".color.png"), root / (stem + ".color.jpg")});
      if (f.rgb_path.empty()) throw std::runtime_error(stem + ": no colour image");
      if (s.frames.empty()) {
        std::string size_error;
        if (!imageSize(f.depth_path, &width, &height, &size_error)) {
          throw std::runtime_error(size_error);
        }
      }
      f.K.width = width;
      f.K.height = height;
      // 7-Scenes' published intrinsics are the depth camera's (used for both images).
      f.K.fx = have_k ? Km(0, 0) : 585.0;
      f.K.fy = have_k ? Km(1, 1) : 585.0;
      f.K.cx = have_k ? Km(0, 2) : 320.0;
      f.K.cy = have_k ? Km(1, 2) : 240.0;
      f.depth_unit_m = 0.001;
      f.depth_invalid = 65535;
      const fs::path pose = root / (stem + ".pose.txt");
      if (fs::exists(pose)) {
        f.T_world_cam = readMatrix4(pose);
        f.has_camera_pose = true;
      }
      s.frames.push_back(f);
    }
    *sequence = std::move(s);
    return true;
  } catch (const std::exception& e) {
    *error = "7-Scenes sequence " + dir + ": " + e.what();
    return false;
  }
}

namespace {

/// TUM's "stamp path" lists (rgb.txt, depth.txt); '#' lines are comments.
std::vector<std::pair<double, std::string>> readTumList(const fs::path& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path.string());
  std::vector<std::pair<double, std::string>> rows;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (line.empty() || line[0] == '#') continue;
    std::istringstream row(line);
    double stamp = 0.0;
    std::string file;
    if (!(row >> stamp >> file)) {
      throw std::runtime_error(path.string() + " line " + std::to_string(number) +
                               ": expected 'stamp file'");
    }
    rows.emplace_back(stamp, file);
  }
  return rows;
}

struct StampedPose {
  double stamp = 0.0;
  Eigen::Vector3d t;
  Eigen::Quaterniond q;
};

std::vector<StampedPose> readTumTrajectory(const fs::path& path) {
  std::vector<StampedPose> poses;
  std::ifstream in(path);
  if (!in) return poses;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream row(line);
    StampedPose p;
    double qx, qy, qz, qw;
    if (!(row >> p.stamp >> p.t.x() >> p.t.y() >> p.t.z() >> qx >> qy >> qz >> qw)) continue;
    p.q = Eigen::Quaterniond(qw, qx, qy, qz);
    if (!(p.q.norm() > 0.5) || !p.t.allFinite()) continue;
    p.q.normalize();
    poses.push_back(p);
  }
  return poses;
}

/// The trajectory at `stamp`, interpolated between the two poses around it when they are at most
/// `max_gap_s` apart. False outside.
bool poseAt(const std::vector<StampedPose>& poses, double stamp, double max_gap_s,
            Eigen::Isometry3d* T) {
  const auto after = std::lower_bound(poses.begin(), poses.end(), stamp,
                                      [](const StampedPose& p, double s) { return p.stamp < s; });
  if (after == poses.begin() || after == poses.end()) return false;
  const StampedPose& b = *after;
  const StampedPose& a = *(after - 1);
  if (b.stamp - a.stamp > max_gap_s) return false;
  const double w = (stamp - a.stamp) / std::max(b.stamp - a.stamp, 1e-9);
  T->setIdentity();
  T->linear() = a.q.slerp(w, b.q).toRotationMatrix();
  T->translation() = (1.0 - w) * a.t + w * b.t;
  return true;
}

/// TUM RGB-D's published intrinsics of the three Freiburg Kinects (the ROS default otherwise).
PinholeIntrinsics tumIntrinsics(const std::string& name, int width, int height) {
  PinholeIntrinsics K;
  K.width = width;
  K.height = height;
  if (name.find("freiburg1") != std::string::npos) {
    K.fx = 517.3, K.fy = 516.5, K.cx = 318.6, K.cy = 255.3;
  } else if (name.find("freiburg2") != std::string::npos) {
    K.fx = 520.9, K.fy = 521.0, K.cx = 325.1, K.cy = 249.7;
  } else if (name.find("freiburg3") != std::string::npos) {
    K.fx = 535.4, K.fy = 539.2, K.cx = 320.1, K.cy = 247.6;
  } else {
    K.fx = 525.0, K.fy = 525.0, K.cx = 319.5, K.cy = 239.5;
  }
  return K;
}

}  // namespace

bool readTumRgbd(const std::string& dir, RealSequence* sequence, std::string* error) {
  try {
    const fs::path root(dir);
    const auto rgb = readTumList(root / "rgb.txt");
    const auto depth = readTumList(root / "depth.txt");
    const std::vector<StampedPose> truth = readTumTrajectory(root / "groundtruth.txt");
    if (rgb.empty() || depth.empty()) throw std::runtime_error("rgb.txt or depth.txt is empty");
    RealSequence s;
    s.format = "tum";
    s.dir = dir;
    s.name = fs::absolute(root).lexically_normal().filename().string();
    int width = 0, height = 0;
    std::string size_error;
    if (!imageSize((root / depth.front().second).string(), &width, &height, &size_error)) {
      throw std::runtime_error(size_error);
    }
    const PinholeIntrinsics K = tumIntrinsics(s.name, width, height);
    // Each colour image with the nearest depth image within 20 ms (TUM's associate.py).
    std::size_t d = 0;
    for (const auto& [stamp, file] : rgb) {
      while (d + 1 < depth.size() &&
             std::abs(depth[d + 1].first - stamp) <= std::abs(depth[d].first - stamp)) {
        ++d;
      }
      if (std::abs(depth[d].first - stamp) > 0.02) continue;
      RealFrame f;
      f.index = static_cast<int>(s.frames.size());
      char name[32];
      std::snprintf(name, sizeof(name), "%.6f", stamp);
      f.name = name;
      f.stamp_s = stamp;
      f.rgb_path = (root / file).string();
      f.depth_path = (root / depth[d].second).string();
      f.K = K;
      f.depth_unit_m = 1.0 / 5000.0;  // TUM: 5000 units a metre
      f.has_camera_pose = poseAt(truth, stamp, 0.05, &f.T_world_cam);
      s.frames.push_back(f);
    }
    if (s.frames.empty())
      throw std::runtime_error("no colour image has a depth image within 20 ms");
    *sequence = std::move(s);
    return true;
  } catch (const std::exception& e) {
    *error = "TUM RGB-D sequence " + dir + ": " + e.what();
    return false;
  }
}

bool readRealSequence(const std::string& dir, const std::string& format, double fps,
                      RealSequence* sequence, std::string* error) {
  std::string f = format;
  if (f == "auto") {
    const fs::path root(dir);
    if (fs::exists(root / "scene_camera.json")) {
      f = "bop";
    } else if (fs::exists(root / "rgb.txt") && fs::exists(root / "depth.txt")) {
      f = "tum";
    } else if (fs::exists(root / "frame-000000.depth.png") ||
               fs::exists(root / "camera-intrinsics.txt")) {
      f = "7scenes";
    } else {
      *error = dir +
               ": not a dataset folder this importer knows (BOP / YCB-Video: scene_camera.json; "
               "TUM RGB-D: rgb.txt and depth.txt; 7-Scenes: frame-000000.depth.png)";
      return false;
    }
  }
  if (f == "bop" || f == "ycbv") return readBopScene(dir, fps, sequence, error);
  if (f == "7scenes") return readSevenScenes(dir, sequence, error);
  if (f == "tum") return readTumRgbd(dir, sequence, error);
  *error = "unknown dataset format '" + format + "' (auto, bop, ycbv, 7scenes, tum)";
  return false;
}

bool loadDepthMetres(const RealFrame& frame, std::vector<float>* depth, int* width, int* height,
                     std::string* error) {
  const cv::Mat raw = cv::imread(frame.depth_path, cv::IMREAD_ANYDEPTH);
  if (raw.empty() || raw.type() != CV_16UC1) {
    *error = "frame " + frame.name + ": " + frame.depth_path +
             (raw.empty() ? " cannot be read" : " is not a 16-bit depth image");
    return false;
  }
  *width = raw.cols;
  *height = raw.rows;
  const float unit = static_cast<float>(frame.depth_unit_m);
  depth->assign(static_cast<std::size_t>(raw.total()), 0.0f);
  for (int v = 0; v < raw.rows; ++v) {
    const std::uint16_t* row = raw.ptr<std::uint16_t>(v);
    for (int u = 0; u < raw.cols; ++u) {
      const std::uint16_t value = row[u];
      if (value == 0 || (frame.depth_invalid != 0 && value == frame.depth_invalid)) continue;
      // In float, as the ROS layer converts 16-bit millimetres (conversions.cpp): the visual
      // odometry's result moves by millimetres with the last bit of its depth.
      (*depth)[static_cast<std::size_t>(v) * raw.cols + u] = static_cast<float>(value) * unit;
    }
  }
  return true;
}

namespace {

bool loadColour(const RealFrame& frame, int code, std::vector<std::uint8_t>* out, int* width,
                int* height, std::string* error) {
  const cv::Mat bgr = cv::imread(frame.rgb_path, cv::IMREAD_COLOR);
  if (bgr.empty()) {
    *error = "frame " + frame.name + ": " + frame.rgb_path + " cannot be read";
    return false;
  }
  cv::Mat converted;
  cv::cvtColor(bgr, converted, code);
  *width = converted.cols;
  *height = converted.rows;
  const cv::Mat packed = converted.isContinuous() ? converted : converted.clone();
  out->assign(packed.data, packed.data + packed.total() * packed.elemSize());
  return true;
}

}  // namespace

bool loadRgb(const RealFrame& frame, std::vector<std::uint8_t>* rgb, int* width, int* height,
             std::string* error) {
  return loadColour(frame, cv::COLOR_BGR2RGB, rgb, width, height, error);
}

bool loadGray(const RealFrame& frame, std::vector<std::uint8_t>* gray, int* width, int* height,
              std::string* error) {
  return loadColour(frame, cv::COLOR_BGR2GRAY, gray, width, height, error);
}

bool loadLabelVisibility(RealFrame* frame, std::string* error) {
  if (frame->label_path.empty()) {
    *error = "frame " + frame->name + " has no label image";
    return false;
  }
  const cv::Mat label = cv::imread(frame->label_path, cv::IMREAD_ANYDEPTH | cv::IMREAD_GRAYSCALE);
  if (label.empty()) {
    *error = "frame " + frame->name + ": " + frame->label_path + " cannot be read";
    return false;
  }
  cv::Mat labels;
  label.convertTo(labels, CV_32S);
  for (RealObjectTruth& o : frame->objects) {
    const cv::Mat mask = labels == o.obj_id;
    o.visible_pixels = cv::countNonZero(mask);
    if (o.visible_pixels > 0) {
      const cv::Rect r = cv::boundingRect(mask);
      o.visible_box = PixelBox{r.x, r.y, r.width, r.height};
    } else {
      o.visible_box = PixelBox{};
    }
  }
  return true;
}

TruthVisibility::TruthVisibility(const ModelSet& models,
                                 std::shared_ptr<OffscreenRenderer> renderer)
    : models_(models), renderer_(std::move(renderer)) {}

int TruthVisibility::meshOf(const ObjectModel* model) {
  const auto known = meshes_.find(model);
  if (known != meshes_.end()) return known->second;
  const int handle = renderer_->addMesh(model->mesh);
  meshes_[model] = handle;
  return handle;
}

bool TruthVisibility::measure(RealFrame* frame, std::string* error) {
  std::vector<RenderItem> items;
  std::vector<std::size_t> object_of;  // per item
  for (std::size_t k = 0; k < frame->objects.size(); ++k) {
    const ObjectModel* model = models_.findById(frame->objects[k].obj_id);
    if (!model) continue;
    RenderItem item;
    item.mesh = meshOf(model);
    if (item.mesh < 0) continue;
    item.T_cam_model = frame->objects[k].T_cam_obj;
    item.instance_id = static_cast<std::uint16_t>(items.size() + 1);
    items.push_back(item);
    object_of.push_back(k);
  }
  if (items.empty()) return true;
  // The scene's render only for visible pixels the folder does not give (no label image, no
  // scene_gt_info.json); each object alone only for a visible fraction it does not give.
  const bool need_scene = std::any_of(object_of.begin(), object_of.end(), [&](std::size_t k) {
    return frame->objects[k].visible_pixels < 0;
  });
  RenderedImages scene;
  if (need_scene &&
      !renderer_->render(frame->K, items, &scene, PixelBox{}, OffscreenRenderer::kInstance)) {
    *error = "frame " + frame->name + ": rendering the ground truth failed: " + renderer_->error();
    return false;
  }
  for (std::size_t i = 0; i < items.size(); ++i) {
    RealObjectTruth& o = frame->objects[object_of[i]];
    if (o.visible_pixels < 0) {
      int in_scene = 0, x0 = frame->K.width, y0 = frame->K.height, x1 = -1, y1 = -1;
      for (int v = 0; v < frame->K.height; ++v) {
        for (int u = 0; u < frame->K.width; ++u) {
          if (scene.instanceAt(u, v) != items[i].instance_id) continue;
          ++in_scene;
          x0 = std::min(x0, u), y0 = std::min(y0, v), x1 = std::max(x1, u), y1 = std::max(y1, v);
        }
      }
      o.visible_pixels = in_scene;
      o.visible_box = in_scene > 0 ? PixelBox{x0, y0, x1 - x0 + 1, y1 - y0 + 1} : PixelBox{};
    }
    if (o.visible_fraction >= 0.0) continue;  // BOP's scene_gt_info.json has its own
    RenderedImages alone;
    const PixelBox region =
        renderer_->projectedRegion(frame->K, items[i].mesh, items[i].T_cam_model);
    int alone_pixels = 0;
    if (region.valid() &&
        renderer_->render(frame->K, {items[i]}, &alone, region, OffscreenRenderer::kInstance)) {
      for (std::uint16_t id : alone.instance) alone_pixels += id != 0;
    }
    o.visible_fraction = alone_pixels > 0
                             ? std::min(1.0, static_cast<double>(o.visible_pixels) / alone_pixels)
                             : 0.0;
  }
  return true;
}

std::vector<std::string> classNamesById(const ModelSet& models) {
  std::vector<std::string> names;
  for (const auto& m : models.models()) {
    if (m->id < 0) continue;
    if (m->id >= static_cast<int>(names.size())) names.resize(m->id + 1);
    names[m->id] = m->name;
  }
  return names;
}

bool readBopEstimates(const std::string& path, std::vector<BopEstimate>* estimates,
                      std::string* error) {
  std::ifstream in(path);
  if (!in) {
    *error = "cannot read " + path;
    return false;
  }
  std::vector<BopEstimate> rows;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line.rfind("scene_id", 0) == 0) continue;
    std::vector<std::string> fields;
    std::stringstream row(line);
    std::string field;
    while (std::getline(row, field, ',')) fields.push_back(field);
    try {
      if (fields.size() < 6)
        throw std::runtime_error("expected scene_id,im_id,obj_id,score,R,t,time");
      BopEstimate e;
      e.scene_id = std::stoi(fields[0]);
      e.im_id = std::stoi(fields[1]);
      e.obj_id = std::stoi(fields[2]);
      e.score = std::stod(fields[3]);
      nlohmann::json R = nlohmann::json::array(), t = nlohmann::json::array();
      std::istringstream rs(fields[4]), ts(fields[5]);
      double v;
      while (rs >> v) R.push_back(v);
      while (ts >> v) t.push_back(v);
      e.T_cam_obj = poseOf(R, t, 1e-3, "pose");
      e.time_s = fields.size() > 6 ? std::stod(fields[6]) : -1.0;
      if (!std::isfinite(e.score)) throw std::runtime_error("score is not finite");
      rows.push_back(e);
    } catch (const std::exception& ex) {
      *error = path + " line " + std::to_string(number) + ": " + ex.what();
      return false;
    }
  }
  *estimates = std::move(rows);
  return true;
}

TruthDetector::TruthDetector(const TruthDetectorModel& model) : model_(model), rng_(model.seed) {}

double TruthDetector::rayBias(int obj_id) const {
  for (const auto& [id, bias] : bias_) {
    if (id == obj_id) return bias;
  }
  return 0.0;
}

std::vector<ObjectMeasurement> TruthDetector::detect(const RealFrame& frame,
                                                     const std::vector<std::string>& class_names,
                                                     int min_visible_pixels) {
  std::vector<ObjectMeasurement> out;
  std::normal_distribution<double> normal(0.0, 1.0);
  for (const RealObjectTruth& o : frame.objects) {
    if (o.obj_id < 0 || o.obj_id >= static_cast<int>(class_names.size()) ||
        class_names[o.obj_id].empty()) {
      continue;
    }
    if (o.visible_pixels >= 0 && o.visible_pixels < min_visible_pixels) continue;
    auto known = std::find_if(bias_.begin(), bias_.end(),
                              [&](const auto& b) { return b.first == o.obj_id; });
    if (known == bias_.end()) {
      std::uniform_real_distribution<double> magnitude(model_.ray_bias_min_m,
                                                       model_.ray_bias_max_m);
      const double sign = std::bernoulli_distribution(0.5)(rng_) ? 1.0 : -1.0;
      bias_.emplace_back(o.obj_id, sign * magnitude(rng_));
      known = bias_.end() - 1;
    }
    Eigen::Isometry3d T = o.T_cam_obj;
    const Eigen::Vector3d ray = T.translation().normalized();
    T.translation() += known->second * ray;
    if (model_.translation_sigma_m > 0.0) {
      T.translation() +=
          model_.translation_sigma_m * Eigen::Vector3d(normal(rng_), normal(rng_), normal(rng_));
    }
    if (model_.rotation_sigma_rad > 0.0) {
      const Eigen::Vector3d w =
          model_.rotation_sigma_rad * Eigen::Vector3d(normal(rng_), normal(rng_), normal(rng_));
      if (w.norm() > 0.0) {
        T.linear() =
            (Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix() * T.linear()).eval();
      }
    }
    ObjectMeasurement m;
    m.class_name = class_names[o.obj_id];
    m.class_id = o.obj_id;
    m.score = model_.score;
    m.T_cam_obj = T;
    m.box = o.visible_box;
    out.push_back(m);
  }
  return out;
}

double alongRayError(const Eigen::Isometry3d& estimate, const Eigen::Isometry3d& truth) {
  const Eigen::Vector3d ray = truth.translation().normalized();
  return (estimate.translation() - truth.translation()).dot(ray);
}

}  // namespace geofusion

namespace geofusion {

DepthStatisticsAccumulator::DepthStatisticsAccumulator(std::vector<double> bin_upper_m)
    : bin_upper_m_(std::move(bin_upper_m)), residuals_(bin_upper_m_.size()) {}

void DepthStatisticsAccumulator::add(const PinholeIntrinsics& K, const std::vector<float>& observed,
                                     const std::vector<float>& clean,
                                     const std::vector<std::uint16_t>& instance) {
  const int W = K.width, H = K.height;
  auto at = [W](const std::vector<float>& d, int u, int v) {
    return d[static_cast<std::size_t>(v) * W + u];
  };
  cv::Mat not_edge(H, W, CV_8U, cv::Scalar(1));
  for (int v = 0; v < H; ++v) {
    for (int u = 0; u < W; ++u) {
      const float z = at(clean, u, v);
      if (!(z > 0.f)) continue;
      for (const auto& [du, dv] : {std::make_pair(1, 0), std::make_pair(0, 1)}) {
        if (u + du >= W || v + dv >= H) continue;
        const float zn = at(clean, u + du, v + dv);
        if (zn > 0.f && std::abs(zn - z) > 0.02f) {
          not_edge.at<std::uint8_t>(v, u) = 0;
          not_edge.at<std::uint8_t>(v + dv, u + du) = 0;
        }
      }
    }
  }
  cv::Mat distance;
  cv::distanceTransform(not_edge, distance, cv::DIST_L2, 3);
  for (int v = 0; v < H; ++v) {
    for (int u = 0; u < W; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * W + u;
      const float z = clean[i], o = observed[i];
      if (!(z > 0.f)) continue;
      const float d = distance.at<float>(v, u);
      const bool reading = o > 0.f;
      if (d <= 3.f) {
        ++edge_pixels_;
        edge_holes_ += !reading;
      }
      if (d <= 10.5f && reading) {
        const int k = static_cast<int>(std::lround(d));
        ++band_readings_[k];
        band_bad_[k] += std::abs(o - z) > 0.01f;
      }
      if (instance[i] != 0) {
        if (d <= 3.f) continue;
        ++object_pixels_;
        object_holes_ += !reading;
        if (!reading) continue;
        for (std::size_t b = 0; b < bin_upper_m_.size(); ++b) {
          if (z < bin_upper_m_[b]) {
            residuals_[b].push_back(std::abs(o - z));
            break;
          }
        }
        continue;
      }
      bool object_right = false, object_left = false;
      for (int k = 1; k <= 6; ++k) {
        object_right |= u + k < W && instance[i + k] != 0;
        object_left |= u - k >= 0 && instance[i - k] != 0;
      }
      if (object_right && !object_left) ++left_, left_holes_ += !reading;
      if (object_left && !object_right) ++right_, right_holes_ += !reading;
    }
  }
}

DepthStatistics DepthStatisticsAccumulator::result() const {
  DepthStatistics s;
  s.bin_upper_m = bin_upper_m_;
  for (const auto& r : residuals_) {
    s.bin_pixels.push_back(static_cast<long>(r.size()));
    std::vector<float> sorted = r;
    if (sorted.empty()) {
      s.median_abs_residual_m.push_back(std::nan(""));
      continue;
    }
    std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
    s.median_abs_residual_m.push_back(sorted[sorted.size() / 2]);
  }
  auto share = [](long part, long whole) { return whole > 0 ? double(part) / whole : 0.0; };
  s.object_invalid = share(object_holes_, object_pixels_);
  s.edge_invalid = share(edge_holes_, edge_pixels_);
  for (std::size_t k = 0; k < band_bad_.size(); ++k) {
    s.edge_band_px += share(band_bad_[k], band_readings_[k]);
  }
  s.left_of_objects_invalid = share(left_holes_, left_);
  s.right_of_objects_invalid = share(right_holes_, right_);
  return s;
}

std::vector<float> cleanDepthOf(const PinholeIntrinsics& K, const std::vector<float>& real,
                                const std::vector<float>& rendered,
                                const std::vector<std::uint16_t>& instance) {
  const int W = K.width, H = K.height;
  std::vector<float> clean(real.size(), 0.f);
  for (int v = 0; v < H; ++v) {
    const std::size_t row = static_cast<std::size_t>(v) * W;
    for (int u = 0; u < W; ++u) {
      const std::size_t i = row + u;
      if (instance[i] != 0) {
        clean[i] = rendered[i];
        continue;
      }
      if (real[i] > 0.f) {
        clean[i] = real[i];
        continue;
      }
      // A hole in the background: the nearest background readings on each side of the row.
      float left = 0.f, right = 0.f;
      int lu = u - 1, ru = u + 1;
      while (lu >= 0 && instance[row + lu] == 0 && !(real[row + lu] > 0.f)) --lu;
      while (ru < W && instance[row + ru] == 0 && !(real[row + ru] > 0.f)) ++ru;
      if (lu >= 0 && instance[row + lu] == 0) left = real[row + lu];
      if (ru < W && instance[row + ru] == 0) right = real[row + ru];
      if (left > 0.f && right > 0.f) {
        const float t = static_cast<float>(u - lu) / static_cast<float>(ru - lu);
        clean[i] = (1.f - t) * left + t * right;
      } else {
        clean[i] = std::max(left, right);
      }
    }
  }
  return clean;
}

}  // namespace geofusion
