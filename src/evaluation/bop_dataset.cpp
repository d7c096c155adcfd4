#include "geofusion/evaluation/bop_dataset.h"

#include "geofusion/common/atomic_file.h"
#include "geofusion/common/image_box.h"
#include "geofusion/evaluation/bop_metrics.h"
#include "geofusion/evaluation/keyframe_matcher.h"

#include <nlohmann/json.hpp>

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

namespace geofusion {
namespace {

using nlohmann::json;

bool makeFolder(const std::string& path, std::string* error) {
  std::string partial;
  std::stringstream parts(path);
  for (std::string part; std::getline(parts, part, '/');) {
    partial += part + "/";
    if (part.empty() || part == ".") continue;
    if (::mkdir(partial.c_str(), 0755) != 0 && errno != EEXIST) {
      *error = "cannot make the folder " + partial;
      return false;
    }
  }
  return true;
}

// The JSON file at `path`, or `empty` when there is none; false when it cannot be read.
bool readJson(const std::string& path, const json& empty, json* out, std::string* error) {
  std::ifstream f(path);
  if (!f) {
    *out = empty;
    return true;
  }
  try {
    f >> *out;
  } catch (const std::exception& e) {
    *error = path + ": not JSON (" + e.what() + "); not replaced";
    return false;
  }
  return true;
}

bool writeJson(const std::string& path, const json& j, std::string* error) {
  return writeTextAtomically(path, j.dump(1) + "\n", error);
}

std::vector<double> flat(const Eigen::Matrix4d& M) {
  std::vector<double> v;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) v.push_back(M(r, c));
  return v;
}

// models_info.json's entry (mm, BOP's frame): diameter, box, the appearance symmetries as BOP
// lists them (discrete: 4x4 row-major; continuous: axis and a point on it), turning about the
// centre of the points' box (bop_metrics.h) written in BOP's frame.
json modelInfo(const ObjectModel& model) {
  const BopModel bop = bopModelOf(model);
  Eigen::AlignedBox3d box;
  for (const Eigen::Vector3d& p : bop.points) box.extend(1000.0 * (p - model.bop_origin));
  json info = {{"diameter", 1000.0 * bop.diameter_m}};
  const char* axes = "xyz";
  for (int a = 0; a < 3; ++a) {
    info[std::string("min_") + axes[a]] = box.isEmpty() ? 0.0 : box.min()[a];
    info[std::string("size_") + axes[a]] = box.isEmpty() ? 0.0 : box.sizes()[a];
  }
  const Eigen::Vector3d centre_mm = 1000.0 * (bop.centre - model.bop_origin);
  const Symmetry& s = model.appearance_symmetry;
  if (s.type == Symmetry::Type::kDiscrete) {
    json list = json::array();
    for (const Eigen::Quaterniond& q : s.rotations) {
      Eigen::Isometry3d S = Eigen::Isometry3d::Identity();
      S.linear() = q.toRotationMatrix();
      S.translation() = centre_mm - S.linear() * centre_mm;
      list.push_back(flat(S.matrix()));
    }
    info["symmetries_discrete"] = list;
  } else if (s.type == Symmetry::Type::kContinuous) {
    const Eigen::Vector3d axis = s.axis.normalized();
    info["symmetries_continuous"] =
        json::array({{{"axis", {axis.x(), axis.y(), axis.z()}},
                      {"offset", {centre_mm.x(), centre_mm.y(), centre_mm.z()}}}});
  }
  return info;
}

// The evaluation points as an ASCII PLY (bop_toolkit's inout.load_ply reads x, y, z), mm.
bool writePointsPly(const std::string& path, const ObjectModel& model, std::string* error) {
  std::ostringstream out;
  out << "ply\nformat ascii 1.0\nelement vertex " << model.points.size()
      << "\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  char line[96];
  for (const Eigen::Vector3f& p : model.points) {
    const Eigen::Vector3d q = 1000.0 * (p.cast<double>() - model.bop_origin);
    std::snprintf(line, sizeof(line), "%.6f %.6f %.6f\n", q.x(), q.y(), q.z());
    out << line;
  }
  return writeTextAtomically(path, out.str(), error);
}

// One image's ground truth: scene_gt's and scene_gt_info's lists, the object index of each
// entry (the toolkit's gt_id) and BOP19's targets (instances per obj_id).
struct ImageTruth {
  json gt = json::array(), info = json::array();
  std::vector<int> objects;
  std::map<int, int> targets;
};

json boxJson(int x, int y, int w, int h) {
  return json::array({x, y, w, h});
}

ImageTruth imageTruth(const GroundTruth& gt, const GroundTruthFrame& f, const BopIds& ids) {
  ImageTruth out;
  const Eigen::Isometry3d T_cam_map = f.T_map_optical.inverse();
  for (std::size_t i = 0; i < gt.scene.objects.size(); ++i) {
    const SceneObject& o = gt.scene.objects[i];
    if (!o.presentAt(f.index)) continue;  // not in the scene at that frame
    const Eigen::Isometry3d T_obj = T_cam_map * o.T_world_obj;
    const Eigen::Isometry3d T = T_obj * Eigen::Translation3d(o.model->bop_origin);
    const Eigen::Matrix3d& R = T.linear();
    const Eigen::Vector3d t = 1000.0 * T.translation();
    const int obj_id = ids.objectOf(*o.model);
    out.gt.push_back(
        {{"obj_id", obj_id},
         {"cam_R_m2c",
          {R(0, 0), R(0, 1), R(0, 2), R(1, 0), R(1, 1), R(1, 2), R(2, 0), R(2, 1), R(2, 2)}},
         {"cam_t_m2c", {t.x(), t.y(), t.z()}}});
    const double visible = i < f.visible_fraction.size() ? f.visible_fraction[i] : 0.0;
    const int pixels = i < f.visible_pixels.size() ? f.visible_pixels[i] : 0;
    const PixelBox m = i < f.visible_boxes.size() ? f.visible_boxes[i] : PixelBox();
    const Box2d b = projectedBox(o.model->points, T_obj, gt.intrinsics);
    out.info.push_back(
        {{"visib_fract", visible},
         {"px_count_visib", pixels},
         {"px_count_all", visible > 0.0 ? static_cast<int>(std::lround(pixels / visible)) : 0},
         {"bbox_visib", m.valid() ? boxJson(m.x, m.y, m.width, m.height) : boxJson(-1, -1, -1, -1)},
         {"bbox_obj", b.empty() ? boxJson(-1, -1, -1, -1)
                                : boxJson(static_cast<int>(b.x0), static_cast<int>(b.y0),
                                          static_cast<int>(std::lround(b.width())),
                                          static_cast<int>(std::lround(b.height())))}});
    out.objects.push_back(static_cast<int>(i));
    if (visible >= kBopTargetMinVisible) ++out.targets[obj_id];
  }
  return out;
}

// The scene's files, its targets and its part of the id mapping.
struct SceneFiles {
  json camera = json::object(), gt = json::object(), info = json::object();
  json targets = json::array(), mapping = json::object();
  int images = 0;
};

SceneFiles sceneFiles(const GroundTruth& gt, const RunResults& results, const BopIds& ids,
                      double stamp_tolerance_s) {
  const KeyframeMatcher frames(gt, stamp_tolerance_s);
  const PinholeIntrinsics& K = gt.intrinsics;
  SceneFiles s;
  json images = json::object(), gt_objects = json::object();
  for (const KeyframeResult& k : results.keyframes) {
    const GroundTruthFrame* f = frames.at(k.stamp_s);
    if (!f) continue;
    const int im_id = ids.imageOf(k.keyframe);
    const std::string key = std::to_string(im_id);
    ImageTruth truth = imageTruth(gt, *f, ids);
    s.camera[key] = {{"cam_K", {K.fx, 0.0, K.cx, 0.0, K.fy, K.cy, 0.0, 0.0, 1.0}},
                     {"depth_scale", 1.0}};
    s.gt[key] = std::move(truth.gt);
    s.info[key] = std::move(truth.info);
    for (const auto& [obj_id, n] : truth.targets)
      s.targets.push_back(
          {{"scene_id", ids.scene_id}, {"im_id", im_id}, {"obj_id", obj_id}, {"inst_count", n}});
    images[key] = {{"keyframe", k.keyframe}, {"stamp", k.stamp_s}, {"frame", f->index}};
    gt_objects[key] = truth.objects;
    ++s.images;
  }
  s.mapping = {{"name", gt.scene_name},
               {"width", K.width},
               {"height", K.height},
               {"images", images},
               {"gt_objects", gt_objects}};
  return s;
}

// Every class of the model set (an estimate of any class is scored, BOP's toolkit loads the
// models of all the dataset's obj_ids), their info merged into models_info.json.
bool writeModels(const std::string& root, const ModelSet& models, const BopIds& ids, json* classes,
                 std::string* error) {
  const std::string folder = root + "/models_eval";
  if (!makeFolder(folder, error)) return false;
  json info;
  if (!readJson(folder + "/models_info.json", json::object(), &info, error)) return false;
  std::set<int> written;
  for (const auto& model : models.models()) {
    const int obj_id = ids.objectOf(*model);
    if (!written.insert(obj_id).second) {
      if (error) *error = "two classes with BOP obj_id " + std::to_string(obj_id);
      return false;
    }
    char name[32];
    std::snprintf(name, sizeof(name), "/obj_%06d.ply", obj_id);
    if (!writePointsPly(folder + name, *model, error)) return false;
    info[std::to_string(obj_id)] = modelInfo(*model);
    (*classes)[std::to_string(obj_id)] = model->name;
  }
  return writeJson(folder + "/models_info.json", info, error);
}

// An exclusive lock on the folder (flock on <root>/.geofusion_lock) while one writer updates the
// files several scenes share; released when it goes out of scope.
class FolderLock {
 public:
  explicit FolderLock(const std::string& root)
      : fd_(::open((root + "/.geofusion_lock").c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644)) {
    locked_ = fd_ >= 0 && ::flock(fd_, LOCK_EX) == 0;
  }
  ~FolderLock() {
    if (fd_ >= 0) ::close(fd_);  // releases the lock
  }
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;
  bool locked() const { return locked_; }

 private:
  int fd_;
  bool locked_ = false;
};

}  // namespace

bool writeBopDataset(const std::string& root, const ModelSet& models, const GroundTruth& gt,
                     const RunResults& results, const BopIds& ids, double stamp_tolerance_s,
                     std::string* error) {
  std::string e;
  SceneFiles scene = sceneFiles(gt, results, ids, stamp_tolerance_s);
  if (scene.images == 0) {
    if (error) *error = "no keyframe of the results is a keyframe of the ground truth";
    return false;
  }
  if (!makeFolder(root, &e)) {
    if (error) *error = e;
    return false;
  }
  const FolderLock lock(root);
  if (!lock.locked()) {
    if (error) *error = "cannot lock " + root + "/.geofusion_lock";
    return false;
  }
  json mapping, targets;
  bool ok = readJson(root + "/geofusion_ids.json", json::object(), &mapping, &e) &&
            readJson(root + "/test_targets_bop19.json", json::array(), &targets, &e);
  if (ok && !mapping.contains("obj_ids")) mapping["obj_ids"] = json::object();
  ok = ok && writeModels(root, models, ids, &mapping["obj_ids"], &e);
  char scene_dir[32];
  std::snprintf(scene_dir, sizeof(scene_dir), "/test/%06d", ids.scene_id);
  const std::string dir = root + scene_dir;
  ok = ok && makeFolder(dir, &e) && writeJson(dir + "/scene_camera.json", scene.camera, &e) &&
       writeJson(dir + "/scene_gt.json", scene.gt, &e) &&
       writeJson(dir + "/scene_gt_info.json", scene.info, &e);
  if (ok) {  // this scene's targets and mapping replace the ones an earlier call wrote
    json kept = json::array();
    for (const json& t : targets)
      if (t.value("scene_id", -1) != ids.scene_id) kept.push_back(t);
    for (const json& t : scene.targets) kept.push_back(t);
    mapping["scenes"][std::to_string(ids.scene_id)] = scene.mapping;
    ok = writeJson(root + "/test_targets_bop19.json", kept, &e) &&
         writeJson(root + "/geofusion_ids.json", mapping, &e);
  }
  if (!ok && error) *error = e;
  return ok;
}

}  // namespace geofusion
