#include "python_conversions.h"

#include "geofusion/common/lens.h"
#include "geofusion/common/pose_validation.h"
#include "geofusion/estimation/contacts.h"
#include "geofusion/estimation/depth_refinement.h"
#include "geofusion/estimation/optimization.h"
#include "geofusion/estimation/relocalisation.h"

#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <cstring>

namespace geofusion {
namespace python {
namespace {

template <typename T>
bool hasDtype(const py::array& a) {
  return a.dtype().is(py::dtype::of<T>());
}

// A 2-D array with contiguous rows (a C-contiguous array, or a row slice of one).
void requireImage(const py::array& a, const char* what, const char* dtype, bool dtype_ok) {
  if (!dtype_ok)
    throw py::type_error(std::string(what) + ": expected dtype " + dtype + ", got " + shape(a));
  if (a.ndim() != 2)
    throw py::value_error(std::string(what) + ": expected a 2-D array (H x W), got " + shape(a));
  if (a.shape(0) < 1 || a.shape(1) < 1)
    throw py::value_error(std::string(what) + ": the image is empty, " + shape(a));
}

// The value as a C-contiguous array of doubles (any numeric array or nested list converts).
py::array_t<double> doubles(const py::handle& value, const std::string& what) {
  auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(value);
  if (!a) {
    PyErr_Clear();
    throw py::type_error(what + ": expected numbers (an array or a list)");
  }
  return a;
}

double scoreOf(const py::handle& value, const std::string& what) {
  try {
    return value.cast<double>();
  } catch (const py::cast_error&) {
    throw py::type_error(what + ": the score is not a number");
  }
}

RawDetection rawDetection(const py::handle& item, const std::string& what) {
  py::object cls, score, T;
  if (py::isinstance<py::dict>(item)) {
    const py::dict d = py::reinterpret_borrow<py::dict>(item);
    for (const char* key : {"class", "score", "pose"})
      if (!d.contains(key)) throw py::value_error(what + ": no '" + key + "'");
    cls = d["class"], score = d["score"], T = d["pose"];
  } else {
    const py::sequence s = py::reinterpret_borrow<py::sequence>(item);
    if (!py::isinstance<py::sequence>(item) || py::isinstance<py::str>(item) || s.size() != 3)
      throw py::type_error(what + ": expected (class, score, pose) or a dict of them");
    cls = s[0], score = s[1], T = s[2];
  }
  if (!py::isinstance<py::str>(cls)) throw py::type_error(what + ": the class is not a string");
  RawDetection raw;
  raw.class_name = cls.cast<std::string>();
  raw.score = scoreOf(score, what);
  const py::array_t<double> a = doubles(T, what + " pose");
  if (a.ndim() == 1 && a.shape(0) == 7) {  // exactly as the ROS layer reads a Pose
    const double* p = a.data();
    raw.position_cam = Eigen::Vector3d(p[0], p[1], p[2]);
    raw.orientation_cam = Eigen::Quaterniond(p[6], p[3], p[4], p[5]);
  } else {
    const Eigen::Isometry3d Tm = pose(T, what + " pose");
    raw.position_cam = Tm.translation();
    raw.orientation_cam = Eigen::Quaterniond(Tm.linear());
  }
  return raw;
}

}  // namespace

std::string shape(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
  return s + (a.ndim() == 1 ? ",) " : ") ") + std::string(py::str(a.dtype()));
}

DepthInput depthInput(const py::array& array, const char* what) {
  requireImage(array, what, "float32 (metres)", hasDtype<float>(array));
  DepthInput in;
  in.keep = py::array_t<float, py::array::c_style>::ensure(array);  // no copy when contiguous
  const auto* data = static_cast<const float*>(in.keep.data());
  const std::size_t n = static_cast<std::size_t>(array.shape(0) * array.shape(1));
  bool clean = true;
  for (std::size_t i = 0; i < n && clean; ++i) clean = std::isfinite(data[i]) && data[i] >= 0.f;
  if (!clean) {
    py::array_t<float> copy({array.shape(0), array.shape(1)});
    float* out = copy.mutable_data();
    for (std::size_t i = 0; i < n; ++i)
      out[i] = std::isfinite(data[i]) && data[i] > 0.f ? data[i] : 0.f;
    in.keep = copy;
  }
  in.view = DepthImageView{static_cast<const float*>(in.keep.data()),
                           static_cast<int>(array.shape(1)), static_cast<int>(array.shape(0))};
  return in;
}

GreyInput greyInput(const py::array& array, const char* what) {
  requireImage(array, what, "uint8", hasDtype<std::uint8_t>(array));
  GreyInput in;
  in.keep = array;  // read in place when its rows are contiguous (a C array or a row slice)
  if (array.strides(1) != 1 || array.strides(0) < array.shape(1))
    in.keep = py::array_t<std::uint8_t, py::array::c_style>::ensure(array);
  in.view = GrayImageView{static_cast<const std::uint8_t*>(in.keep.data()),
                          static_cast<int>(array.shape(1)), static_cast<int>(array.shape(0)),
                          static_cast<int>(in.keep.strides(0))};
  return in;
}

// A raw image made pinhole with the same K (common/lens.h): depth float32 H x W from the nearest
// pixel, grey uint8 H x W and colour uint8 H x W x 3 bilinear. A new array, the caller's as it was.
py::array rectifyImage(const py::array& image, const py::handle& K, const py::handle& D) {
  const py::array_t<double> d = doubles(D, "D");
  if (d.ndim() != 1)
    throw py::value_error(
        "D: expected 5 (plumb_bob), 8 (rational_polynomial) or 4 coefficients, got " + shape(d));
  const LensDistortion lens{std::vector<double>(d.data(), d.data() + d.shape(0))};
  if (!lens.problem().empty()) throw py::value_error("D: " + lens.problem());
  const bool depth = image.ndim() == 2 && hasDtype<float>(image);
  const bool grey = image.ndim() == 2 && hasDtype<std::uint8_t>(image);
  const bool colour = image.ndim() == 3 && image.shape(2) == 3 && hasDtype<std::uint8_t>(image);
  if (!depth && !grey && !colour)
    throw py::value_error(
        "image: expected float32 H x W depth, uint8 H x W grey or uint8 H x W x 3 colour, got " +
        shape(image));
  const PinholeIntrinsics intr =
      intrinsics(K, static_cast<int>(image.shape(1)), static_cast<int>(image.shape(0)));
  const std::string cannot = "image: " + shape(image) + " too large to rectify";
  static LensWarp warp;  // its maps kept for the next image of the same camera (under the GIL)
  std::vector<py::ssize_t> dims(image.shape(), image.shape() + image.ndim());
  if (depth) {
    const auto in = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(image);
    std::vector<float> v(in.data(), in.data() + in.size());
    if (!warp.rectifyDepth(intr, lens, &v)) throw py::value_error(cannot);
    py::array_t<float> out(dims);
    std::copy(v.begin(), v.end(), out.mutable_data());
    return std::move(out);
  }
  const auto in =
      py::array_t<std::uint8_t, py::array::c_style | py::array::forcecast>::ensure(image);
  std::vector<std::uint8_t> v(in.data(), in.data() + in.size());
  if (!(grey ? warp.rectifyGrey(intr, lens, &v) : warp.rectifyRgb(intr, lens, &v)))
    throw py::value_error(cannot);
  py::array_t<std::uint8_t> out(dims);
  std::copy(v.begin(), v.end(), out.mutable_data());
  return std::move(out);
}

PinholeIntrinsics intrinsics(const py::handle& K, int width, int height) {
  const py::array_t<double> a = doubles(K, "K");
  if (a.ndim() != 2 || a.shape(0) != 3 || a.shape(1) != 3)
    throw py::value_error("K: expected a 3 x 3 camera matrix, got " + shape(a));
  const auto k = a.unchecked<2>();
  PinholeIntrinsics intr;
  intr.width = width;
  intr.height = height;
  intr.fx = k(0, 0), intr.fy = k(1, 1), intr.cx = k(0, 2), intr.cy = k(1, 2);
  if (!(std::isfinite(intr.fx) && std::isfinite(intr.fy) && std::isfinite(intr.cx) &&
        std::isfinite(intr.cy)) ||
      !intr.valid())
    throw py::value_error("K: focal lengths must be positive and every value finite");
  return intr;
}

Eigen::Isometry3d pose(const py::handle& value, const std::string& what) {
  const py::array_t<double> a = doubles(value, what);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  if (a.ndim() == 1 && a.shape(0) == 7) {
    const double* p = a.data();
    const Eigen::Quaterniond q(p[6], p[3], p[4], p[5]);
    const PoseStatus status = checkPose(Eigen::Vector3d(p[0], p[1], p[2]), q);
    if (status != PoseStatus::kValid) throw py::value_error(what + ": " + toString(status));
    return Eigen::Isometry3d(Eigen::Translation3d(p[0], p[1], p[2]) * q);  // as tf2_eigen does
  }
  if (a.ndim() != 2 || a.shape(0) != 4 || a.shape(1) != 4)
    throw py::value_error(what + ": expected a 4 x 4 matrix or [x, y, z, qx, qy, qz, qw], got " +
                          shape(a));
  const auto m = a.unchecked<2>();
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) T.matrix()(r, c) = m(r, c);
  if (!T.matrix().allFinite()) throw py::value_error(what + ": the pose is not finite (NaN/inf)");
  // Rotations written with a few digits (BOP results files) are accepted within the ROS layer's
  // quaternion tolerance and made exactly orthonormal (the nearest rotation, by SVD).
  const Eigen::Matrix3d R = T.linear();
  const double off = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if ((T.matrix().row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-9 ||
      off > kUnitQuaternionTolerance || R.determinant() < 0)
    throw py::value_error(what +
                          ": not a rigid transform (rotation not orthonormal or last row "
                          "not 0 0 0 1)");
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(R, Eigen::ComputeFullU | Eigen::ComputeFullV);
  T.linear() = svd.matrixU() * svd.matrixV().transpose();
  T.matrix().row(3) << 0, 0, 0, 1;
  return T;
}

std::vector<RawDetection> rawDetections(const py::handle& detections, const ModelSet& models,
                                        const FrameByFrame& checker) {
  if (!py::isinstance<py::sequence>(detections) && !py::isinstance<py::iterable>(detections))
    throw py::type_error("detections: expected a list of (class, score, pose)");
  std::vector<RawDetection> out;
  for (const py::handle& item : detections) {
    const std::string what = "detections[" + std::to_string(out.size()) + "]";
    RawDetection raw = rawDetection(item, what);
    if (const ObjectModel* model = models.find(raw.class_name)) raw.class_id = model->id;
    ObjectMeasurement checked;
    SkipReason reason;
    if (!checker.check(raw, &checked, &reason)) {
      // Input errors raise; what the configuration filters (low score, range) is reported.
      if (reason == SkipReason::kUnknownClass)
        throw py::value_error(what + ": " + unknownClass(raw.class_name, models));
      if (reason != SkipReason::kLowScore && reason != SkipReason::kOutOfRange)
        throw py::value_error(what + " (" + raw.class_name + "): " + toString(reason));
    }
    out.push_back(std::move(raw));
  }
  return out;
}

std::string unknownClass(const std::string& name, const ModelSet& models) {
  std::string known;
  for (const auto& m : models.models()) known += (known.empty() ? "" : ", ") + m->name;
  return "unknown class '" + name + "' (model set '" + models.name() + "' has " + known + ")";
}

py::array matrix(const Eigen::MatrixXd& m) {
  py::array_t<double> a({m.rows(), m.cols()});
  auto out = a.mutable_unchecked<2>();
  for (Eigen::Index r = 0; r < m.rows(); ++r)
    for (Eigen::Index c = 0; c < m.cols(); ++c) out(r, c) = m(r, c);
  return a;
}

py::array vector(const Eigen::VectorXd& v) {
  py::array_t<double> a(v.size());
  std::memcpy(a.mutable_data(), v.data(), sizeof(double) * static_cast<std::size_t>(v.size()));
  return a;
}

py::array poses(const std::vector<Eigen::Isometry3d>& poses) {
  py::array_t<double> a({static_cast<py::ssize_t>(poses.size()), py::ssize_t{4}, py::ssize_t{4}});
  auto out = a.mutable_unchecked<3>();
  for (std::size_t i = 0; i < poses.size(); ++i)
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) out(i, r, c) = poses[i].matrix()(r, c);
  return a;
}

py::list objectList(const std::vector<ObjectEstimate>& objects) {
  py::list out;
  for (const ObjectEstimate& o : objects) {
    out.append(py::dict(
        py::arg("id") = o.id, py::arg("class") = o.model ? o.model->name : std::string(),
        py::arg("pose") = matrix(o.T_map_obj.matrix()), py::arg("existence") = o.existence,
        py::arg("false_positive") = o.false_positive, py::arg("consistency") = o.best_consistency,
        py::arg("measurements") = o.measurements, py::arg("first_keyframe") = o.first_keyframe,
        py::arg("last_keyframe") = o.last_keyframe, py::arg("confirmed") = o.confirmed,
        py::arg("covariance") = matrix(o.covariance)));
  }
  return out;
}

namespace {

py::list detectionList(const std::vector<DetectionReport>& reports) {
  py::list out;
  for (const DetectionReport& d : reports) {
    out.append(py::dict(py::arg("class") = d.class_name, py::arg("score") = d.detector_score,
                        py::arg("decision") = toString(d.decision), py::arg("object") = d.object,
                        py::arg("refinement") = toString(d.refinement),
                        py::arg("ray_offset_m") = d.ray_offset_m,
                        py::arg("correction_translation_m") = d.correction_translation_m,
                        py::arg("correction_rotation_rad") = d.correction_rotation_rad,
                        py::arg("consistency") = d.consistency, py::arg("r_in") = d.r_in,
                        py::arg("r_out") = d.r_out, py::arg("r_occ") = d.r_occ,
                        py::arg("T_cam_in") = matrix(d.T_cam_in.matrix()),
                        py::arg("T_cam_out") = matrix(d.T_cam_out.matrix())));
  }
  return out;
}

py::list contactList(const std::vector<FeatureContact>& contacts,
                     const std::vector<ObjectEstimate>& objects) {
  auto id = [&](int index) {
    return index >= 0 && index < static_cast<int>(objects.size())
               ? objects[static_cast<std::size_t>(index)].id
               : -1;
  };
  py::list out;
  for (const FeatureContact& c : contacts) {
    out.append(py::dict(
        py::arg("a") = id(c.object_a), py::arg("b") = id(c.object_b),
        py::arg("kind") = toString(c.kind), py::arg("type") = shortName(c.type),
        py::arg("normal") = vector(c.normal), py::arg("distance_residual") = c.distance_residual,
        py::arg("direction_residual") = c.direction_residual, py::arg("held") = c.held));
  }
  return out;
}

py::dict stageDict(const StageReport& s) {
  return py::dict(py::arg("status") = toString(s.status), py::arg("iterations") = s.iterations,
                  py::arg("initial_cost") = s.initial_cost, py::arg("final_cost") = s.final_cost);
}

py::dict relocalisationDict(const Relocalisation& r) {
  return py::dict(py::arg("decision") = toString(r.decision), py::arg("searched") = r.tried,
                  py::arg("applied") = r.applied, py::arg("detections") = r.detections,
                  py::arg("support_before") = r.inliers_before,
                  py::arg("support") = r.inliers_after, py::arg("runner_up") = r.runner_up,
                  py::arg("mahalanobis_sq") = r.mahalanobis_sq,
                  py::arg("correction") = matrix(r.T_correction.matrix()));
}

}  // namespace

py::dict keyframeDict(const KeyframeResult& r) {
  py::list removals;
  for (const Removal& x : r.removals)
    removals.append(py::dict(py::arg("id") = x.id, py::arg("reason") = toString(x.reason),
                             py::arg("into") = x.into));
  const StageTimings& t = r.timings;
  return py::dict(
      py::arg("keyframe") = r.keyframe, py::arg("stamp") = r.stamp_s,
      py::arg("T_map_cam") = matrix(r.T_map_cam.matrix()),
      py::arg("objects") = objectList(r.objects), py::arg("tentative") = objectList(r.tentative),
      py::arg("detections") = detectionList(r.detections), py::arg("removals") = removals,
      py::arg("contacts") = contactList(r.contacts, r.objects),
      py::arg("skipped_detections") = static_cast<std::size_t>(r.skipped_detections),
      py::arg("detection_warning") = r.detection_warning,
      py::arg("relocalisation") = relocalisationDict(r.relocalisation),
      py::arg("stage_one") = stageDict(r.stage_one), py::arg("stage_two") = stageDict(r.stage_two),
      py::arg("timings_ms") =
          py::dict(py::arg("consistency") = t.consistency_ms,
                   py::arg("association") = t.association_ms, py::arg("lifecycle") = t.lifecycle_ms,
                   py::arg("stage_one") = t.stage_one_ms, py::arg("relations") = t.relations_ms,
                   py::arg("stage_two") = t.stage_two_ms, py::arg("total") = t.total_ms));
}

}  // namespace python
}  // namespace geofusion
