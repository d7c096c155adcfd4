#include "geofusion/estimation/object_lifecycle.h"

#include "geofusion/common/enum_names.h"
#include "geofusion/model/collision.h"

#include <algorithm>
#include <utility>

namespace geofusion {
namespace {

const std::pair<RemovalReason, const char*> kRemovalNames[] = {
    {RemovalReason::kCandidateTimeout, "candidate_timeout"},
    {RemovalReason::kSeenAbsent, "seen_absent"},
    {RemovalReason::kMerged, "merged"},
};

}  // namespace

const char* toString(RemovalReason reason) {
  return nameIn(kRemovalNames, reason);
}

bool parseRemovalReason(const std::string& name, RemovalReason* reason) {
  return parseIn(kRemovalNames, name, reason);
}

double ObjectTrack::depthEvidence() const {
  double sum = prior_evidence;
  for (const TrackObservation& o : observations) sum += o.consistency;
  return sum;
}

ObjectTrack makeTrack(int id, const std::shared_ptr<const ObjectModel>& model,
                      const Eigen::Isometry3d& T_map_obj, int keyframe) {
  ObjectTrack tr;
  tr.id = id;
  tr.model = model;
  tr.T_stage_one = tr.T_refined = T_map_obj;
  tr.first_keyframe = keyframe;
  const Eigen::AlignedBox3f box = boxOf(*tr.model);
  tr.box_centre = box.center().cast<double>();
  tr.box_half = (0.5f * box.diagonal()).cast<double>();
  return tr;
}

void confirmOrTimeOut(std::vector<ObjectTrack>* tracks, const std::vector<int>& touched,
                      int keyframe, const AssociationConfig& config,
                      std::vector<Removal>* removed) {
  std::vector<ObjectTrack> kept;
  for (ObjectTrack& tr : *tracks) {
    if (std::find(touched.begin(), touched.end(), tr.id) != touched.end()) {
      const double f = falsePositiveScore(tr.best_consistency, tr.measurementCount());
      tr.confirmed = f <= config.eps_fp;
    }
    // A candidate above eps_fp is not in the map; unseen for long, it is dropped.
    if (!tr.confirmed && keyframe - tr.last_keyframe > config.candidate_timeout_keyframes)
      removed->push_back({tr.id, RemovalReason::kCandidateTimeout});
    else
      kept.push_back(std::move(tr));
  }
  *tracks = std::move(kept);
}

void removeSeenAbsent(std::vector<ObjectTrack>* tracks, const std::vector<int>& measured,
                      int keyframe, const LifecycleConfig& config, const FreeSpaceLook& look,
                      std::vector<Removal>* removed) {
  std::vector<ObjectTrack>& all = *tracks;
  // The confirmed objects no detection measured, least recently checked first; at most
  // max_checks_per_keyframe of them rendered (an object out of view costs no render).
  std::vector<std::size_t> unmeasured;
  for (std::size_t j = 0; j < all.size(); ++j) {
    ObjectTrack& tr = all[j];
    if (std::find(measured.begin(), measured.end(), tr.id) != measured.end())
      tr.free_space_keyframes = 0;
    else if (tr.confirmed)
      unmeasured.push_back(j);
  }
  std::stable_sort(unmeasured.begin(), unmeasured.end(), [&](std::size_t a, std::size_t b) {
    return all[a].last_checked < all[b].last_checked;
  });
  int checks = 0;
  for (std::size_t j : unmeasured) {
    if (config.max_checks_per_keyframe > 0 && checks >= config.max_checks_per_keyframe) break;
    ObjectTrack& tr = all[j];
    const ConsistencyResult seen = look(tr);
    if (seen.rendered == 0) continue;  // out of view
    ++checks;
    tr.last_checked = keyframe;
    if (seen.determined && seen.r_occ <= config.max_occlusion_ratio) {
      if (seen.r_out >= config.free_space_outlier_ratio)
        ++tr.free_space_keyframes;
      else if (seen.r_in >= config.seen_inlier_ratio)
        tr.free_space_keyframes = 0;
    }
  }
  std::vector<ObjectTrack> kept;
  for (ObjectTrack& tr : all) {
    if (tr.free_space_keyframes >= std::max(1, config.free_space_keyframes))
      removed->push_back({tr.id, RemovalReason::kSeenAbsent});
    else
      kept.push_back(std::move(tr));
  }
  all = std::move(kept);
}

// The paper's overlap test (issue 32): boxes overlapping by more than merge_ratio and hulls
// interpenetrating by more than neighbours in clutter can. Thin objects (markers, scissors)
// cannot interpenetrate by much: the bound scales down with the thinner object's smallest extent.
// Objects of two classes (a real object differs from its mesh by millimetres, so real neighbours
// overlap a little) must interpenetrate by merge_cross_class_fraction of that extent: a
// look-alike reported in place of the object.
bool mappedTwice(const ObjectTrack& a, const Eigen::Isometry3d& T_a, const ObjectTrack& b,
                 const Eigen::Isometry3d& T_b, const AssociationConfig& config,
                 HullCollider* collider) {
  Eigen::Isometry3d Ta = T_a, Tb = T_b;
  Ta.translation() += Ta.linear() * a.box_centre;
  Tb.translation() += Tb.linear() * b.box_centre;
  if (boxCollisionRatio(Ta, a.box_half, Tb, b.box_half) <= config.merge_ratio) return false;
  const double thinnest = 2.0 * std::min(a.box_half.minCoeff(), b.box_half.minCoeff());
  double needed = std::min(config.merge_min_penetration_m, config.merge_thin_fraction * thinnest);
  if (a.model->name != b.model->name) {
    needed = std::max(needed, config.merge_cross_class_fraction * thinnest);
    // Seen together, each where the depth agreed, again and again: two objects, however thin one
    // is; only one inside the other is a phantom (issue 45: scissors beside a pudding box,
    // merged away after 66 keyframes when a pose update tipped the box 5 mm into them).
    if (config.merge_co_measured_keyframes > 0 &&
        coMeasuredKeyframes(a, b) >= config.merge_co_measured_keyframes)
      needed = std::max(needed, config.merge_min_penetration_m);
  }
  // Measured on the shapes (their convex parts), not on one hull: a hull spans the air inside a
  // banana's curve or a mug's handle, where a neighbour can lie (issue 45).
  const double depth = config.merge_on_convex_parts
                           ? collider->partsPenetration(a.model, T_a, b.model, T_b)
                           : collider->penetration(a.model, T_a, b.model, T_b);
  return depth >= needed;
}

void changeClass(ObjectTrack* track, const std::shared_ptr<const ObjectModel>& model) {
  track->model = model;
  track->appearance_model.reset();
  const Eigen::AlignedBox3f box = boxOf(*model);
  track->box_centre = box.center().cast<double>();
  track->box_half = (0.5f * box.diagonal()).cast<double>();
  ++track->class_changes;
}

bool challengerWins(ObjectTrack* track, const std::string& other, double f_other, double f_held,
                    double vote_weight) {
  ObjectTrack::ClassEvidence& held = track->class_evidence[track->model->name];
  ObjectTrack::ClassEvidence& challenger = track->class_evidence[other];
  held.consistency += std::max(0.0, f_held);
  challenger.consistency += std::max(0.0, f_other);
  ++challenger.votes;
  return challenger.consistency + vote_weight * challenger.votes >
         held.consistency + vote_weight * held.votes;
}

int coMeasuredKeyframes(const ObjectTrack& a, const ObjectTrack& b) {
  int n = 0;
  for (const TrackObservation& x : a.observations) {
    if (x.consistency <= 0.0) continue;
    n += std::any_of(b.observations.begin(), b.observations.end(), [&](const TrackObservation& y) {
      return y.keyframe == x.keyframe && y.consistency > 0.0;
    });
  }
  return n;
}

void absorb(ObjectTrack* dropped_track, ObjectTrack* kept) {
  const ObjectTrack& dropped = *dropped_track;
  for (const TrackObservation& o : dropped.observations) {
    const bool clash =
        std::any_of(kept->observations.begin(), kept->observations.end(),
                    [&](const TrackObservation& x) { return x.keyframe == o.keyframe; });
    // A measurement the depth refuted where it put the object (f_gc 0: far off along the ray,
    // past the refinement's guard) does not move an object the depth supports (issue 45: on
    // bench_rgb_01 such measurements dragged a sugar box onto its neighbour until they merged).
    const bool refuted = o.consistency <= 0.0 && kept->best_consistency > 0.0;
    if (!clash && !refuted) kept->observations.push_back(o);
  }
  std::sort(
      kept->observations.begin(), kept->observations.end(),
      [](const TrackObservation& x, const TrackObservation& y) { return x.keyframe < y.keyframe; });
  kept->prior.add(dropped.prior, kept->symmetryModel(), kept->T_stage_one.linear());
  kept->folded = kept->prior;  // folded again from the merged observations
  for (TrackObservation& o : kept->observations) o.folded = false;
  kept->best_consistency = std::max(kept->best_consistency, dropped.best_consistency);
  kept->prior_measurements += dropped.prior_measurements;
  kept->prior_evidence += dropped.prior_evidence;
  // The object keeps the identity it had first (a resumed map's id, the id a planner or the
  // markers already know): the track that stays may be the younger duplicate.
  const bool dropped_older =
      dropped.first_keyframe < kept->first_keyframe ||
      (dropped.first_keyframe == kept->first_keyframe && dropped.id < kept->id);
  if (dropped_older) std::swap(kept->id, dropped_track->id);
  kept->first_keyframe = std::min(kept->first_keyframe, dropped.first_keyframe);
  kept->last_keyframe = std::max(kept->last_keyframe, dropped.last_keyframe);
}

void mergeOverlapping(std::vector<ObjectTrack>* tracks, const AssociationConfig& config,
                      HullCollider* collider, const TrackPose& pose,
                      const std::function<bool(const ObjectTrack&)>& recently_seen,
                      std::vector<Removal>* removed) {
  std::vector<ObjectTrack>& all = *tracks;
  bool merged = true;
  while (merged) {
    merged = false;
    for (std::size_t a = 0; a < all.size() && !merged; ++a) {
      for (std::size_t b = a + 1; b < all.size() && !merged; ++b) {
        const ObjectTrack &A = all[a], &B = all[b];
        if (!recently_seen(A) && !recently_seen(B)) continue;  // checked when last seen
        if (!mappedTwice(A, pose(A), B, pose(B), config, collider)) continue;
        // Two of one class: the one with the higher false-positive score goes into the other (the
        // paper). Two classes (a look-alike reported for a stretch, a persistent phantom beside a
        // real object): the one the depth supported more over all its measurements stays.
        const bool same_class = A.model->name == B.model->name;
        const bool keep_a = same_class
                                ? falsePositiveScore(A.best_consistency, A.measurementCount()) <=
                                      falsePositiveScore(B.best_consistency, B.measurementCount())
                                : A.depthEvidence() >= B.depthEvidence();
        const std::size_t keep = keep_a ? a : b, drop = keep_a ? b : a;
        if (same_class) absorb(&all[drop], &all[keep]);
        removed->push_back({all[drop].id, RemovalReason::kMerged, all[keep].id});
        all.erase(all.begin() + static_cast<std::ptrdiff_t>(drop));
        merged = true;
      }
    }
  }
}

}  // namespace geofusion
