// The ground truth of a package recording as a BOP dataset folder (issue 51), so that BOP's own
// toolkit (bop_toolkit's eval_calc_errors.py / eval_calc_scores.py) can score the BOP results
// the package writes (estimation/bop_results.h) for the same run. Layout (bop_toolkit's
// dataset_params for a dataset <root>, split `test`):
//   <root>/models_eval/obj_<obj_id>.ply     every class's evaluation points, mm, BOP's frame
//   <root>/models_eval/models_info.json     diameter, box, appearance symmetries (mm)
//   <root>/test/<scene_id>/scene_camera.json, scene_gt.json, scene_gt_info.json
//   <root>/test_targets_bop19.json          objects at least 10 % visible, per image
//   <root>/geofusion_ids.json               the mapping: scene name, image size, keyframe and
//                                           stamp of each image, class of each obj_id, object
//                                           index of each gt
// Images are the run's keyframes (im_id = BopIds::imageOf(keyframe), as in the results CSV), the
// ground truth's keyframe of the same stamp (within stamp_tolerance_s). Several scenes share one
// folder: each call replaces its scene's entries and keeps the others'.
#pragma once

#include "geofusion/estimation/bop_results.h"
#include "geofusion/simulation/dataset.h"

#include <string>

namespace geofusion {

/// BOP19's targets: objects at least this visible (bop_toolkit's visib_gt_min for the
/// test_targets_bop19.json of its datasets): BOP's definition, not a setting.
constexpr double kBopTargetMinVisible = 0.1;

/// Writes (or updates) the BOP dataset folder `root` with the ground truth of `gt` at the
/// keyframes of `results` and the models of every class of `models` (the ones the results may
/// name); false with `error` when a file cannot be written, two classes share an obj_id or no
/// keyframe matches. Every file is written atomically.
bool writeBopDataset(const std::string& root, const ModelSet& models, const GroundTruth& gt,
                     const RunResults& results, const BopIds& ids, double stamp_tolerance_s,
                     std::string* error);

}  // namespace geofusion
