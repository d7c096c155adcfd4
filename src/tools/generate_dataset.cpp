// generate_dataset: makes a named suite of dense-clutter recordings (docs/dataset.md). For each
// scene: a physically settled clutter scene, a Fetch-like robot trajectory around the table, a
// rosbag with the topics of a real Fetch recording and a ground-truth YAML beside it. Prints the
// calibration of the noisy inputs (detections' ADD-S per class, odometry drift, depth noise).
//
//   generate_dataset --suite demo|bench|bench_rgb|bench_iid|vo|vo_fast [--out-dir DIR] [--models
//   DIR]
//       [--model-set YAML] [--scenes bench_01,...] [--keyframes N] [--image-every N]
//       [--detector densefusion|posecnn|densefusion_persistent|rgb]
//       [--sensor nguyen2012|structured_light|active_stereo|time_of_flight] [--lens
//       primesense|none] [--colour fetch_head|none]
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
  std::string lens;      ///< "": the suite's own lens (primesense or none)
  std::string colour;    ///< "": the suite's own colour camera model (fetch_head or none)
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
         "         [--lens primesense|none] [--colour fetch_head|none]\n"
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
         "  --lens         lens distortion of the images and camera_info (default the suite's:\n"
         "                 primesense for the bench suites, none for the others)\n"
         "  --colour       colour camera's blur, rolling shutter, exposure and noise (default\n"
         "                 the suite's: fetch_head for the vo suites, none for the others)\n"
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
  args.value("--lens", &o.lens);
  args.value("--colour", &o.colour);
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
  if (!o.lens.empty() && o.lens != "primesense" && o.lens != "none")
    throw std::runtime_error("--lens must be primesense or none");
  if (!o.colour.empty() && o.colour != "fetch_head" && o.colour != "none")
    throw std::runtime_error("--colour must be fetch_head or none");
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

using Clock = std::chrono::steady_clock;

// The suite as the options change it (keyframes, image rate, detector, depth camera, scenes);
// the options then name the suite's detector and depth camera. False, having said why, when a
// scene asked for is not in the suite.
bool applyOptions(Options* opt, geofusion::SuiteSpec* suite) {
  using namespace geofusion;
  if (opt->keyframes > 0) suite->keyframes = opt->keyframes;
  if (opt->image_every > 0) suite->image_every = opt->image_every;
  suite->trajectory.frames = suite->cameraFrames();
  suite->trajectory.rate_hz = suite->camera_rate_hz;
  if (!opt->detector.empty()) {
    DetectorModel::byName(opt->detector, &suite->detector);
    suite->detector_name = opt->detector;
  }
  opt->detector = suite->detector_name;  // what the recordings and the printout say
  if (!opt->sensor.empty()) DepthNoise::byName(opt->sensor, &suite->depth);
  opt->sensor = suite->depth.name;
  if (opt->lens == "primesense") suite->lens = LensDistortion::primesense();
  if (opt->lens == "none") suite->lens = LensDistortion{};
  if (opt->colour == "fetch_head") suite->colour = ColourNoise::fetchHead();
  if (opt->colour == "none") suite->colour = ColourNoise{};
  if (!opt->scenes.empty()) {
    std::vector<SceneSpec> chosen;
    for (const std::string& name : opt->scenes) {
      bool found = false;
      for (const SceneSpec& s : suite->scenes) {
        if (s.name == name) chosen.push_back(s), found = true;
      }
      if (!found) {
        std::cerr << "generate_dataset: suite " << suite->name << " has no scene " << name << "\n";
        return false;
      }
    }
    suite->scenes = chosen;
  }
  return true;
}

// The suite's model set: the built-in primitives, or the YCB-Video models. False, having said
// why, when these cannot be loaded.
bool loadModels(const Options& opt, const geofusion::SuiteSpec& suite,
                geofusion::ModelSet* models) {
  using namespace geofusion;
  if (suite.model_set == "primitives") {
    *models = ModelSet::builtinPrimitives();
    return true;
  }
  std::vector<std::string> errors;
  if (!ModelSet::load(opt.model_set_yaml, opt.models_dir, models, &errors) || models->size() == 0) {
    std::cerr << "generate_dataset: suite " << suite.name << " needs the YCB-Video models ("
              << opt.model_set_yaml << ", meshes from " << opt.models_dir
              << "); give --models DIR or set GEOFUSION_YCB_DIR\n";
    for (const auto& e : errors) std::cerr << "  " << e << "\n";
    return false;
  }
  for (const auto& e : errors) std::cerr << "generate_dataset: warning: " << e << "\n";
  return true;
}

// What makes a cached scene valid: every option that changes its files.
std::string suiteRequest(const Options& opt, const geofusion::SuiteSpec& suite,
                         const geofusion::ModelSet& models) {
  using namespace geofusion;
  std::ostringstream request;
  request << describeSuite(suite) << "; models " << models.name() << " (" << models.size()
          << " classes); detector " << opt.detector << "; depth camera " << opt.sensor << "; depth "
          << opt.depth_encoding << "; lz4 " << opt.compress << "\n";
  // The symmetries change the simulated detector's flips.
  for (const auto& model : models.models())
    request << "  " << model->name << " symmetry " << describe(model->symmetry) << "\n";
  return request.str();
}

/// What every scene of the suite is made with.
struct SuiteInputs {
  const Options& opt;
  const geofusion::SuiteSpec& suite;
  const geofusion::ModelSet& models;
  const geofusion::RecordingLayout& layout;
  const geofusion::PinholeIntrinsics& K;
};

/// The files of one scene: its recording, its ground truth and the request they were made for.
struct SceneFiles {
  SceneFiles(const std::string& dir, const std::string& name)
      : bag(dir + "/" + name + ".bag"),
        gt(dir + "/" + name + "_gt.yaml"),
        request(dir + "/" + name + ".request") {}
  std::string bag, gt, request;
};

/// A scene's recording, counted.
struct SceneCounts {
  int keyframes = 0, detections = 0;
};

// Whether the scene's files are there, made for `scene_request` (and --force not given); says so.
bool cached(const Options& opt, const geofusion::SceneSpec& spec,
            const std::string& scene_request) {
  const SceneFiles files(opt.out_dir, spec.name);
  if (!opt.force && exists(files.bag) && exists(files.gt) &&
      readFile(files.request) == scene_request) {
    std::cout << "  " << spec.name << ": cached (" << files.bag << "; --force remakes it)\n";
    return true;
  }
  return false;
}

// The scene of `spec`, physically settled and changed as it says, into the ground truth. False,
// having said why, when it cannot be made.
bool settleScene(const geofusion::SuiteSpec& suite, const geofusion::SceneSpec& spec,
                 const geofusion::ModelSet& models, geofusion::GroundTruth* gt) {
  using namespace geofusion;
  std::string report;
  if (!makeSuiteScene(suite, spec, models, &gt->scene, &gt->scene_seed, &report)) {
    std::cerr << "generate_dataset: " << spec.name << ": " << report << "\n";
    return false;
  }
  if (!applySceneChanges(spec, suite.cameraFrames(), suite.clutter, &gt->scene, &report)) {
    std::cerr << "generate_dataset: " << spec.name << ": " << report << "\n";
    return false;
  }
  if (spec.removed + spec.moved > 0) std::cout << "  " << spec.name << ": " << report << "\n";
  if (gt->scene_seed != spec.seed) {
    std::cout << "  " << spec.name << ": seed " << spec.seed
              << " did not settle within the penetration bound; settled with derived seed "
              << gt->scene_seed << "\n";
  }
  return true;
}

// Every frame along `poses` into the recording (TF, odometry) and the ground truth; the keyframes
// rendered, with their images and detections, the first few also as previews.
void writeFrames(const SuiteInputs& in, const geofusion::SceneSpec& spec,
                 const std::vector<geofusion::FramePose>& poses,
                 geofusion::SequenceRenderer* renderer, geofusion::RecordingWriter* writer,
                 geofusion::SequenceCalibration* calibration, geofusion::GroundTruth* gt,
                 SceneCounts* counts, std::string* error) {
  using namespace geofusion;
  const SuiteSpec& suite = in.suite;
  const PinholeIntrinsics& K = in.K;
  const ClutterScene& scene = gt->scene;
  std::mt19937 rng(spec.seed + 2000);
  // The colour camera's own random numbers: depth and detections stay as they were.
  ColourCamera colour(suite.colour, spec.seed + 3000);
  LensWarp lens_warp;
  const ros::Time t0(suite.stamp_origin_s);
  writer->writeStaticTransforms(t0, RobotGeometry::cameraLinkToOptical());
  const int preview_every =
      in.opt.previews > 0 ? std::max(1, suite.keyframes / in.opt.previews) : suite.keyframes + 1;
  int& keyframe = counts->keyframes;
  for (std::size_t k = 0; k < poses.size(); ++k) {
    const FramePose& pose = poses[k];
    const ros::Time stamp = t0 + ros::Duration(pose.stamp_s);
    writer->writeTransforms(stamp, pose.T_odom_base, &pose.T_base_link);
    writer->writeOdometry(stamp, pose.T_odom_base);
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
          renderer->render(pose, suite.depth, suite.detector, in.models, rng, static_cast<int>(k));
      if (suite.colour.enabled) {
        const FramePose& before = poses[k > 0 ? k - 1 : k];
        colour.apply(K, before.T_map_optical, pose.T_map_optical, 1.0 / suite.camera_rate_hz,
                     medianDepth(f.images.depth), &f.images.rgb);
      }
      // The depth noise measured on the pinhole images (against the clean pinhole render) ...
      calibration->add(scene, pose.T_map_optical, f);
      // ... then what the lens makes of them (camera_info says so with its D).
      lens_warp.distortRgb(K, suite.lens, &f.images.rgb);
      lens_warp.distortDepth(K, suite.lens, &f.images.depth);
      writer->writeImages(stamp, K, f.images.rgb, f.images.depth, suite.lens);
      // A detector answers after its processing time; the header keeps the image stamp.
      writer->writeDetections(stamp, stamp + ros::Duration(0.1), f.detections);
      g.visible_fraction = f.visible_fraction;
      g.visible_pixels = f.visible_pixels;
      g.visible_boxes = f.visible_boxes;
      g.place_visible_fraction = f.place_visible_fraction;
      g.detection_truth = f.detection_truth;
      g.swapped = f.swapped;
      counts->detections += static_cast<int>(f.detections.size());
      if (keyframe % preview_every == 0 && keyframe / preview_every < in.opt.previews) {
        char name[64];
        std::snprintf(name, sizeof(name), "/previews/%s_kf%03d", spec.name.c_str(), keyframe);
        if (!writeFramePreview(in.opt.out_dir + name, K, f, error)) {
          std::cerr << "generate_dataset: warning: " << *error << "\n";
        }
      }
      ++keyframe;
    }
    gt->frames.push_back(std::move(g));
  }
}

// The scene's recording, into `bag_path`, and the rest of its ground truth. False, having said
// why, when the recording or the renderer cannot start.
bool recordScene(const SuiteInputs& in, const geofusion::SceneSpec& spec,
                 const std::vector<geofusion::FramePose>& poses, const std::string& bag_path,
                 geofusion::SequenceCalibration* calibration, geofusion::GroundTruth* gt,
                 SceneCounts* counts, std::string* error) {
  using namespace geofusion;
  RecordingWriter writer;
  if (!writer.open(bag_path, in.layout, error)) {
    std::cerr << "generate_dataset: " << *error << "\n";
    return false;
  }
  std::pair<std::string, std::string> textures;
  if (in.suite.textured_background) {
    textures = writeBackgroundTextures(in.opt.out_dir + "/textures", error);
    if (textures.first.empty()) {
      std::cerr << "generate_dataset: " << *error << "\n";
      return false;
    }
  }
  SequenceRenderer renderer(gt->scene, in.K, textures);
  if (!renderer.ok()) {
    std::cerr << "generate_dataset: the OSMesa renderer could not start\n";
    return false;
  }
  gt->suite = in.suite.name;
  gt->scene_name = spec.name;
  gt->seed = spec.seed;
  gt->model_set = in.models.name();
  gt->detector = in.opt.detector;
  gt->intrinsics = in.K;
  gt->odom_frame = in.layout.odom_frame;
  gt->base_frame = in.layout.base_frame;
  gt->camera_link_frame = in.layout.camera_link_frame;
  gt->camera_frame = in.layout.optical_frame;
  writeFrames(in, spec, poses, &renderer, &writer, calibration, gt, counts, error);
  writer.close();
  gt->phantoms = renderer.phantoms(in.models);
  return true;
}

// One scene: settled, its trajectory recorded, its ground truth written beside the recording and
// its summary line printed and added to `drift_report`. False, having said why, on a failure.
bool generateScene(const SuiteInputs& in, const geofusion::SceneSpec& spec,
                   const std::string& scene_request, geofusion::SequenceCalibration* calibration,
                   std::ostringstream* drift_report) {
  using namespace geofusion;
  const SceneFiles files(in.opt.out_dir, spec.name);
  std::remove(files.request.c_str());
  const auto start = Clock::now();
  GroundTruth gt;
  if (!settleScene(in.suite, spec, in.models, &gt)) return false;
  const ClutterScene& scene = gt.scene;
  std::vector<FramePose> poses = makeTrajectory(scene, in.suite.trajectory, spec.seed);
  addOdometryDrift(&poses, in.suite.odometry, spec.seed + 1000);
  const DriftStats drift = measureDrift(poses);

  std::string error;
  SceneCounts counts;
  if (!recordScene(in, spec, poses, files.bag + ".tmp", calibration, &gt, &counts, &error))
    return false;
  if (!writeGroundTruth(files.gt, gt, &error)) {
    std::cerr << "generate_dataset: " << error << "\n";
    return false;
  }
  if (std::rename((files.bag + ".tmp").c_str(), files.bag.c_str()) != 0) {
    std::cerr << "generate_dataset: cannot rename " << files.bag << ".tmp\n";
    return false;
  }
  std::ofstream(files.request) << scene_request;
  int support = 0;
  for (const auto& c : scene.contacts) support += c.support();
  const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
  char line[400];
  std::snprintf(line, sizeof(line),
                "  %s: %zu objects, %zu contacts (%d support), penetration %.2f mm; %zu frames, "
                "%d keyframes, %d detections; odometry drift max %.1f cm over %.2f m; %.0f s\n",
                spec.name.c_str(), scene.objects.size(), scene.contacts.size(), support,
                1000.0 * scene.max_penetration_m, poses.size(), counts.keyframes, counts.detections,
                100.0 * drift.max_m, drift.path_length_m, seconds);
  std::cout << line << std::flush;
  *drift_report << line;
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace geofusion;
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
  if (!applyOptions(&opt, &suite)) return 2;

  // The model set.
  ModelSet models;
  if (!loadModels(opt, suite, &models)) return 1;
  if (!makeDirs(opt.out_dir) || (opt.previews > 0 && !makeDirs(opt.out_dir + "/previews"))) {
    std::cerr << "generate_dataset: cannot create " << opt.out_dir << "\n";
    return 1;
  }

  RecordingLayout layout;
  layout.depth_encoding = opt.depth_encoding;
  layout.lz4 = opt.compress;
  const PinholeIntrinsics K;
  const std::string request = suiteRequest(opt, suite, models);

  std::cout << "generate_dataset: suite " << suite.name << " (" << suite.scenes.size()
            << " scenes, " << suite.keyframes << " keyframes each, images every "
            << suite.image_every << " of " << suite.camera_rate_hz << " Hz frames, "
            << models.size() << " classes from " << models.name() << ", " << opt.detector
            << " detections) into " << opt.out_dir << std::endl;
  const SuiteInputs inputs{opt, suite, models, layout, K};
  SequenceCalibration calibration(suite.detector.min_visible_pixels);
  std::ostringstream drift_report;
  const auto suite_start = Clock::now();
  int generated = 0;
  for (const SceneSpec& spec : suite.scenes) {
    const std::string scene_request = request + spec.describeChanges();
    if (cached(opt, spec, scene_request)) continue;
    if (!generateScene(inputs, spec, scene_request, &calibration, &drift_report)) return 1;
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
