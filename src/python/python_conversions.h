// NumPy and Python values to the core's types and back, with the checks that turn bad input
// into Python exceptions (TypeError for a wrong type or dtype, ValueError for a wrong shape or
// value). geofusion.core's bindings only (src/python).
#pragma once

#include "geofusion/common/camera.h"
#include "geofusion/common/images.h"
#include "geofusion/common/measurement.h"
#include "geofusion/estimation/frame_by_frame.h"
#include "geofusion/estimation/scene_estimator.h"
#include "geofusion/model/object_model.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <string>
#include <vector>

// pybind11 2.4 (Ubuntu 20.04) names the module class `module`; 2.6 renamed it `module_`.
#if PYBIND11_VERSION_MAJOR == 2 && PYBIND11_VERSION_MINOR < 6
namespace pybind11 {
using module_ = module;
}  // namespace pybind11
#endif

namespace geofusion {
namespace python {

namespace py = pybind11;

/// A depth image read in place from NumPy (float32, 2-D, C-contiguous, metres); an image with
/// non-finite or negative values is copied once with those set to 0 (no depth), as the ROS
/// layer's conversion does. `keep` holds the array (or the copy) alive.
struct DepthInput {
  DepthImageView view;
  py::array keep;
};
DepthInput depthInput(const py::array& array, const char* what);

/// An 8-bit grey image read in place (uint8, 2-D, rows contiguous).
struct GreyInput {
  GrayImageView view;
  py::array keep;
};
GreyInput greyInput(const py::array& array, const char* what);

/// "(480, 640) float32"
std::string shape(const py::array& array);

/// A raw image of a camera with lens distortion D made pinhole with the same K (common/lens.h):
/// depth float32 H x W from the nearest pixel, grey uint8 H x W and colour uint8 H x W x 3
/// bilinear. A new array; the caller's stays as it was.
py::array rectifyImage(const py::array& image, const py::handle& K, const py::handle& D);

/// Intrinsics of a 3 x 3 camera matrix for an image of width x height.
PinholeIntrinsics intrinsics(const py::handle& K, int width, int height);

/// A rigid pose: a 4 x 4 matrix (rotation orthonormal, last row 0 0 0 1) or
/// [x, y, z, qx, qy, qz, qw] (ROS order, unit quaternion).
Eigen::Isometry3d pose(const py::handle& value, const std::string& what);

/// The detections [(class, score, pose), ...] (or dicts with keys class, score, pose) as the
/// ROS layer reads them; a detection that is not usable input (non-finite or improper pose,
/// empty or unknown class, score outside [0, 1]) raises ValueError naming it and the reason.
std::vector<RawDetection> rawDetections(const py::handle& detections, const ModelSet& models,
                                        const FrameByFrame& checker);

std::string unknownClass(const std::string& name, const ModelSet& models);

py::array matrix(const Eigen::MatrixXd& m);
py::array vector(const Eigen::VectorXd& v);
/// N x 4 x 4
py::array poses(const std::vector<Eigen::Isometry3d>& poses);

py::list objectList(const std::vector<ObjectEstimate>& objects);
/// A keyframe's (or the final) result as plain Python: objects, detections with their decisions,
/// removals, contacts (by object id, -1 the support plane), stages, timings, relocalisation.
py::dict keyframeDict(const KeyframeResult& result);

}  // namespace python
}  // namespace geofusion
