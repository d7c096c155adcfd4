// geofusion.core: the ROS-free core from Python (pybind11), docs/python.md. A model set, the one
// configuration loader, the scene estimator fed keyframe by keyframe with NumPy arrays, the
// consistency score of a pose against a depth image and the visual odometry. Images are read in
// place from NumPy's buffer (float32 depth, uint8 grey, C-contiguous); bad input raises with the
// loader's or the detection checks' message. The GIL is held throughout: the estimator and its
// OSMesa renderer are used by one thread at a time.
#include "python_conversions.h"

#include "geofusion/config/config.h"
#include "geofusion/estimation/bop_results.h"
#include "geofusion/estimation/frame_by_frame.h"
#include "geofusion/estimation/map_stability.h"
#include "geofusion/estimation/scene_estimator.h"
#include "geofusion/model/object_model.h"
#include "geofusion/odometry/visual_odometry.h"
#include "geofusion/render/consistency.h"
#include "geofusion/render/renderer.h"

#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>
#include <set>
#include <string>
#include <vector>

namespace py = pybind11;

namespace geofusion {
namespace python {
namespace {

// One OSMesa renderer for every estimator and score of the process (contexts are costly).
std::shared_ptr<OffscreenRenderer> sharedRenderer() {
  static std::shared_ptr<OffscreenRenderer> renderer = std::make_shared<OffscreenRenderer>();
  return renderer;
}

// The configuration: defaults, a YAML file, or a dict (written as YAML and read by the same
// loader). Errors raise ValueError with every message; warnings (unknown keys) are Python warnings.
GeoFusionConfig loadConfig(const py::object& source) {
  GeoFusionConfig config;
  ConfigReport report;
  bool ok = true;
  if (source.is_none()) return config;
  if (py::isinstance<py::str>(source)) {
    ok = loadConfigFile(source.cast<std::string>(), &config, &report);
  } else if (py::isinstance<py::dict>(source)) {
    const std::string text =
        py::module_::import("yaml").attr("safe_dump")(source).cast<std::string>();
    ok = loadConfigText(text, "the dict", &config, &report);
  } else {
    throw py::type_error("config: expected None, a YAML file's path or a dict, got " +
                         std::string(py::str(source.get_type())));
  }
  for (const std::string& w : report.warnings)
    PyErr_WarnEx(PyExc_UserWarning, ("geofusion config: " + w).c_str(), 1);
  if (!ok || !report.ok()) {
    std::string all = "geofusion config: cannot load";
    for (const std::string& e : report.errors) all += "\n  " + e;
    throw py::value_error(all);
  }
  return config;
}

// The package's folder (the model-set table), through rospkg: found when the workspace is
// sourced, else a clear error rather than a path built from nothing.
std::string packageDir() {
  try {
    return py::module_::import("rospkg")
        .attr("RosPack")()
        .attr("get_path")("geofusion")
        .cast<std::string>();
  } catch (const py::error_already_set&) {
    throw py::value_error(
        "model set: the geofusion package is not found: source the workspace's setup.bash "
        "first (or give a model-set YAML file's path)");
  }
}

std::shared_ptr<ModelSet> loadModels(const std::string& name, const std::string& models_dir,
                                     const GeoFusionConfig& config) {
  auto models = std::make_shared<ModelSet>();
  std::vector<std::string> errors;
  const bool by_name = name != "primitives" && name.find('/') == std::string::npos &&
                       name.find(".yaml") == std::string::npos;
  const std::string package = by_name ? packageDir() : "";
  if (!loadModelSet(name, models_dir, package, models.get(), &errors,
                    config.model_set.surface_features)) {
    std::string all = "model set '" + name + "': cannot load";
    for (const std::string& e : errors) all += "\n  " + e;
    throw py::value_error(all);
  }
  for (const std::string& e : errors)
    PyErr_WarnEx(PyExc_UserWarning, ("geofusion model set: " + e).c_str(), 1);
  return models;
}

// The scene estimator as run_offline and the nodelet run it: the detection checks of the
// pipeline (FrameByFrame: pose, class, score, range, cap), then SceneEstimator::addKeyframe.
class PyEstimator {
 public:
  PyEstimator(std::shared_ptr<ModelSet> models, const GeoFusionConfig& config)
      : models_(std::move(models)), config_(config), checker_(config.checks) {
    estimator_ = std::make_unique<SceneEstimator>(*models_, config_.estimator, sharedRenderer());
    estimator_->prepare();
    std::set<std::string> classes;
    for (const auto& m : models_->models()) classes.insert(m->name);
    checker_.setKnownClasses(std::move(classes));
  }

  py::dict addKeyframe(const py::array& depth, const py::handle& K, const py::handle& T_odom_cam,
                       const py::handle& detections, const py::object& stamp) {
    DepthInput d = depthInput(depth, "depth");
    Keyframe kf;
    kf.K = intrinsics(K, d.view.width, d.view.height);
    kf.depth = d.view;
    kf.T_odom_cam = pose(T_odom_cam, "T_odom_cam");
    kf.stamp_s =
        stamp.is_none() ? static_cast<double>(estimator_->numKeyframes()) : stamp.cast<double>();
    const std::vector<RawDetection> raw = rawDetections(detections, *models_, checker_);
    DetectionTally tally;
    for (const WorldDetection& w : checker_.process(raw, kf.T_odom_cam, &tally))
      kf.detections.push_back(w.measurement);
    KeyframeResult result = estimator_->addKeyframe(kf);
    py::dict out = keyframeDict(result);
    contacts_ = result.contacts;
    record_.keyframes.push_back(std::move(result));  // for bop_results
    last_K_ = kf.K;
    out["skipped_detections"] =
        out["skipped_detections"].cast<std::size_t>() + tally.totalSkipped();
    return out;
  }

  py::dict finish() {
    const KeyframeResult r = estimator_->finish();
    py::dict out = keyframeDict(r);
    contacts_ = r.contacts;
    out["trajectory"] = poses(estimator_->trajectory());
    out["stamps"] = estimator_->keyframeStamps();
    const SupportPlane& plane = estimator_->supportPlane();
    if (plane.valid) {
      out["support_plane"] =
          py::dict(py::arg("normal") = vector(plane.normal), py::arg("height") = plane.height);
    }
    return out;
  }

  // The keyframes so far as BOP results (bop_results.h); written to `path` when one is given.
  std::string bopResults(const py::object& path, int scene_id) const {
    BopIds ids;
    ids.scene_id = scene_id;
    if (!path.is_none()) {
      std::string error;
      if (!writeBopResults(path.cast<std::string>(), keyframeMapImages(record_), last_K_, ids,
                           &error))
        throw std::runtime_error("bop_results: " + error);
    }
    return bopResultsCsv(keyframeMapImages(record_), last_K_, ids);
  }

  // The map so far under gravity on its support plane (physics/stability.h, the `physics`
  // settings of the configuration).
  py::dict stability() const {
    const SupportPlane& plane = estimator_->supportPlane();
    const physics::StabilityResult r = checkMapStability(
        estimator_->objects(), &plane, config_.estimator.gravity, config_.estimator.physics);
    py::list bodies;
    for (const physics::BodyMotion& m : r.bodies)
      bodies.append(py::dict(
          py::arg("id") = m.id, py::arg("simulated") = m.simulated, py::arg("problem") = m.problem,
          py::arg("translation_m") = m.translation_m, py::arg("rotation_deg") = m.rotation_deg,
          py::arg("start_penetration_m") = m.start_penetration_m,
          py::arg("penetrating_id") = m.penetrating_id,
          py::arg("interpenetrating") = m.interpenetrating, py::arg("stable") = m.stable));
    return py::dict(py::arg("objects") = bodies, py::arg("has_plane") = r.has_plane,
                    py::arg("simulated") = r.simulated,
                    py::arg("interpenetrating") = r.interpenetrating,
                    py::arg("checked") = r.checked, py::arg("stable") = r.stable,
                    py::arg("mean_translation_m") = r.mean_translation_m,
                    py::arg("max_translation_m") = r.max_translation_m,
                    py::arg("max_rotation_deg") = r.max_rotation_deg,
                    py::arg("least_stable_pair") =
                        py::make_tuple(r.least_stable_pair.first, r.least_stable_pair.second),
                    py::arg("warnings") = r.warnings);
  }

  // The map so far as a plan (scene_graph.h): per object its relations, whether it stands (the
  // stability check above) and whether it is free to pick, and the removal order.
  py::dict sceneGraph() const {
    const SupportPlane& plane = estimator_->supportPlane();
    const physics::StabilityResult stability = checkMapStability(
        estimator_->objects(), &plane, config_.estimator.gravity, config_.estimator.physics);
    const SupportGraph g =
        mapSupportGraph(estimator_->objects(), contacts_, config_.estimator.gravity, &stability,
                        config_.scene_graph);
    py::list nodes;
    for (const SupportGraphNode& n : g.nodes)
      nodes.append(py::dict(
          py::arg("id") = n.id, py::arg("class_name") = n.class_name,
          py::arg("supported_by") = n.supported_by, py::arg("supports") = n.supports,
          py::arg("leans_on") = n.leans_on, py::arg("leaned_on_by") = n.leaned_on_by,
          py::arg("beside") = n.beside, py::arg("over") = n.over,
          py::arg("covered_by") = n.covered_by,
          py::arg("stable") = n.stable < 0 ? py::object(py::none()) : py::bool_(n.stable == 1),
          py::arg("free_to_pick") = n.free_to_pick, py::arg("removal_step") = n.removal_step));
    return py::dict(py::arg("objects") = nodes, py::arg("removal_order") = g.removal_order,
                    py::arg("warnings") = g.warnings);
  }

  py::list objects() const { return objectList(estimator_->objects()); }
  py::array trajectory() const { return poses(estimator_->trajectory()); }
  int numKeyframes() const { return estimator_->numKeyframes(); }
  std::string method() const { return toString(config_.estimator.method); }

 private:
  std::shared_ptr<ModelSet> models_;
  GeoFusionConfig config_;
  FrameByFrame checker_;
  std::unique_ptr<SceneEstimator> estimator_;
  RunResults record_;                     ///< every keyframe's result (bop_results)
  std::vector<FeatureContact> contacts_;  ///< of the latest map (addKeyframe or finish)
  PinholeIntrinsics last_K_;
};

// f_gc of one pose against a depth image, with the configuration's consistency settings.
py::dict consistency(const ModelSet& models, const std::string& class_name,
                     const py::handle& T_cam_obj, const py::array& depth, const py::handle& K,
                     const py::object& config_source) {
  const GeoFusionConfig config = loadConfig(config_source);
  std::shared_ptr<const ObjectModel> model;
  for (const auto& m : models.models())
    if (m->name == class_name) model = m;
  if (!model) throw py::value_error(unknownClass(class_name, models));
  const DepthInput d = depthInput(depth, "depth");
  const PinholeIntrinsics intr = intrinsics(K, d.view.width, d.view.height);
  ConsistencyScorer scorer(sharedRenderer(), config.estimator.consistency);
  const ConsistencyResult r = scorer.score(model, pose(T_cam_obj, "T_cam_obj"), d.view, intr);
  return py::dict(py::arg("score") = r.score, py::arg("r_in") = r.r_in, py::arg("r_out") = r.r_out,
                  py::arg("r_occ") = r.r_occ, py::arg("determined") = r.determined,
                  py::arg("rendered") = r.rendered, py::arg("inliers") = r.inliers,
                  py::arg("outliers") = r.outliers, py::arg("occluded") = r.occluded,
                  py::arg("missing") = r.missing);
}

// The visual odometry; the camera matrix given once (constructor) or with each frame.
class PyVisualOdometry {
 public:
  PyVisualOdometry(const GeoFusionConfig& config, const py::object& K)
      : vo_(config.visual_odometry), K_(K) {}

  py::dict track(const py::array& grey, const py::array& depth, const py::object& K, double stamp) {
    const GreyInput g = greyInput(grey, "grey");
    const DepthInput d = depthInput(depth, "depth");
    if (g.view.width != d.view.width || g.view.height != d.view.height)
      throw py::value_error("track: grey and depth differ in size (" + shape(grey) + " and " +
                            shape(depth) + "): the depth must be registered to the grey image");
    const py::object& camera = K.is_none() ? K_ : K;
    if (camera.is_none())
      throw py::value_error("track: no camera matrix: give K here or to VisualOdometry(K=...)");
    const VoFrameResult r =
        vo_.track(g.view, d.view, intrinsics(camera, d.view.width, d.view.height), stamp);
    return py::dict(py::arg("state") = toString(r.state), py::arg("pose_valid") = r.pose_valid,
                    py::arg("T_odom_cam") = matrix(r.T_odom_cam.matrix()),
                    py::arg("covariance") = matrix(r.covariance),
                    py::arg("restarted") = r.restarted, py::arg("relocalised") = r.relocalised,
                    py::arg("by_depth") = r.by_depth, py::arg("keyframe") = r.keyframe,
                    py::arg("features") = r.features,
                    py::arg("features_with_depth") = r.features_with_depth,
                    py::arg("matches") = r.matches, py::arg("inliers") = r.inliers,
                    py::arg("time_ms") = r.time_ms, py::arg("problem") = r.problem);
  }

  void reset(const py::object& T) {
    vo_.reset(T.is_none() ? Eigen::Isometry3d::Identity() : pose(T, "T_odom_cam"));
  }
  int numKeyframes() const { return vo_.numKeyframes(); }

 private:
  VisualOdometry vo_;
  py::object K_;
};

// The configuration as Python sees it: an opaque object made by load_config.
struct PyConfig {
  GeoFusionConfig config;
};

}  // namespace

void bindModule(py::module_& m) {
  m.doc() = "GeoFusion's ROS-free core: scene estimation from keyframes (docs/python.md)";
  py::class_<PyConfig>(m, "Config", "The one configuration (docs/parameters.md)")
      .def(
          "yaml",
          [](const PyConfig& c, bool changed_only) { return configYaml(c.config, changed_only); },
          py::arg("changed_only") = false, "The effective configuration as YAML.")
      .def_property_readonly("method", [](const PyConfig& c) { return c.config.method; });
  m.def(
      "load_config", [](const py::object& source) { return PyConfig{loadConfig(source)}; },
      py::arg("source") = py::none(),
      "The configuration: defaults (None), a YAML file's path or a dict of the same keys.");

  py::class_<ModelSet, std::shared_ptr<ModelSet>>(m, "ModelSet",
                                                  "Object models (docs/model_sets.md)")
      .def_property_readonly("name", &ModelSet::name)
      .def_property_readonly("classes",
                             [](const ModelSet& s) {
                               std::vector<std::string> names;
                               for (const auto& model : s.models()) names.push_back(model->name);
                               return names;
                             })
      .def("__len__", &ModelSet::size);
  m.def(
      "load_model_set",
      [](const std::string& name, const std::string& models_dir, const py::object& config) {
        return loadModels(name, models_dir, loadConfig(config));
      },
      py::arg("name") = "primitives", py::arg("models_dir") = "", py::arg("config") = py::none(),
      "A model set: 'primitives' (built in), a name of the package's table ('ycb_video', meshes "
      "from models_dir) or a model-set YAML file.");

  py::class_<PyEstimator>(m, "SceneEstimator", "GeoFusion's scene estimator (docs/estimator.md)")
      .def(py::init([](std::shared_ptr<ModelSet> models, const py::object& config) {
             const GeoFusionConfig c = py::isinstance<PyConfig>(config)
                                           ? config.cast<const PyConfig&>().config
                                           : loadConfig(config);
             return std::make_unique<PyEstimator>(std::move(models), c);
           }),
           py::arg("models"), py::arg("config") = py::none())
      .def("add_keyframe", &PyEstimator::addKeyframe, py::arg("depth"), py::arg("K"),
           py::arg("T_odom_cam"), py::arg("detections"), py::arg("stamp") = py::none(),
           "One keyframe: depth (float32 H x W, metres), K (3 x 3), the odometry camera pose "
           "(4 x 4 or [x, y, z, qx, qy, qz, qw]) and detections [(class, score, pose), ...]; "
           "returns the keyframe's result as a dict.")
      .def("finish", &PyEstimator::finish,
           "The final map (a last stage I and II), contacts, "
           "trajectory.")
      .def("objects", &PyEstimator::objects)
      .def("stability", &PyEstimator::stability,
           "The map so far under gravity on its support plane (Bullet, the configuration's "
           "physics settings): per object its motion and whether it is stable (docs/stability.md).")
      .def("scene_graph", &PyEstimator::sceneGraph,
           "The map so far as a plan: per object what supports it, what it supports, what it "
           "leans on and stands beside, whether it is stable and free to pick, and the removal "
           "order, top first (docs/scene_graph.md).")
      .def("bop_results", &PyEstimator::bopResults, py::arg("path") = py::none(),
           py::arg("scene_id") = 0,
           "Every keyframe's map objects in view as BOP results (CSV text, docs/results.md); "
           "written to path when given.")
      .def_property_readonly("trajectory", &PyEstimator::trajectory)
      .def_property_readonly("num_keyframes", &PyEstimator::numKeyframes)
      .def_property_readonly("method", &PyEstimator::method);

  m.def("consistency", &consistency, py::arg("models"), py::arg("class_name"), py::arg("T_cam_obj"),
        py::arg("depth"), py::arg("K"), py::arg("config") = py::none(),
        "The geometric consistency f_gc of a model at a pose against a depth image.");

  m.def("rectify", &rectifyImage, py::arg("image"), py::arg("K"), py::arg("D"),
        "A raw image of a camera with lens distortion D (camera_info's plumb_bob or "
        "rational_polynomial coefficients) made pinhole with the same K: depth (float32 H x W, "
        "nearest pixel), grey (uint8 H x W) or colour (uint8 H x W x 3), both bilinear.");

  py::class_<PyVisualOdometry>(m, "VisualOdometry",
                               "ORB RGB-D visual odometry "
                               "(docs/visual_odometry.md)")
      .def(py::init([](const py::object& K, const py::object& config) {
             return std::make_unique<PyVisualOdometry>(loadConfig(config), K);
           }),
           py::arg("K") = py::none(), py::arg("config") = py::none())
      .def("track", &PyVisualOdometry::track, py::arg("grey"), py::arg("depth"),
           py::arg("K") = py::none(), py::arg("stamp") = 0.0,
           "One frame: grey (uint8 H x W), registered depth (float32, metres).")
      .def("reset", &PyVisualOdometry::reset, py::arg("T_odom_cam") = py::none())
      .def_property_readonly("num_keyframes", &PyVisualOdometry::numKeyframes);
}

}  // namespace python
}  // namespace geofusion

PYBIND11_MODULE(core, m) {
  geofusion::python::bindModule(m);
}
