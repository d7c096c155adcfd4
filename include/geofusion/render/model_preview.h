// A picture of an object model with what GeoFusion made of it: the mesh rendered (OSMesa,
// textured when it has a texture, shaded by its depth) from two opposite corners, with its
// surface features drawn over it (plane outlines and normals, cylinder sides, edges) and its
// symmetry axes. make_model_set writes one per object so a user can check them.
#pragma once

#include "geofusion/model/object_model.h"

#include <string>
#include <vector>

namespace geofusion {

/// Writes the preview of `mesh` with `features` and `symmetry` (its axes through
/// `symmetry_centre`) as a PNG at `path`; `caption`
/// lines are printed on it. False, with the reason, when it cannot render or write.
bool writeModelPreview(const TriangleMesh& mesh, const SurfaceFeatures& features,
                       const Symmetry& symmetry, const Eigen::Vector3d& symmetry_centre,
                       const std::vector<std::string>& caption, const std::string& path,
                       std::string* error);

}  // namespace geofusion
