#include "geofusion/simulation/dataset.h"

#include "geofusion/common/yaml_io.h"

#include <yaml-cpp/yaml.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <random>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace geofusion {

bool suiteByName(const std::string& name, SuiteSpec* suite) {
  SuiteSpec s;
  s.name = name;
  if (name == "demo") {
    s.model_set = "primitives";
    s.scenes = {{"demo_01", 7, 10}};
    s.keyframes = 60;
    s.clutter.area_x_m = 0.36;
    s.clutter.area_y_m = 0.26;
  } else if (name == "bench" || name == "bench_rgb" || name == "bench_iid") {
    // Six scenes of 16-20 objects (mean 18), as the paper's data set, seen by a 6D estimator
    // whose errors persist from frame to frame (docs/dataset.md): "bench" a DenseFusion-like
    // RGB-D estimator, "bench_rgb" a colour-only one on other scenes. "bench_iid": bench's scenes
    // with independent per-frame errors, for the paper's tables.
    const bool rgb = name == "bench_rgb";
    const int objects[] = {18, 16, 20, 17, 19, 18};
    for (int k = 0; k < 6; ++k) {
      s.scenes.push_back({name + "_0" + std::to_string(k + 1),
                          static_cast<unsigned>((rgb ? 201 : 101) + k), objects[k]});
    }
    if (name == "bench") {  // a changed scene: two objects taken away, two moved (issue 20)
      SceneSpec changed{"bench_07", 107, 18};
      changed.removed = 2;
      changed.moved = 2;
      s.scenes.push_back(changed);
    }
    s.model_set = "ycb_video";
    s.keyframes = 200;
    s.clutter.area_x_m = 0.45;
    s.clutter.area_y_m = 0.34;
    s.clutter.lean_fraction = 0.2;  // objects leaning on others (issue 20)
    s.detector_name = rgb ? "rgb" : name == "bench" ? "densefusion_persistent" : "densefusion";
    DetectorModel::byName(s.detector_name, &s.detector);
    s.depth = DepthNoise::structuredLight();  // the Fetch head camera, calibrated (issue 31)
    s.lens = LensDistortion::primesense();    // ... and its family's lens (issue 31)
  } else if (name == "vo" || name == "vo_fast") {
    // Visual odometry: every 30 Hz frame has images, table and floor are textured. "vo": the
    // table orbit of the other suites (15 s); "vo_fast": 10 s with a faster orbit and the head
    // swinging across the table (camera turns up to about 80 deg/s).
    s.model_set = "primitives";
    s.image_every = 1;
    s.textured_background = true;
    s.colour = ColourNoise::fetchHead();  // blur and rolling shutter as the head turns (issue 31)
    s.clutter.area_x_m = 0.36;
    s.clutter.area_y_m = 0.26;
    if (name == "vo") {
      s.scenes = {{"vo_orbit", 31, 10}};
      s.keyframes = 450;
    } else {
      s.scenes = {{"vo_fast", 32, 10}};
      s.keyframes = 300;
      s.trajectory.arc_rad = 3.2;
      s.trajectory.pause_fraction = 0.05;
      s.trajectory.look_amplitude_m = 0.3;
      s.trajectory.look_rate = 5.0;
    }
  } else {
    return false;
  }
  s.trajectory.frames = s.cameraFrames();
  s.trajectory.rate_hz = s.camera_rate_hz;
  *suite = s;
  return true;
}

std::vector<std::string> suiteNames() {
  return {"demo", "bench", "bench_rgb", "bench_iid", "vo", "vo_fast"};
}

std::string describeSuite(const SuiteSpec& s) {
  std::ostringstream o;
  o.precision(9);
  const ClutterConfig& c = s.clutter;
  const TrajectoryConfig& t = s.trajectory;
  const OdometryNoise& n = s.odometry;
  const DepthNoise& d = s.depth;
  const DetectorModel& m = s.detector;
  o << "generator v" << kGeneratorVersion << "; suite " << s.name << " " << s.model_set
    << "; keyframes " << s.keyframes << " every " << s.image_every << " at " << s.camera_rate_hz
    << " Hz; clutter " << c.area_x_m << " " << c.area_y_m << " " << c.stack_fraction << " "
    << c.lying_fraction << " " << c.lean_fraction << " " << c.max_penetration_m << " "
    << c.touch_distance_m << "; trajectory " << t.min_distance_m << " " << t.max_distance_m << " "
    << t.min_height_m << " " << t.max_height_m << " " << t.arc_rad << " " << t.pause_fraction
    << "; odometry " << n.translation_fraction << " " << n.yaw_rad_per_m << " "
    << n.translation_m_per_sqrt_m << " " << n.yaw_rad_per_sqrt_rad << "; depth " << d.describe()
    << "; detector " << m.translation_sigma_m << " " << m.rotation_sigma_rad << " "
    << m.gross_error_rate << " " << m.symmetric_flip_rate << " " << m.class_swap_rate << " "
    << m.miss_rate << " " << m.miss_occlusion_gain << " " << m.min_visible_pixels << " "
    << m.false_positives_per_frame;
  for (const auto& g : m.class_noise_gain) o << " " << g.first << "=" << g.second;
  // Later additions, said only when set (the requests of earlier suites stay as they were).
  if (t.look_amplitude_m != TrajectoryConfig().look_amplitude_m ||
      t.look_rate != TrajectoryConfig().look_rate)
    o << "; look " << t.look_amplitude_m << " " << t.look_rate;
  if (s.textured_background) o << "; textured background";
  if (s.colour.enabled) o << "; colour " << s.colour.describe();
  if (s.lens.any()) o << "; lens " << s.lens.describe();
  const PersistentErrorModel& e = m.persistence;
  if (e.enabled() || e.score_correctness != PersistentErrorModel().score_correctness) {
    o << "; persistent " << e.bias_translation_m << " " << e.bias_rotation_rad << " "
      << e.bias_correlation_keyframes << " " << e.ray_depth_fraction << " "
      << e.ray_correlation_keyframes << " " << e.swap_stretch_rate << " " << e.swap_stretch_min
      << "-" << e.swap_stretch_max << " " << e.miss_stretch_rate << " " << e.miss_stretch_min << "-"
      << e.miss_stretch_max << " " << e.phantoms << " " << e.phantom_stretch_min << "-"
      << e.phantom_stretch_max << " " << e.phantom_presence << " " << e.score_correctness;
  }
  return o.str();
}

bool makeSuiteScene(const SuiteSpec& suite, const SceneSpec& spec, const ModelSet& models,
                    ClutterScene* scene, unsigned* used_seed, std::string* report, int attempts) {
  ClutterConfig clutter = suite.clutter;
  clutter.num_objects = spec.num_objects;
  std::string reasons;
  for (int a = 0; a < attempts; ++a) {
    const unsigned seed = spec.seed + 7919u * static_cast<unsigned>(a);
    std::string why;
    if (makeClutterScene(models, clutter, seed, scene, &why)) {
      if (used_seed) *used_seed = seed;
      return true;
    }
    reasons += (reasons.empty() ? "" : "; ") + ("seed " + std::to_string(seed) + ": " + why);
  }
  if (report) *report = reasons;
  return false;
}

std::string SceneSpec::describeChanges() const {
  if (removed == 0 && moved == 0) return "";
  std::ostringstream o;
  o << "; changes " << removed << " removed " << moved << " moved at " << change_at;
  return o.str();
}

namespace {

// Objects whose only contacts with other objects are their own supports (nothing rests or leans
// on them), and among them those whose only contact is the table's support.
void changeableObjects(const ClutterScene& scene, std::vector<int>* removable,
                       std::vector<int>* movable) {
  const int n = static_cast<int>(scene.objects.size());
  for (int i = 0; i < n; ++i) {
    bool carries = false, only_table = true;
    for (const FeatureContact& c : scene.contacts) {
      if (c.object_a != i && c.object_b != i) continue;
      const int other = c.object_a == i ? c.object_b : c.object_a;
      if (!(c.support() && c.object_b == i)) carries |= other >= 0;
      only_table &= other == -1 && c.support();
    }
    if (carries) continue;
    removable->push_back(i);
    if (only_table) movable->push_back(i);
  }
}

// A free place on the table for object i: its footprint circle (about its origin, as it stands)
// 2 cm clear of every object there at the end and of its old place, 5 cm inside the table's edges.
double footprint(const SceneObject& o) {
  double r = 0.0;
  for (const auto& v : o.model->mesh.vertices)
    r = std::max(r, (o.T_world_obj.linear() * v.cast<double>()).head<2>().norm());
  return r;
}

bool freeSpot(const ClutterScene& scene, int i, std::mt19937* rng, Eigen::Vector2d* xy) {
  const SceneObject& moving = scene.objects[static_cast<std::size_t>(i)];
  const double r = footprint(moving);
  std::uniform_real_distribution<double> ux(-0.5 * scene.table.size_x_m + 0.05 + r,
                                            0.5 * scene.table.size_x_m - 0.05 - r);
  std::uniform_real_distribution<double> uy(-0.5 * scene.table.size_y_m + 0.05 + r,
                                            0.5 * scene.table.size_y_m - 0.05 - r);
  for (int attempt = 0; attempt < 500; ++attempt) {
    const Eigen::Vector2d p(ux(*rng), uy(*rng));
    bool clear = (p - moving.T_world_obj.translation().head<2>()).norm() > 2 * r + 0.02;
    for (const SceneObject& o : scene.objects) {
      if (!clear) break;
      if (&o == &moving || !o.presentAtTheEnd()) continue;
      clear = (p - o.T_world_obj.translation().head<2>()).norm() > r + footprint(o) + 0.02;
    }
    if (clear) {
      *xy = p;
      return true;
    }
  }
  return false;
}

}  // namespace

bool applySceneChanges(const SceneSpec& spec, int frames, const ClutterConfig& clutter,
                       ClutterScene* scene, std::string* report) {
  if (spec.removed == 0 && spec.moved == 0) return true;
  std::vector<int> removable, movable;
  changeableObjects(*scene, &removable, &movable);
  std::mt19937 rng(spec.seed + 3000);
  // The smallest first: the table around dense clutter has room for a can, seldom for a box.
  std::shuffle(movable.begin(), movable.end(), rng);
  std::stable_sort(movable.begin(), movable.end(), [&](int a, int b) {
    return footprint(scene->objects[static_cast<std::size_t>(a)]) <
           footprint(scene->objects[static_cast<std::size_t>(b)]);
  });
  if (static_cast<int>(movable.size()) < spec.moved) {
    if (report) *report = "too few objects stand on the table alone to move";
    return false;
  }
  const int change = static_cast<int>(std::lround(spec.change_at * (frames - 1)));
  std::ostringstream log;
  std::vector<int> changed;
  for (int m = 0; m < spec.moved; ++m) {
    const int i = movable[static_cast<std::size_t>(m)];
    Eigen::Vector2d xy;
    if (!freeSpot(*scene, i, &rng, &xy)) {
      if (report)
        *report = "no free spot on the table to move " +
                  scene->objects[static_cast<std::size_t>(i)].model->name + " to";
      return false;
    }
    SceneObject copy = scene->objects[static_cast<std::size_t>(i)];
    copy.T_world_obj.translation().head<2>() = xy;
    copy.present_from_frame = change;
    scene->objects[static_cast<std::size_t>(i)].present_until_frame = change;
    scene->objects.push_back(copy);
    changed.push_back(i);
    log << (log.tellp() > 0 ? ", " : "") << copy.model->name << " #" << i << " moved to #"
        << scene->objects.size() - 1;
  }
  std::shuffle(removable.begin(), removable.end(), rng);
  int removed = 0;
  for (int i : removable) {
    if (removed == spec.removed) break;
    if (std::find(changed.begin(), changed.end(), i) != changed.end()) continue;
    scene->objects[static_cast<std::size_t>(i)].present_until_frame = change;
    log << (log.tellp() > 0 ? ", " : "") << scene->objects[static_cast<std::size_t>(i)].model->name
        << " #" << i << " taken away";
    ++removed;
  }
  if (removed < spec.removed) {
    if (report) *report = "too few objects carry nothing to take away";
    return false;
  }
  scene->contacts = groundTruthContacts(*scene, clutter);
  if (report) *report = "at frame " + std::to_string(change) + ": " + log.str();
  return true;
}

// --------------------------------------------------------------------------------------------
// Ground-truth YAML.
namespace {

std::string featureKey(const FeatureRef& f) {
  return std::string(f.plane ? "plane " : "curve ") + std::to_string(f.index);
}

FeatureRef parseFeature(const std::string& s) {
  FeatureRef f;
  std::istringstream in(s);
  std::string kind;
  in >> kind >> f.index;
  if (!in || (kind != "plane" && kind != "curve")) {
    throw std::runtime_error("feature '" + s + "' is not 'plane N' or 'curve N'");
  }
  f.plane = kind == "plane";
  return f;
}

}  // namespace

bool writeGroundTruth(const std::string& path, const GroundTruth& gt, std::string* error) {
  YAML::Emitter out;
  out.SetDoublePrecision(12);  // significant digits
  out << YAML::BeginMap;
  out << YAML::Key << "format" << YAML::Value << "geofusion_ground_truth_v1";
  out << YAML::Key << "suite" << YAML::Value << gt.suite;
  out << YAML::Key << "scene" << YAML::Value << gt.scene_name;
  out << YAML::Key << "seed" << YAML::Value << gt.seed;
  out << YAML::Key << "scene_seed" << YAML::Value << gt.scene_seed;
  out << YAML::Key << "model_set" << YAML::Value << gt.model_set;
  out << YAML::Key << "detector" << YAML::Value << gt.detector;
  if (gt.platform != "robot" || gt.odometry != "wheel") {  // the generated suites' files unchanged
    out << YAML::Key << "platform" << YAML::Value << gt.platform;
    out << YAML::Key << "odometry" << YAML::Value << gt.odometry;
  }
  out << YAML::Key << "frame_ids" << YAML::Value << YAML::Flow << YAML::BeginMap;
  out << YAML::Key << "map" << YAML::Value << gt.map_frame;
  out << YAML::Key << "odom" << YAML::Value << gt.odom_frame;
  out << YAML::Key << "base" << YAML::Value << gt.base_frame;
  out << YAML::Key << "camera_link" << YAML::Value << gt.camera_link_frame;
  out << YAML::Key << "camera" << YAML::Value << gt.camera_frame << YAML::EndMap;
  const PinholeIntrinsics& K = gt.intrinsics;
  out << YAML::Key << "intrinsics" << YAML::Value << YAML::Flow << YAML::BeginMap;
  out << YAML::Key << "width" << YAML::Value << K.width << YAML::Key << "height" << YAML::Value
      << K.height << YAML::Key << "fx" << YAML::Value << K.fx << YAML::Key << "fy" << YAML::Value
      << K.fy << YAML::Key << "cx" << YAML::Value << K.cx << YAML::Key << "cy" << YAML::Value
      << K.cy << YAML::EndMap;
  const TableSpec& table = gt.scene.table;
  out << YAML::Key << "table" << YAML::Value << YAML::Flow << YAML::BeginMap;
  out << YAML::Key << "height" << YAML::Value << table.height_m;
  out << YAML::Key << "size" << YAML::Value << YAML::Flow << YAML::BeginSeq << table.size_x_m
      << table.size_y_m << table.thickness_m << YAML::EndSeq << YAML::EndMap;
  out << YAML::Key << "objects" << YAML::Value << YAML::BeginSeq;
  for (std::size_t i = 0; i < gt.scene.objects.size(); ++i) {
    const SceneObject& o = gt.scene.objects[i];
    out << YAML::Flow << YAML::BeginMap;
    out << YAML::Key << "index" << YAML::Value << i;
    out << YAML::Key << "class_name" << YAML::Value << o.model->name;
    out << YAML::Key << "class_id" << YAML::Value << o.model->id;
    yaml_io::emitPose(out, "pose", o.T_world_obj);
    if (o.present_from_frame != 0)
      out << YAML::Key << "present_from_frame" << YAML::Value << o.present_from_frame;
    if (!o.presentAtTheEnd())
      out << YAML::Key << "present_until_frame" << YAML::Value << o.present_until_frame;
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;
  out << YAML::Key << "max_penetration_m" << YAML::Value << gt.scene.max_penetration_m;
  out << YAML::Key << "contacts" << YAML::Value << YAML::BeginSeq;
  for (const FeatureContact& c : gt.scene.contacts) {
    out << YAML::Flow << YAML::BeginMap;
    out << YAML::Key << "a" << YAML::Value << c.object_a;
    out << YAML::Key << "b" << YAML::Value << c.object_b;
    out << YAML::Key << "type" << YAML::Value << shortName(c.type);
    out << YAML::Key << "feature_a" << YAML::Value << featureKey(c.feature_a);
    out << YAML::Key << "feature_b" << YAML::Value << featureKey(c.feature_b);
    out << YAML::Key << "kind" << YAML::Value << toString(c.kind);
    out << YAML::Key << "normal" << YAML::Value << YAML::Flow << YAML::BeginSeq << c.normal.x()
        << c.normal.y() << c.normal.z() << YAML::EndSeq;
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;
  out << YAML::Key << "phantoms" << YAML::Value << YAML::BeginSeq;
  for (const PhantomObject& p : gt.phantoms) {
    out << YAML::Flow << YAML::BeginMap;
    out << YAML::Key << "host" << YAML::Value << p.host;
    out << YAML::Key << "class_name" << YAML::Value << p.class_name;
    yaml_io::emitPose(out, "pose", p.T_world_obj);
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;
  out << YAML::Key << "frames" << YAML::Value << YAML::BeginSeq;
  for (const GroundTruthFrame& f : gt.frames) {
    out << YAML::Flow << YAML::BeginMap;
    out << YAML::Key << "index" << YAML::Value << f.index;
    char stamp[32];
    std::snprintf(stamp, sizeof(stamp), "%.9f", f.stamp_s);
    out << YAML::Key << "stamp" << YAML::Value << stamp;
    out << YAML::Key << "keyframe" << YAML::Value << f.keyframe;
    yaml_io::emitPose(out, "map_base", f.T_map_base);
    yaml_io::emitPose(out, "odom_base", f.T_odom_base);
    yaml_io::emitPose(out, "base_camera_link", f.T_base_link);
    yaml_io::emitPose(out, "map_camera", f.T_map_optical);
    if (f.keyframe) {
      out << YAML::Key << "visible_fraction" << YAML::Value << YAML::Flow << YAML::BeginSeq;
      for (double v : f.visible_fraction) {
        out << std::round(v * 1000.0) / 1000.0;
      }
      out << YAML::EndSeq;
      out << YAML::Key << "visible_pixels" << YAML::Value << YAML::Flow << f.visible_pixels;
      if (std::any_of(f.place_visible_fraction.begin(), f.place_visible_fraction.end(),
                      [](double v) { return v >= 0.0; })) {
        out << YAML::Key << "place_visible_fraction" << YAML::Value << YAML::Flow << YAML::BeginSeq;
        for (double v : f.place_visible_fraction) out << std::round(v * 1000.0) / 1000.0;
        out << YAML::EndSeq;
      }
      out << YAML::Key << "visible_boxes" << YAML::Value << YAML::Flow << YAML::BeginSeq;
      for (const PixelBox& b : f.visible_boxes) {
        out << YAML::Flow << YAML::BeginSeq << b.x << b.y << b.width << b.height << YAML::EndSeq;
      }
      out << YAML::EndSeq;
      out << YAML::Key << "detection_truth" << YAML::Value << YAML::Flow << f.detection_truth;
      out << YAML::Key << "swapped" << YAML::Value << YAML::Flow << f.swapped;
    }
    out << YAML::EndMap;
  }
  out << YAML::EndSeq << YAML::EndMap;
  return yaml_io::writeAtomically(
      path,
      "# GeoFusion ground truth (docs/dataset.md). Poses [x, y, z, qx, qy, qz, qw], metres;\n"
      "# T_a_b maps b coordinates into a; map = world, z up, origin on the floor.\n",
      out, error);
}

bool readGroundTruth(const std::string& path, const ModelSet& models, GroundTruth* gt,
                     std::string* error) {
  try {
    const YAML::Node root = YAML::LoadFile(path);
    if (root["format"].as<std::string>("") != "geofusion_ground_truth_v1") {
      throw std::runtime_error("not a geofusion_ground_truth_v1 file");
    }
    GroundTruth g;
    g.suite = root["suite"].as<std::string>("");
    g.scene_name = root["scene"].as<std::string>("");
    g.seed = root["seed"].as<unsigned>(0);
    g.scene_seed = root["scene_seed"].as<unsigned>(0);
    g.model_set = root["model_set"].as<std::string>("");
    g.detector = root["detector"].as<std::string>("");
    g.platform = root["platform"].as<std::string>("robot");
    g.odometry = root["odometry"].as<std::string>("wheel");
    if (g.platform != "robot" && g.platform != "hand_held") {
      throw std::runtime_error("platform must be robot or hand_held, not '" + g.platform + "'");
    }
    if (g.odometry != "wheel" && g.odometry != "camera_trajectory" && g.odometry != "none") {
      throw std::runtime_error("odometry must be wheel, camera_trajectory or none, not '" +
                               g.odometry + "'");
    }
    const YAML::Node ids = root["frame_ids"];
    g.map_frame = ids["map"].as<std::string>();
    g.odom_frame = ids["odom"].as<std::string>();
    g.base_frame = ids["base"].as<std::string>();
    g.camera_link_frame = ids["camera_link"].as<std::string>();
    g.camera_frame = ids["camera"].as<std::string>();
    const YAML::Node k = root["intrinsics"];
    g.intrinsics.width = k["width"].as<int>();
    g.intrinsics.height = k["height"].as<int>();
    g.intrinsics.fx = k["fx"].as<double>();
    g.intrinsics.fy = k["fy"].as<double>();
    g.intrinsics.cx = k["cx"].as<double>();
    g.intrinsics.cy = k["cy"].as<double>();
    const YAML::Node table = root["table"];
    g.scene.table.height_m = table["height"].as<double>();
    g.scene.table.size_x_m = table["size"][0].as<double>();
    g.scene.table.size_y_m = table["size"][1].as<double>();
    g.scene.table.thickness_m = table["size"][2].as<double>();
    for (const YAML::Node& o : root["objects"]) {
      const std::string name = o["class_name"].as<std::string>();
      const ObjectModel* model = models.find(name);
      if (!model) throw std::runtime_error("class '" + name + "' is not in the model set");
      SceneObject obj;
      for (const auto& m : models.models())
        if (m.get() == model) obj.model = m;
      obj.T_world_obj = yaml_io::parsePose(o["pose"], "object pose");
      obj.present_from_frame = o["present_from_frame"].as<int>(0);
      obj.present_until_frame = o["present_until_frame"].as<int>(-1);
      g.scene.objects.push_back(obj);
    }
    g.scene.max_penetration_m = root["max_penetration_m"].as<double>(0.0);
    const int n = static_cast<int>(g.scene.objects.size());
    for (const YAML::Node& c : root["contacts"]) {
      FeatureContact fc;
      fc.object_a = c["a"].as<int>();
      fc.object_b = c["b"].as<int>();
      if (fc.object_a < -1 || fc.object_a >= n || fc.object_b < -1 || fc.object_b >= n) {
        throw std::runtime_error("contact refers to an object that does not exist");
      }
      fc.type = contactTypeOfShortName(c["type"].as<std::string>());
      fc.feature_a = parseFeature(c["feature_a"].as<std::string>());
      fc.feature_b = parseFeature(c["feature_b"].as<std::string>());
      fc.kind = contactKindOfName(c["kind"].as<std::string>());
      const YAML::Node nn = c["normal"];
      fc.normal = Eigen::Vector3d(nn[0].as<double>(), nn[1].as<double>(), nn[2].as<double>());
      g.scene.contacts.push_back(fc);
    }
    for (const YAML::Node& p : root["phantoms"]) {
      PhantomObject phantom;
      phantom.host = p["host"].as<int>();
      if (phantom.host < 0 || phantom.host >= n) {
        throw std::runtime_error("phantom beside an object that does not exist");
      }
      phantom.class_name = p["class_name"].as<std::string>();
      phantom.T_world_obj = yaml_io::parsePose(p["pose"], "phantom pose");
      g.phantoms.push_back(phantom);
    }
    for (const YAML::Node& f : root["frames"]) {
      GroundTruthFrame fr;
      fr.index = f["index"].as<int>();
      fr.stamp_s = f["stamp"].as<double>();
      fr.keyframe = f["keyframe"].as<bool>();
      fr.T_map_base = yaml_io::parsePose(f["map_base"], "map_base");
      fr.T_odom_base = yaml_io::parsePose(f["odom_base"], "odom_base");
      fr.T_base_link = yaml_io::parsePose(f["base_camera_link"], "base_camera_link");
      fr.T_map_optical = yaml_io::parsePose(f["map_camera"], "map_camera");
      if (fr.keyframe) {
        fr.visible_fraction = f["visible_fraction"].as<std::vector<double>>();
        fr.visible_pixels = f["visible_pixels"].as<std::vector<int>>();
        if (f["place_visible_fraction"])
          fr.place_visible_fraction = f["place_visible_fraction"].as<std::vector<double>>();
        fr.detection_truth = f["detection_truth"].as<std::vector<int>>();
        for (const YAML::Node& b : f["visible_boxes"]) {
          fr.visible_boxes.push_back(
              PixelBox{b[0].as<int>(), b[1].as<int>(), b[2].as<int>(), b[3].as<int>()});
        }
        if (f["swapped"]) fr.swapped = f["swapped"].as<std::vector<int>>();
        if (static_cast<int>(fr.visible_fraction.size()) != n ||
            static_cast<int>(fr.visible_pixels.size()) != n ||
            (!fr.visible_boxes.empty() && static_cast<int>(fr.visible_boxes.size()) != n) ||
            (!fr.place_visible_fraction.empty() &&
             static_cast<int>(fr.place_visible_fraction.size()) != n)) {
          throw std::runtime_error("frame " + std::to_string(fr.index) +
                                   ": visibility lists do not have one entry an object");
        }
      }
      g.frames.push_back(std::move(fr));
    }
    *gt = std::move(g);
    return true;
  } catch (const std::exception& e) {
    if (error) *error = path + ": " + e.what();
    return false;
  }
}

bool writeFramePreview(const std::string& prefix, const PinholeIntrinsics& K,
                       const SequenceFrame& frame, std::string* error) {
  const std::size_t n = static_cast<std::size_t>(K.width) * K.height;
  if (frame.images.rgb.size() != 3 * n || frame.images.depth.size() != n) {
    if (error) *error = "frame images do not match the intrinsics";
    return false;
  }
  cv::Mat rgb(K.height, K.width, CV_8UC3, const_cast<std::uint8_t*>(frame.images.rgb.data()));
  cv::Mat bgr;
  cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
  cv::Mat depth8(K.height, K.width, CV_8UC1);
  cv::Mat holes(K.height, K.width, CV_8UC1);
  for (int v = 0; v < K.height; ++v) {
    for (int u = 0; u < K.width; ++u) {
      const float z = frame.images.depth[static_cast<std::size_t>(v) * K.width + u];
      holes.at<std::uint8_t>(v, u) = z > 0.f ? 0 : 255;
      depth8.at<std::uint8_t>(v, u) =
          static_cast<std::uint8_t>(std::clamp((z - 0.4) / 2.1 * 255.0, 0.0, 255.0));
    }
  }
  cv::Mat depth_colour;
  cv::applyColorMap(depth8, depth_colour, cv::COLORMAP_TURBO);
  depth_colour.setTo(cv::Scalar(0, 0, 0), holes);
  cv::Mat overlay = bgr.clone();
  for (std::size_t k = 0; k < frame.detections.size(); ++k) {
    const RawDetection& d = frame.detections[k];
    const bool truth = k < frame.detection_truth.size() && frame.detection_truth[k] >= 0;
    const cv::Scalar colour = truth ? cv::Scalar(60, 200, 60) : cv::Scalar(40, 40, 230);
    cv::rectangle(overlay, cv::Rect(d.box.x, d.box.y, d.box.width, d.box.height), colour, 1);
    cv::putText(overlay, d.class_name.substr(0, 14), cv::Point(d.box.x, std::max(8, d.box.y - 2)),
                cv::FONT_HERSHEY_PLAIN, 0.8, colour, 1);
  }
  try {
    if (!cv::imwrite(prefix + "_rgb.png", bgr) ||
        !cv::imwrite(prefix + "_depth.png", depth_colour) ||
        !cv::imwrite(prefix + "_detections.png", overlay)) {
      if (error) *error = "cannot write " + prefix + "_*.png";
      return false;
    }
  } catch (const cv::Exception& e) {
    if (error) *error = e.what();
    return false;
  }
  return true;
}

}  // namespace geofusion
