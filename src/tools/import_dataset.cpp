// import_dataset: converts a real RGB-D dataset folder into the package's recording (a bag with
// the head camera's topics) and its ground-truth file (docs/dataset.md, "Real recordings"), so that
// run_offline, evaluate_run, vo_benchmark and the nodes run on it as on a generated suite.
//
//   import_dataset --in DIR --out-dir DIR [--name NAME] [--format auto|bop|ycbv|7scenes|tum]
//       [--fps 30] [--model-set ycb_video|primitives|FILE.yaml] [--models DIR]
//       [--detections none|truth|FILE.csv] [--scene-id N] [--ray-bias MIN,MAX]
//       [--noise T_M,R_RAD] [--seed N] [--camera-poses odometry|none]
//       [--depth-encoding 16UC1|32FC1] [--model-frame auto|model|bop] [--quiet]
// --model-frame: the frame the folder's object poses (and a --detections CSV's) are in: BOP's
// (the origin at each model's bounding-box centre, ObjectModel::bop_origin; BOP's own ycbv
// folders) or the models' own (YCB-Video's meta.mat, converted by ycbv_meta_to_bop.py); auto:
// BOP's for a BOP folder (depth/), the models' for a YCB-Video one (NNNNNN-depth.png).
// Hand-held data has no robot: the recording has no /odom and no base; with --camera-poses
// odometry (the default) the dataset's camera trajectory is on /tf as odom -> optical frame (the
// ground truth says `odometry: camera_trajectory`), with none there is no pose at all (run the
// visual odometry). Exit 0 on success, 1 when the folder cannot be converted, 2 on bad arguments.
#include "command_line.h"
#include "geofusion/evaluation/real_datasets.h"
#include "geofusion/render/renderer.h"
#include "geofusion/ros/recording_writer.h"
#include "geofusion/simulation/dataset.h"
#include "model_set_option.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

namespace {

struct Options {
  std::string in, out_dir, name, format = "auto";
  double fps = 30.0;
  std::string model_set = "ycb_video", models_dir;
  std::string detections = "truth";  ///< none, truth or a BOP results CSV
  int scene_id = -1;                 ///< -1: the folder's name as a number
  geofusion::TruthDetectorModel detector;
  std::string camera_poses = "odometry";
  std::string depth_encoding = "16UC1";
  std::string model_frame = "auto";
  bool quiet = false;
};

void usage() {
  std::cerr << "usage: import_dataset --in DIR --out-dir DIR [--name NAME]\n"
               "         [--format auto|bop|ycbv|7scenes|tum] [--fps 30]\n"
               "         [--model-set ycb_video|primitives|FILE.yaml] [--models DIR]\n"
               "         [--detections none|truth|FILE.csv] [--scene-id N] [--ray-bias MIN,MAX]\n"
               "         [--noise T_M,R_RAD] [--seed N] [--camera-poses odometry|none]\n"
               "         [--depth-encoding 16UC1|32FC1] [--model-frame auto|model|bop] [--quiet]\n";
}

/// "A,B": two non-negative numbers (A <= B when `ordered`).
std::pair<double, double> pairOf(const std::string& flag, const std::string& value, bool ordered) {
  std::istringstream in(value);
  double a = 0.0, b = 0.0;
  char comma = 0;
  if (!(in >> a >> comma >> b) || comma != ',' || !(in >> std::ws).eof() || !(a >= 0.0) ||
      !(b >= 0.0) || (ordered && b < a)) {
    throw std::runtime_error(flag + " needs two numbers A,B (0 <= A" +
                             std::string(ordered ? " <= B" : ", 0 <= B") + "), not '" + value +
                             "'");
  }
  return {a, b};
}

Options parse(int argc, char** argv) {
  Options o;
  geofusion::CommandLine args;
  args.value("--in", &o.in);
  args.value("--out-dir", &o.out_dir);
  args.value("--name", &o.name);
  args.value("--format", &o.format);
  args.value("--fps", &o.fps);
  args.value("--model-set", &o.model_set);
  args.value("--models", &o.models_dir);
  args.value("--detections", &o.detections);
  args.value("--scene-id", &o.scene_id);
  args.custom("--ray-bias", [&o](const std::string& v) {
    std::tie(o.detector.ray_bias_min_m, o.detector.ray_bias_max_m) = pairOf("--ray-bias", v, true);
  });
  args.custom("--noise", [&o](const std::string& v) {
    std::tie(o.detector.translation_sigma_m, o.detector.rotation_sigma_rad) =
        pairOf("--noise", v, false);
  });
  args.value("--seed", &o.detector.seed);
  args.value("--camera-poses", &o.camera_poses);
  args.value("--depth-encoding", &o.depth_encoding);
  args.value("--model-frame", &o.model_frame);
  args.toggle("--quiet", &o.quiet);
  args.parse(argc, argv, usage);
  if (o.in.empty() || o.out_dir.empty())
    throw std::runtime_error("--in and --out-dir are required");
  if (!(o.fps > 0.0)) throw std::runtime_error("--fps must be positive");
  if (o.camera_poses != "odometry" && o.camera_poses != "none")
    throw std::runtime_error("--camera-poses must be odometry or none");
  if (o.depth_encoding != "16UC1" && o.depth_encoding != "32FC1")
    throw std::runtime_error("--depth-encoding must be 16UC1 or 32FC1");
  if (o.model_frame != "auto" && o.model_frame != "model" && o.model_frame != "bop")
    throw std::runtime_error("--model-frame must be auto, model or bop");
  return o;
}

/// Per frame, the detections of a BOP results file for this scene (im_id = the frame's name).
std::map<std::string, std::vector<geofusion::BopEstimate>> estimatesByFrame(
    const std::vector<geofusion::BopEstimate>& all, int scene_id) {
  std::map<std::string, std::vector<geofusion::BopEstimate>> out;
  for (const auto& e : all) {
    if (e.scene_id == scene_id) out[std::to_string(e.im_id)].push_back(e);
  }
  return out;
}

geofusion::RawDetection rawOf(const std::string& class_name, int class_id, double score,
                              const Eigen::Isometry3d& T_cam_obj, const geofusion::PixelBox& box) {
  geofusion::RawDetection d;
  d.class_name = class_name;
  d.class_id = class_id;
  d.score = score;
  d.position_cam = T_cam_obj.translation();
  d.orientation_cam = Eigen::Quaterniond(T_cam_obj.rotation());
  d.box = box;
  return d;
}

/// The scene's objects: each (obj_id, n-th instance of it in a frame) once, at its world pose
/// in the first frame that has it (the first camera is the world without camera poses).
struct SceneIndex {
  std::vector<std::pair<int, int>> keys;  ///< obj_id, instance
  std::vector<Eigen::Isometry3d> T_world_obj;
  int indexOf(int obj_id, int instance) const {
    for (std::size_t k = 0; k < keys.size(); ++k) {
      if (keys[k] == std::make_pair(obj_id, instance)) return static_cast<int>(k);
    }
    return -1;
  }
};

/// Per object of a frame, its index in the scene (adding new ones).
std::vector<int> indexFrameObjects(const geofusion::RealFrame& f,
                                   const Eigen::Isometry3d& T_world_cam, SceneIndex* scene) {
  std::vector<int> index;
  std::map<int, int> instances;
  for (const auto& o : f.objects) {
    const int instance = instances[o.obj_id]++;
    int k = scene->indexOf(o.obj_id, instance);
    if (k < 0) {
      k = static_cast<int>(scene->keys.size());
      scene->keys.emplace_back(o.obj_id, instance);
      scene->T_world_obj.push_back(T_world_cam * o.T_cam_obj);
    }
    index.push_back(k);
  }
  return index;
}

struct Importer {
  Options opt;
  geofusion::RealSequence seq;
  geofusion::ModelSet models;
  std::vector<std::string> names;  ///< by class id
  std::map<std::string, std::vector<geofusion::BopEstimate>> estimates;
  int unknown_ids = 0, detections = 0;

  bool loadInputs(std::string* error);
  void fromBopFrame();
  bool write(std::string* error);
  void frameTruth(const geofusion::RealFrame& f, const std::vector<int>& index,
                  std::size_t n_objects, geofusion::GroundTruthFrame* g) const;
  std::vector<geofusion::RawDetection> frameDetections(const geofusion::RealFrame& f,
                                                       geofusion::TruthDetector* truth,
                                                       const std::vector<int>& index,
                                                       std::vector<int>* detection_truth);
};

bool Importer::loadInputs(std::string* error) {
  if (!geofusion::readRealSequence(opt.in, opt.format, opt.fps, &seq, error)) return false;
  if (!loadModelSetOption("import_dataset", opt.model_set, opt.models_dir, &models)) {
    *error = "the model set " + opt.model_set + " cannot be loaded";
    return false;
  }
  names = geofusion::classNamesById(models);
  if (opt.name.empty()) opt.name = seq.name;
  if (!seq.frames.front().has_camera_pose) {
    std::cerr << "import_dataset: warning: " << opt.in
              << " gives no camera poses: its frames are taken as one viewpoint (the world is the "
                 "camera) and the recording has none (run the visual odometry)\n";
    opt.camera_poses = "none";
  }
  if (opt.scene_id < 0) {
    try {
      opt.scene_id = std::stoi(seq.name);
    } catch (const std::exception&) {
      opt.scene_id = 0;
    }
  }
  if (opt.detections != "none" && opt.detections != "truth") {
    std::vector<geofusion::BopEstimate> all;
    if (!geofusion::readBopEstimates(opt.detections, &all, error)) return false;
    estimates = estimatesByFrame(all, opt.scene_id);
    if (estimates.empty()) {
      *error = opt.detections + " has no row of scene_id " + std::to_string(opt.scene_id) +
               " (--scene-id)";
      return false;
    }
  }
  if (opt.model_frame == "auto") opt.model_frame = seq.format == "bop" ? "bop" : "model";
  if (opt.model_frame == "bop") fromBopFrame();
  return true;
}

// BOP's poses are of each model's BOP frame (origin at ObjectModel::bop_origin): brought to the
// model's own frame, T_cam_obj = T_cam_bop x Translation(-bop_origin). Unknown ids stay as they
// are (they are reported where they are used).
void Importer::fromBopFrame() {
  auto convert = [this](int obj_id, Eigen::Isometry3d* T) {
    if (const geofusion::ObjectModel* model = models.findById(obj_id))
      *T = *T * Eigen::Translation3d(-model->bop_origin);
  };
  for (geofusion::RealFrame& f : seq.frames)
    for (auto& o : f.objects) convert(o.obj_id, &o.T_cam_obj);
  for (auto& frame : estimates)
    for (auto& e : frame.second) convert(e.obj_id, &e.T_cam_obj);
}

void Importer::frameTruth(const geofusion::RealFrame& f, const std::vector<int>& index,
                          std::size_t n_objects, geofusion::GroundTruthFrame* g) const {
  g->index = f.index;
  g->keyframe = true;
  g->T_map_optical = f.T_world_cam;
  g->T_map_base = f.T_world_cam;  // hand-held: the camera is its own base
  g->T_odom_base = opt.camera_poses == "odometry" ? f.T_world_cam : Eigen::Isometry3d::Identity();
  g->visible_fraction.assign(n_objects, 0.0);
  g->visible_pixels.assign(n_objects, 0);
  g->visible_boxes.assign(n_objects, geofusion::PixelBox{});
  for (std::size_t k = 0; k < f.objects.size(); ++k) {
    const auto& o = f.objects[k];
    const std::size_t i = static_cast<std::size_t>(index[k]);
    g->visible_fraction[i] = std::max(0.0, o.visible_fraction);
    g->visible_pixels[i] = std::max(0, o.visible_pixels);
    g->visible_boxes[i] = o.visible_box;
  }
}

std::vector<geofusion::RawDetection> Importer::frameDetections(const geofusion::RealFrame& f,
                                                               geofusion::TruthDetector* truth,
                                                               const std::vector<int>& index,
                                                               std::vector<int>* detection_truth) {
  std::vector<geofusion::RawDetection> out;
  detection_truth->clear();
  if (opt.detections == "truth") {
    for (const auto& m : truth->detect(f, names, 1)) {
      out.push_back(rawOf(m.class_name, m.class_id, m.score, m.T_cam_obj, m.box));
      // The object it came from: the first of its id not yet reported (instances in order).
      int k = 0;
      while (k < static_cast<int>(f.objects.size()) &&
             (f.objects[k].obj_id != m.class_id ||
              std::count(detection_truth->begin(), detection_truth->end(), index[k]) > 0)) {
        ++k;
      }
      detection_truth->push_back(k < static_cast<int>(f.objects.size()) ? index[k] : -1);
    }
  } else if (opt.detections != "none") {
    const auto rows = estimates.find(f.name);
    if (rows == estimates.end()) return out;
    for (const auto& e : rows->second) {
      const geofusion::ObjectModel* model = models.findById(e.obj_id);
      if (!model) {
        ++unknown_ids;
        continue;
      }
      out.push_back(rawOf(model->name, e.obj_id, e.score, e.T_cam_obj, geofusion::PixelBox{}));
      detection_truth->push_back(-1);  // an estimator's: which object it is, is not known
    }
  }
  detections += static_cast<int>(out.size());
  return out;
}

bool Importer::write(std::string* error) {
  namespace fs = std::filesystem;
  fs::create_directories(opt.out_dir);
  const std::string bag_path = (fs::path(opt.out_dir) / (opt.name + ".bag")).string();
  const std::string gt_path = (fs::path(opt.out_dir) / (opt.name + "_gt.yaml")).string();
  geofusion::RecordingLayout layout;
  layout.depth_encoding = opt.depth_encoding;
  layout.lz4 = true;
  geofusion::RecordingWriter writer;
  if (!writer.open(bag_path + ".tmp", layout, error)) return false;
  geofusion::GroundTruth gt;
  gt.suite = "real";
  gt.scene_name = opt.name;
  gt.model_set = models.name();
  gt.detector = opt.detections == "truth" ? "truth_ray_bias" : opt.detections;
  gt.platform = "hand_held";
  gt.odometry = opt.camera_poses == "odometry" ? "camera_trajectory" : "none";
  gt.base_frame = gt.camera_link_frame = gt.camera_frame = layout.optical_frame;
  gt.intrinsics = seq.frames.front().K;
  auto renderer = std::make_shared<geofusion::OffscreenRenderer>();
  geofusion::TruthVisibility visibility(models, renderer);
  geofusion::TruthDetector truth(opt.detector);
  SceneIndex scene;
  const double base = seq.format == "tum" ? seq.frames.front().stamp_s : 1000.0;
  for (geofusion::RealFrame& f : seq.frames) {
    if (!f.has_camera_pose && opt.camera_poses == "odometry" && f.index > 0 &&
        seq.frames.front().has_camera_pose) {
      *error = "frame " + f.name + " has no camera pose (--camera-poses none writes none)";
      return false;
    }
    std::vector<float> depth;
    std::vector<std::uint8_t> rgb;
    int w = 0, h = 0, cw = 0, ch = 0;
    if (!geofusion::loadDepthMetres(f, &depth, &w, &h, error) ||
        !geofusion::loadRgb(f, &rgb, &cw, &ch, error)) {
      return false;
    }
    if (w != cw || h != ch || w != f.K.width || h != f.K.height) {
      *error = "frame " + f.name + ": colour, depth and intrinsics disagree on the image size";
      return false;
    }
    std::string vis_error;
    if (!f.label_path.empty() && !geofusion::loadLabelVisibility(&f, &vis_error)) {
      std::cerr << "import_dataset: warning: " << vis_error << "\n";
    }
    if (!f.objects.empty() && !visibility.measure(&f, error)) return false;
    const std::vector<int> index = indexFrameObjects(f, f.T_world_cam, &scene);
    const ros::Time stamp(base + f.stamp_s - seq.frames.front().stamp_s);
    if (f.has_camera_pose && opt.camera_poses == "odometry") {
      writer.writeCameraPose(stamp, f.T_world_cam);
    }
    writer.writeImages(stamp, f.K, rgb, depth);
    geofusion::GroundTruthFrame g;
    g.stamp_s = stamp.toSec();
    const auto raw = frameDetections(f, &truth, index, &g.detection_truth);
    if (opt.detections != "none") writer.writeDetections(stamp, stamp + ros::Duration(0.1), raw);
    frameTruth(f, index, scene.keys.size(), &g);
    gt.frames.push_back(g);
    if (!opt.quiet && f.index % 50 == 0) {
      std::printf("[import_dataset] frame %d of %zu\n", f.index, seq.frames.size());
    }
  }
  writer.close();
  for (std::size_t k = 0; k < scene.keys.size(); ++k) {
    const geofusion::ObjectModel* model = models.findById(scene.keys[k].first);
    geofusion::SceneObject o;
    for (const auto& m : models.models()) {
      if (m.get() == model) o.model = m;
    }
    if (!o.model) {
      *error = "object id " + std::to_string(scene.keys[k].first) + " is not in the model set " +
               models.name() + " (--model-set)";
      return false;
    }
    o.T_world_obj = scene.T_world_obj[k];
    gt.scene.objects.push_back(o);
  }
  // Frames seen before an object appeared list fewer objects: pad them.
  for (auto& g : gt.frames) {
    g.visible_fraction.resize(scene.keys.size(), 0.0);
    g.visible_pixels.resize(scene.keys.size(), 0);
    g.visible_boxes.resize(scene.keys.size(), geofusion::PixelBox{});
  }
  // No table model: a real table is measured by the estimator, not given.
  gt.scene.table.height_m = 0.0;
  gt.scene.table.size_x_m = gt.scene.table.size_y_m = gt.scene.table.thickness_m = 0.0;
  if (!geofusion::writeGroundTruth(gt_path, gt, error)) return false;
  // What it was made from (the benchmark lists a data folder's recordings by these files).
  std::ofstream((fs::path(opt.out_dir) / (opt.name + ".request")).string())
      << "import_dataset " << seq.format << " " << fs::absolute(opt.in).string() << "; model set "
      << models.name() << "; detections " << opt.detections << " " << opt.detector.ray_bias_min_m
      << " " << opt.detector.ray_bias_max_m << " " << opt.detector.translation_sigma_m << " "
      << opt.detector.rotation_sigma_rad << " seed " << opt.detector.seed << "; camera poses "
      << opt.camera_poses << "\n";
  std::error_code ec;
  fs::rename(bag_path + ".tmp", bag_path, ec);
  if (ec) {
    *error = "cannot rename " + bag_path + ".tmp: " + ec.message();
    return false;
  }
  std::printf(
      "[import_dataset] %s (%s, poses in the %s frame, hand-held, odometry: %s): %zu frames, "
      "%zu objects, %d detections%s -> %s, %s\n",
      opt.name.c_str(), seq.format.c_str(), opt.model_frame == "bop" ? "BOP model" : "models' own",
      gt.odometry.c_str(), seq.frames.size(), gt.scene.objects.size(), detections,
      unknown_ids ? (", " + std::to_string(unknown_ids) + " of unknown object ids skipped").c_str()
                  : "",
      bag_path.c_str(), gt_path.c_str());
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  Importer importer;
  try {
    importer.opt = parse(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "import_dataset: " << e.what() << "\n";
    usage();
    return 2;
  }
  std::string error;
  if (!importer.loadInputs(&error) || !importer.write(&error)) {
    std::cerr << "import_dataset: " << error << "\n";
    return 1;
  }
  return 0;
}
