// generate_dataset: makes a named suite of dense-clutter recordings (docs/dataset.md). For each
// scene: a physically settled clutter scene, a Fetch-like robot trajectory around the table, a
// rosbag with the topics of a real Fetch recording and a ground-truth YAML beside it. Prints the
// calibration of the noisy inputs (detections' ADD-S per class, odometry drift, depth noise).
//
//   generate_dataset --suite demo|bench|bench_rgb|bench_iid|vo|vo_fast [--out-dir DIR] [--models
//   DIR]
//       [--model-set YAML] [--scenes bench_01,...] [--keyframes N] [--image-every N]
//       [--detector densefusion|posecnn|densefusion_persistent|rgb]
//       [--sensor nguyen2012|structured_light|active_stereo|time_of_flight]
//       [--depth-encoding 16UC1|32FC1] [--no-compression] [--previews N] [--force]
#include "command_line.h"
#include "geofusion/evaluation/sequence_calibration.h"
#include "geofusion/model/model_import.h"
#include "geofusion/ros/recording_writer.h"
#include "geofusion/simulation/dataset.h"
#include "model_set_option.h"

#include <sys/stat.h>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <string>

namespace {

struct Options {
  std::string suite;
  std::string out_dir;
  std::string models_dir;
  std::string model_set_yaml;  ///< default: the package's config/models/ycb_video.yaml
  std::vector<std::string> scenes;
  int keyframes = -1;
  int image_every = -1;
  std::string detector;  ///< "": the suite's own preset
  std::string sensor;    ///< "": the suite's own depth camera model
  std::string depth_encoding = "16UC1";
  bool compress = true;
  int previews = 4;
  bool force = false;
};

void usage() {
  std::cerr
      << "usage: generate_dataset --suite demo|bench|bench_rgb|bench_iid|vo|vo_fast [--out-dir "
         "DIR]\n"
         "         [--models DIR] [--model-set YAML] [--scenes NAME,NAME] [--keyframes N]\n"
         "         [--image-every N] [--detector densefusion|posecnn|densefusion_persistent|rgb]\n"
         "         [--sensor nguyen2012|structured_light|active_stereo|time_of_flight]\n"
         "         [--depth-encoding 16UC1|32FC1]\n"
         "         [--no-compression] [--previews N=4] [--force]\n"
         "  --out-dir      default $GEOFUSION_DATA/<suite>, else ~/.cache/geofusion/data/<suite>\n"
         "  --models       YCB-Video models folder (bench); default $GEOFUSION_YCB_DIR, else\n"
         "                 ../shared/data/ycb_video beside the package source\n"
         "  --image-every  images and detections every Nth 30 Hz frame (suite default 6)\n"
         "  --detector     detector preset (default the suite's: densefusion_persistent for "
         "bench,\n"
         "                 rgb for bench_rgb, densefusion for the others; docs/dataset.md)\n"
         "  --sensor       depth camera model (default the suite's: structured_light, the\n"
         "                 Fetch head camera, for the bench suites; nguyen2012 for the others)\n"
         "  --previews     keyframes per scene written as PNG into <out-dir>/previews\n"
         "  --force        regenerate scenes whose cached files match the request\n";
}

/// The median of a depth image's readings (0 when it has none).
double medianDepth(std::vector<float> depth) {
  depth.erase(std::remove_if(depth.begin(), depth.end(), [](float z) { return !(z > 0.f); }),
              depth.end());
  if (depth.empty()) return 0.0;
  std::nth_element(depth.begin(), depth.begin() + depth.size() / 2, depth.end());
  return depth[depth.size() / 2];
}

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream in(s);
  for (std::string item; std::getline(in, item, ',');)
    if (!item.empty()) out.push_back(item);
  return out;
}

Options parse(int argc, char** argv) {
  Options o;
  geofusion::CommandLine args;
  args.value("--suite", &o.suite);
  args.value("--out-dir", &o.out_dir);
  args.value("--models", &o.models_dir);
  args.value("--model-set", &o.model_set_yaml);
  args.custom("--scenes", [&o](const std::string& v) { o.scenes = split(v); });
  args.value("--keyframes", &o.keyframes);
  args.value("--image-every", &o.image_every);
  args.value("--detector", &o.detector);
  args.value("--sensor", &o.sensor);
  args.value("--depth-encoding", &o.depth_encoding);
  args.toggle("--no-compression", &o.compress, false);
  args.value("--previews", &o.previews);
  args.toggle("--force", &o.force);
  args.parse(argc, argv, usage);
  if (o.suite.empty()) throw std::runtime_error("--suite is required");
  geofusion::DetectorModel preset;
  if (!o.detector.empty() && !geofusion::DetectorModel::byName(o.detector, &preset)) {
    throw std::runtime_error(
        "--detector must be densefusion, posecnn, densefusion_persistent or rgb");
  }
  geofusion::DepthNoise sensor;
  if (!o.sensor.empty() && !geofusion::DepthNoise::byName(o.sensor, &sensor)) {
    throw std::runtime_error(
        "--sensor must be nguyen2012, structured_light, active_stereo or time_of_flight");
  }
  if (o.keyframes == 0 || o.keyframes < -1 || o.image_every == 0 || o.image_every < -1) {
    throw std::runtime_error("--keyframes and --image-every must be > 0");
  }
  if (o.out_dir.empty()) {
    const char* data = std::getenv("GEOFUSION_DATA");
    const char* home = std::getenv("HOME");
    const std::string root =
        data ? std::string(data) : std::string(home ? home : "/tmp") + "/.cache/geofusion/data";
    o.out_dir = root + "/" + o.suite;
  }
  if (o.models_dir.empty()) o.models_dir = geofusion::defaultYcbDir("generate_dataset");
  if (o.model_set_yaml.empty())
    o.model_set_yaml =
        geofusion::requirePackageDir("generate_dataset") + "/config/models/ycb_video.yaml";
  return o;
}

bool makeDirs(const std::string& path) {
  std::string partial;
  std::stringstream in(path);
  if (!path.empty() && path[0] == '/') partial = "/";
  for (std::string part; std::getline(in, part, '/');) {
    if (part.empty()) continue;
    partial += part + "/";
    if (::mkdir(partial.c_str(), 0755) != 0 && errno != EEXIST) return false;
  }
  return true;
}

bool exists(const std::string& path) {
  return std::ifstream(path).good();
}

std::string readFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

int main(int argc, char** argv) {
  using namespace geofusion;
  using Clock = std::chrono::steady_clock;
  Options opt;
  SuiteSpec suite;
  try {
    opt = parse(argc, argv);
    if (!suiteByName(opt.suite, &suite)) {
      std::string names;
      for (const auto& n : suiteNames()) names += " " + n;
      throw std::runtime_error("unknown suite '" + opt.suite + "' (known:" + names + ")");
    }
  } catch (const std::exception& e) {
    std::cerr << "generate_dataset: " << e.what() << "\n";
    usage();
    return 2;
  }
  if (opt.keyframes > 0) suite.keyframes = opt.keyframes;
  if (opt.image_every > 0) suite.image_every = opt.image_every;
  suite.trajectory.frames = suite.cameraFrames();
  suite.trajectory.rate_hz = suite.camera_rate_hz;
  if (!opt.detector.empty()) {
    DetectorModel::byName(opt.detector, &suite.detector);
    suite.detector_name = opt.detector;
  }
  opt.detector = suite.detector_name;  // what the recordings and the printout say
  if (!opt.sensor.empty()) DepthNoise::byName(opt.sensor, &suite.depth);
  opt.sensor = suite.depth.name;
  if (!opt.scenes.empty()) {
    std::vector<SceneSpec> chosen;
    for (const std::string& name : opt.scenes) {
      bool found = false;
      for (const SceneSpec& s : suite.scenes) {
        if (s.name == name) chosen.push_back(s), found = true;
      }
      if (!found) {
        std::cerr << "generate_dataset: suite " << suite.name << " has no scene " << name << "\n";
        return 2;
      }
    }
    suite.scenes = chosen;
  }

  // The model set.
  ModelSet models;
  if (suite.model_set == "primitives") {
    models = ModelSet::builtinPrimitives();
  } else {
    std::vector<std::string> errors;
    if (!ModelSet::load(opt.model_set_yaml, opt.models_dir, &models, &errors) ||
        models.size() == 0) {
      std::cerr << "generate_dataset: suite " << suite.name << " needs the YCB-Video models ("
                << opt.model_set_yaml << ", meshes from " << opt.models_dir
                << "); give --models DIR or set GEOFUSION_YCB_DIR\n";
      for (const auto& e : errors) std::cerr << "  " << e << "\n";
      return 1;
    }
    for (const auto& e : errors) std::cerr << "generate_dataset: warning: " << e << "\n";
  }
  if (!makeDirs(opt.out_dir) || (opt.previews > 0 && !makeDirs(opt.out_dir + "/previews"))) {
    std::cerr << "generate_dataset: cannot create " << opt.out_dir << "\n";
    return 1;
  }

  RecordingLayout layout;
  layout.depth_encoding = opt.depth_encoding;
  layout.lz4 = opt.compress;
  const PinholeIntrinsics K;
  // What makes a cached scene valid: every option that changes its files.
  std::ostringstream request;
  request << describeSuite(suite) << "; models " << models.name() << " (" << models.size()
          << " classes); detector " << opt.detector << "; depth camera " << opt.sensor << "; depth "
          << opt.depth_encoding << "; lz4 " << opt.compress << "\n";
  // The symmetries change the simulated detector's flips.
  for (const auto& model : models.models())
    request << "  " << model->name << " symmetry " << describe(model->symmetry) << "\n";

  std::cout << "generate_dataset: suite " << suite.name << " (" << suite.scenes.size()
            << " scenes, " << suite.keyframes << " keyframes each, images every "
            << suite.image_every << " of " << suite.camera_rate_hz << " Hz frames, "
            << models.size() << " classes from " << models.name() << ", " << opt.detector
            << " detections) into " << opt.out_dir << std::endl;
  SequenceCalibration calibration(suite.detector.min_visible_pixels);
  std::ostringstream drift_report;
  const auto suite_start = Clock::now();
  int generated = 0;
  for (const SceneSpec& spec : suite.scenes) {
    const std::string bag_path = opt.out_dir + "/" + spec.name + ".bag";
    const std::string gt_path = opt.out_dir + "/" + spec.name + "_gt.yaml";
    const std::string stamp_path = opt.out_dir + "/" + spec.name + ".request";
    const std::string scene_request = request.str() + spec.describeChanges();
    if (!opt.force && exists(bag_path) && exists(gt_path) &&
        readFile(stamp_path) == scene_request) {
      std::cout << "  " << spec.name << ": cached (" << bag_path << "; --force remakes it)\n";
      continue;
    }
    std::remove(stamp_path.c_str());
    const auto start = Clock::now();
    GroundTruth gt;
    std::string report;
    if (!makeSuiteScene(suite, spec, models, &gt.scene, &gt.scene_seed, &report)) {
      std::cerr << "generate_dataset: " << spec.name << ": " << report << "\n";
      return 1;
    }
    if (!applySceneChanges(spec, suite.cameraFrames(), suite.clutter, &gt.scene, &report)) {
      std::cerr << "generate_dataset: " << spec.name << ": " << report << "\n";
      return 1;
    }
    if (spec.removed + spec.moved > 0) std::cout << "  " << spec.name << ": " << report << "\n";
    const ClutterScene& scene = gt.scene;
    if (gt.scene_seed != spec.seed) {
      std::cout << "  " << spec.name << ": seed " << spec.seed
                << " did not settle within the penetration bound; settled with derived seed "
                << gt.scene_seed << "\n";
    }
    std::vector<FramePose> poses = makeTrajectory(scene, suite.trajectory, spec.seed);
    addOdometryDrift(&poses, suite.odometry, spec.seed + 1000);
    const DriftStats drift = measureDrift(poses);

    RecordingWriter writer;
    std::string error;
    if (!writer.open(bag_path + ".tmp", layout, &error)) {
      std::cerr << "generate_dataset: " << error << "\n";
      return 1;
    }
    std::pair<std::string, std::string> textures;
    if (suite.textured_background) {
      textures = writeBackgroundTextures(opt.out_dir + "/textures", &error);
      if (textures.first.empty()) {
        std::cerr << "generate_dataset: " << error << "\n";
        return 1;
      }
    }
    SequenceRenderer renderer(scene, K, textures);
    if (!renderer.ok()) {
      std::cerr << "generate_dataset: the OSMesa renderer could not start\n";
      return 1;
    }
    gt.suite = suite.name;
    gt.scene_name = spec.name;
    gt.seed = spec.seed;
    gt.model_set = models.name();
    gt.detector = opt.detector;
    gt.intrinsics = K;
    gt.odom_frame = layout.odom_frame;
    gt.base_frame = layout.base_frame;
    gt.camera_link_frame = layout.camera_link_frame;
    gt.camera_frame = layout.optical_frame;

    std::mt19937 rng(spec.seed + 2000);
    // The colour camera's own random numbers: depth and detections stay as they were.
    ColourCamera colour(suite.colour, spec.seed + 3000);
    const ros::Time t0(suite.stamp_origin_s);
    writer.writeStaticTransforms(t0, RobotGeometry::cameraLinkToOptical());
    const int preview_every =
        opt.previews > 0 ? std::max(1, suite.keyframes / opt.previews) : suite.keyframes + 1;
    int keyframe = 0, detections = 0;
    for (std::size_t k = 0; k < poses.size(); ++k) {
      const FramePose& pose = poses[k];
      const ros::Time stamp = t0 + ros::Duration(pose.stamp_s);
      writer.writeTransforms(stamp, pose.T_odom_base, &pose.T_base_link);
      writer.writeOdometry(stamp, pose.T_odom_base);
      GroundTruthFrame g;
      g.index = static_cast<int>(k);
      g.stamp_s = stamp.toSec();
      g.T_map_base = pose.T_map_base;
      g.T_odom_base = pose.T_odom_base;
      g.T_base_link = pose.T_base_link;
      g.T_map_optical = pose.T_map_optical;
      g.keyframe = suite.isKeyframe(static_cast<int>(k));
      if (g.keyframe) {
        SequenceFrame f =
            renderer.render(pose, suite.depth, suite.detector, models, rng, static_cast<int>(k));
        if (suite.colour.enabled) {
          const FramePose& before = poses[k > 0 ? k - 1 : k];
          colour.apply(K, before.T_map_optical, pose.T_map_optical, 1.0 / suite.camera_rate_hz,
                       medianDepth(f.images.depth), &f.images.rgb);
        }
        writer.writeImages(stamp, K, f.images.rgb, f.images.depth);
        // A detector answers after its processing time; the header keeps the image stamp.
        writer.writeDetections(stamp, stamp + ros::Duration(0.1), f.detections);
        calibration.add(scene, pose.T_map_optical, f);
        g.visible_fraction = f.visible_fraction;
        g.visible_pixels = f.visible_pixels;
        g.visible_boxes = f.visible_boxes;
        g.place_visible_fraction = f.place_visible_fraction;
        g.detection_truth = f.detection_truth;
        g.swapped = f.swapped;
        detections += static_cast<int>(f.detections.size());
        if (keyframe % preview_every == 0 && keyframe / preview_every < opt.previews) {
          char name[64];
          std::snprintf(name, sizeof(name), "/previews/%s_kf%03d", spec.name.c_str(), keyframe);
          if (!writeFramePreview(opt.out_dir + name, K, f, &error)) {
            std::cerr << "generate_dataset: warning: " << error << "\n";
          }
        }
        ++keyframe;
      }
      gt.frames.push_back(std::move(g));
    }
    writer.close();
    gt.phantoms = renderer.phantoms(models);
    if (!writeGroundTruth(gt_path, gt, &error)) {
      std::cerr << "generate_dataset: " << error << "\n";
      return 1;
    }
    if (std::rename((bag_path + ".tmp").c_str(), bag_path.c_str()) != 0) {
      std::cerr << "generate_dataset: cannot rename " << bag_path << ".tmp\n";
      return 1;
    }
    std::ofstream(stamp_path) << scene_request;
    int support = 0;
    for (const auto& c : scene.contacts) support += c.support();
    const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
    char line[400];
    std::snprintf(line, sizeof(line),
                  "  %s: %zu objects, %zu contacts (%d support), penetration %.2f mm; %zu frames, "
                  "%d keyframes, %d detections; odometry drift max %.1f cm over %.2f m; %.0f s\n",
                  spec.name.c_str(), scene.objects.size(), scene.contacts.size(), support,
                  1000.0 * scene.max_penetration_m, poses.size(), keyframe, detections,
                  100.0 * drift.max_m, drift.path_length_m, seconds);
    std::cout << line << std::flush;
    drift_report << line;
    ++generated;
  }
  const double minutes = std::chrono::duration<double>(Clock::now() - suite_start).count() / 60.0;
  if (generated > 0) {
    std::ostringstream summary;
    summary << "calibration of the " << generated << " generated scene(s), " << opt.detector
            << " detections:\n"
            << calibration.report() << drift_report.str();
    std::cout << summary.str();
    std::ofstream(opt.out_dir + "/calibration_" + opt.detector + ".txt") << summary.str();
  }
  std::printf("generate_dataset: %d scene(s) generated, %zu cached, %.1f min\n", generated,
              suite.scenes.size() - static_cast<std::size_t>(generated), minutes);
  return 0;
}
