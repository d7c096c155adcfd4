// Objects kept and removed on evidence (issue 20), on a rendered tabletop with the benchmark's
// depth noise: a mapped object that is no longer detected but still seen stays; taken away (free
// space where it was), it leaves the map within a few keyframes; moved, it is mapped where it now
// is and not where it was. Its contacts are one per pair and stable from keyframe to keyframe.
#include "geofusion/estimation/object_lifecycle.h"
#include "geofusion/estimation/scene_estimator.h"
#include "geofusion/model/collision.h"
#include "geofusion/model/mesh.h"
#include "geofusion/model/object_model.h"

#include "table_scene.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <tuple>
#include <vector>

namespace geofusion {
namespace {

using test::TableScene;

class ObjectLifecycleTest : public ::testing::Test {
 protected:
  ObjectLifecycleTest() : models(ModelSet::builtinPrimitives()), scene(models) {
    box = scene.place("003_cracker_box", -0.12, 0.06, 0.3);
    brick = scene.place("061_foam_brick", 0.12, -0.04, -0.2);
    can = scene.place("005_tomato_soup_can", 0.02, 0.14);
    scene.renderObserved();
    estimator = std::make_unique<SceneEstimator>(models, EstimatorConfig(), test::sharedRenderer());
  }

  // One keyframe from the fixed camera, the listed objects detected at their true poses.
  KeyframeResult step(const std::vector<int>& detected) {
    return estimator->addKeyframe(scene.keyframe(t++, detected));
  }

  // The map has an object of object i's class within 2 cm of `T_world` (the map frame is the
  // world: the odometry is the true camera).
  static bool mappedAt(const KeyframeResult& r, const std::string& name,
                       const Eigen::Isometry3d& T_world) {
    for (const ObjectEstimate& o : r.objects)
      if (o.model->name == name &&
          (o.T_map_obj.translation() - T_world.translation()).norm() < 0.02)
        return true;
    return false;
  }
  bool mapped(const KeyframeResult& r, int i) const {
    return mappedAt(r, scene.object(i).model->name, scene.object(i).T_world_obj);
  }

  ModelSet models;
  TableScene scene;
  int box = -1, brick = -1, can = -1;
  std::unique_ptr<SceneEstimator> estimator;
  int t = 0;
};

TEST_F(ObjectLifecycleTest, AnObjectSeenButNotDetectedStays) {
  KeyframeResult r;
  for (int k = 0; k < 5; ++k) r = step({box, brick, can});
  ASSERT_TRUE(mapped(r, box) && mapped(r, brick) && mapped(r, can));
  // The detector stops reporting the brick for 50 keyframes; the depth still shows it.
  for (int k = 0; k < 50; ++k) {
    r = step({box, can});
    ASSERT_TRUE(mapped(r, brick)) << "keyframe " << k;
  }
}

TEST_F(ObjectLifecycleTest, AnObjectTakenAwayLeavesTheMapWithinFiveKeyframes) {
  KeyframeResult r;
  for (int k = 0; k < 5; ++k) r = step({box, brick, can});
  ASSERT_TRUE(mapped(r, brick));
  scene.setHidden(brick, true);  // picked up: the table shows where it stood
  scene.renderObserved();
  int gone_after = -1;
  for (int k = 1; k <= 10 && gone_after < 0; ++k) {
    r = step({box, can});
    if (!mapped(r, brick)) gone_after = k;
  }
  EXPECT_GE(gone_after, 1);
  EXPECT_LE(gone_after, 5);
  EXPECT_TRUE(mapped(r, box) && mapped(r, can));  // the others stay
}

// Issue 45: a detector that keeps reporting the object a few centimetres off (a colour-only
// estimator's error, refuted by the depth at its pose as at the map's) is not evidence that it is
// gone; free space removes it once nothing of its class is reported near it. Here the brick is
// taken away while a brick is still reported 3 cm from where it stood.
TEST_F(ObjectLifecycleTest, AnObjectStillReportedNearbyIsNotRemovedByFreeSpace) {
  auto run = [&](double detected_nearby_m, int* gone_while_reported, int* gone_after) {
    EstimatorConfig config;
    config.lifecycle.detected_nearby_m = detected_nearby_m;
    estimator = std::make_unique<SceneEstimator>(models, config, test::sharedRenderer());
    scene.setHidden(brick, false);
    scene.renderObserved();
    KeyframeResult r;
    for (int k = 0; k < 5; ++k) r = step({box, brick, can});
    ASSERT_TRUE(mapped(r, brick));
    scene.setHidden(brick, true);
    scene.renderObserved();
    *gone_while_reported = *gone_after = -1;
    for (int k = 1; k <= 10; ++k) {
      Keyframe kf = scene.keyframe(t++, {box, can});
      ObjectMeasurement off;
      off.class_name = scene.object(brick).model->name;
      off.score = 0.9;
      off.T_cam_obj = scene.cameraPose(brick);
      off.T_cam_obj.translation() += Eigen::Vector3d(0.03, 0.0, 0.0);
      kf.detections.push_back(off);
      r = estimator->addKeyframe(kf);
      if (*gone_while_reported < 0 && !mapped(r, brick)) *gone_while_reported = k;
    }
    for (int k = 1; k <= 10 && *gone_after < 0; ++k) {
      r = step({box, can});
      if (!mapped(r, brick)) *gone_after = k;
    }
    EXPECT_TRUE(mapped(r, box) && mapped(r, can));
  };
  int gone_while_reported = -1, gone_after = -1;
  run(0.05, &gone_while_reported, &gone_after);
  EXPECT_EQ(gone_while_reported, -1) << "removed while a brick was reported 3 cm away";
  EXPECT_GE(gone_after, 1);
  EXPECT_LE(gone_after, 5);
  // Without the rule the reports do not keep it: gone within 5 keyframes as when nothing is seen.
  run(0.0, &gone_while_reported, &gone_after);
  EXPECT_GE(gone_while_reported, 1);
  EXPECT_LE(gone_while_reported, 5);
}

// Issue 22: the free-space checks are bounded a keyframe (the least recently checked first), so
// undetected objects cost a fixed number of renders; each still leaves, later.
TEST_F(ObjectLifecycleTest, FreeSpaceChecksAreBoundedAndTakeTurns) {
  EstimatorConfig config;
  config.lifecycle.max_checks_per_keyframe = 1;
  config.lifecycle.free_space_keyframes = 3;
  estimator = std::make_unique<SceneEstimator>(models, config, test::sharedRenderer());
  KeyframeResult r;
  for (int k = 0; k < 5; ++k) r = step({box, brick, can});
  ASSERT_TRUE(mapped(r, brick) && mapped(r, box));
  scene.setHidden(brick, true);  // two picked up at once
  scene.setHidden(box, true);
  scene.renderObserved();
  int brick_gone = -1, box_gone = -1;
  for (int k = 1; k <= 12; ++k) {
    r = step({can});
    if (brick_gone < 0 && !mapped(r, brick)) brick_gone = k;
    if (box_gone < 0 && !mapped(r, box)) box_gone = k;
  }
  // One check a keyframe, taking turns: each object is checked every other keyframe, so it needs
  // 2 x free_space_keyframes (3) keyframes at most; unbounded, both would go within 3.
  EXPECT_GE(brick_gone, 4);
  EXPECT_LE(brick_gone, 6);
  EXPECT_GE(box_gone, 4);
  EXPECT_LE(box_gone, 6);
  EXPECT_TRUE(mapped(r, can));
}

TEST_F(ObjectLifecycleTest, AMovedObjectIsMappedWhereItIsNotWhereItWas) {
  KeyframeResult r;
  for (int k = 0; k < 5; ++k) r = step({box, brick, can});
  const Eigen::Isometry3d old_pose = scene.object(brick).T_world_obj;
  Eigen::Isometry3d new_pose = old_pose;
  new_pose.translation() += Eigen::Vector3d(0.0, 0.15, 0.0);
  scene.move(brick, new_pose);
  scene.renderObserved();
  for (int k = 0; k < 6; ++k) r = step({box, brick, can});
  EXPECT_TRUE(mapped(r, brick));  // at its new pose
  EXPECT_FALSE(mappedAt(r, scene.object(brick).model->name, old_pose)) << "a ghost is left";
  int bricks = 0;
  for (const ObjectEstimate& o : r.objects) bricks += o.model->name == "061_foam_brick";
  EXPECT_EQ(bricks, 1);
}

// The same keyframe again and again: every object rests on the table, one contact each, never
// a repeat, and the same contacts at every keyframe.
TEST_F(ObjectLifecycleTest, RepeatedKeyframesNeverDuplicateAContact) {
  std::vector<std::tuple<int, int, ContactType>> first;
  for (int k = 0; k < 12; ++k) {
    const KeyframeResult r = step({box, brick, can});
    std::vector<std::tuple<int, int, ContactType>> keys;
    for (const FeatureContact& c : r.contacts) {
      const int a = c.object_a < 0 ? -1 : r.objects[static_cast<std::size_t>(c.object_a)].id;
      const int b = c.object_b < 0 ? -1 : r.objects[static_cast<std::size_t>(c.object_b)].id;
      keys.emplace_back(std::min(a, b), std::max(a, b), c.type);
    }
    std::sort(keys.begin(), keys.end());
    EXPECT_EQ(std::adjacent_find(keys.begin(), keys.end()), keys.end()) << "keyframe " << k;
    if (r.objects.size() < 3) continue;  // not all confirmed yet
    int on_table = 0;
    for (const FeatureContact& c : r.contacts) on_table += c.object_a == -1 && c.support();
    EXPECT_EQ(on_table, 3) << "keyframe " << k;
    if (first.empty()) first = keys;
    EXPECT_EQ(keys, first) << "keyframe " << k << ": the contacts changed";
  }
  EXPECT_FALSE(first.empty());
}

// Issue 32's second case: a real object differs from its mesh by millimetres, so at the true
// poses meshes overlap their neighbours: a pudding box lying flat with a gelatin box resting on
// it sunk 13 mm into it (their boxes overlap by 0.43 of the thinner one's height, past
// merge_ratio), and a can beside both, 10 mm into their sides. The overlap is contact, not
// duplication: all three stay, with their contacts. Merged as before (two classes merged at any
// interpenetration past merge_min_penetration_m) one of them goes.
TEST(ObjectOverlap, AMeshOverlappingItsNeighboursByMillimetresIsKept) {
  const ModelSet models = ModelSet::builtinPrimitives();
  TableScene scene(models);
  const int block = scene.place("008_pudding_box", 0.0, 0.05, 0.0);
  Eigen::Vector3f lo, hi;
  scene.object(block).model->mesh.bounds(&lo, &hi);
  const double block_top = scene.object(block).T_world_obj.translation().z() + hi.z();
  const double block_half_x = hi.x();
  const int can = scene.place("005_tomato_soup_can", block_half_x + 0.0335 - 0.010, 0.05);
  // The gelatin box's +x side flush with the pudding box's: both 10 mm into the can.
  const int pudding = scene.place("009_gelatin_box", 0.0, 0.05);
  scene.object(pudding).model->mesh.bounds(&lo, &hi);
  Eigen::Isometry3d on_top = scene.object(pudding).T_world_obj;
  on_top.translation().x() = block_half_x - hi.x();
  on_top.translation().z() = block_top - lo.z() - 0.013;
  scene.move(pudding, on_top);
  scene.renderObserved();
  auto run = [&](const EstimatorConfig& config, std::vector<Removal>* removals) {
    SceneEstimator estimator(models, config, test::sharedRenderer());
    KeyframeResult r;
    for (int t = 0; t < 12; ++t) {
      r = estimator.addKeyframe(scene.keyframe(t, {block, pudding, can}));
      removals->insert(removals->end(), r.removals.begin(), r.removals.end());
    }
    return r;
  };
  std::vector<Removal> removals;
  const KeyframeResult r = run(EstimatorConfig(), &removals);
  EXPECT_TRUE(removals.empty()) << removals.size() << " removals, the first "
                                << toString(removals.front().reason);
  ASSERT_EQ(r.objects.size(), 3u);
  auto index = [&](int i) {
    for (std::size_t k = 0; k < r.objects.size(); ++k)
      if (r.objects[k].model == scene.object(i).model) return static_cast<int>(k);
    return -2;
  };
  bool block_pudding = false;
  for (const FeatureContact& c : r.contacts) {
    const int lo = std::min(c.object_a, c.object_b), hi = std::max(c.object_a, c.object_b);
    block_pudding |= lo == std::min(index(block), index(pudding)) &&
                     hi == std::max(index(block), index(pudding));
  }
  EXPECT_TRUE(block_pudding) << "the gelatin box does not rest on the pudding box";
  for (int i : {block, pudding, can}) {
    const ObjectEstimate& o = r.objects[static_cast<std::size_t>(index(i))];
    EXPECT_LT((o.T_map_obj.translation() - scene.object(i).T_world_obj.translation()).norm(), 0.015)
        << o.model->name;
  }
  // Cross-class merges at any interpenetration past merge_min_penetration_m, as before.
  EstimatorConfig before;
  before.association.merge_cross_class_fraction = 0.0;
  std::vector<Removal> merged;
  run(before, &merged);
  EXPECT_TRUE(std::any_of(merged.begin(), merged.end(), [](const Removal& m) {
    return m.reason == RemovalReason::kMerged;
  })) << "the case is not exercised: nothing merges even by the old rule";
}

// Issue 45: a banana lying against a wooden block, as on real YCB-Video frames. The meshes touch
// (0.5 mm apart) but the block reaches into the air the banana's convex hull spans inside its
// curve, past the cross-class bound, so a merge decided on the hulls (as before) takes the block
// away. Decided on the shapes (convex parts), both stay.
TEST(ObjectOverlap, ABlockInsideABananasCurveIsKept) {
  if (!test::haveYcb()) GTEST_SKIP() << "YCB-Video models not found at " << test::ycbDir();
  ModelSet ycb, models;
  std::vector<std::string> errors;
  ASSERT_TRUE(test::loadYcbModels(&ycb, &errors)) << errors.front();
  for (const char* name : {"011_banana", "036_wood_block"}) models.add(*ycb.find(name));
  TableScene scene(models);
  const int banana = scene.place("011_banana", -0.02, 0.06);
  const int block = scene.place("036_wood_block", 0.2, 0.06);
  // The block's -x face 0.5 mm beyond the banana's surface over the block's y range.
  auto world = [&](int i) {
    std::vector<Eigen::Vector3d> v;
    for (const auto& p : scene.object(i).model->mesh.vertices)
      v.push_back(scene.object(i).T_world_obj * p.cast<double>());
    return v;
  };
  double block_min_x = 1e9, y_lo = 1e9, y_hi = -1e9, banana_x = -1e9;
  for (const auto& p : world(block)) {
    block_min_x = std::min(block_min_x, p.x());
    y_lo = std::min(y_lo, p.y());
    y_hi = std::max(y_hi, p.y());
  }
  for (const auto& p : world(banana))
    if (p.y() >= y_lo && p.y() <= y_hi) banana_x = std::max(banana_x, p.x());
  Eigen::Isometry3d T = scene.object(block).T_world_obj;
  T.translation().x() += banana_x + 0.0005 - block_min_x;
  scene.move(block, T);
  scene.renderObserved();
  EXPECT_GT(scene.scoreTrue(banana).r_in, 0.85);
  EXPECT_GT(scene.scoreTrue(block).r_in, 0.85);
  // The case: the hulls interpenetrate past the cross-class bound, the shapes do not.
  const auto& mb = scene.object(banana).model;
  const auto& mk = scene.object(block).model;
  EXPECT_GT(mb->collision_parts.size(), 1u);
  EXPECT_EQ(mk->collision_parts.size(), 1u);
  const double bound = EstimatorConfig().association.merge_cross_class_fraction *
                       std::min(mb->extents.minCoeff(), mk->extents.minCoeff());
  HullCollider collider;
  const Eigen::Isometry3d &Tb = scene.object(banana).T_world_obj,
                          &Tk = scene.object(block).T_world_obj;
  const double hulls = collider.penetration(mb, Tb, mk, Tk);
  const double shapes = collider.partsPenetration(mb, Tb, mk, Tk);
  std::printf("hulls %.1f mm, shapes %.1f mm into each other (bound %.1f mm)\n", 1000 * hulls,
              1000 * shapes, 1000 * bound);
  ASSERT_GT(hulls, bound) << "the case is not exercised: the hulls are within the bound";
  EXPECT_LT(shapes, 0.5 * bound);

  SceneEstimator estimator(models, EstimatorConfig(), test::sharedRenderer());
  KeyframeResult r;
  std::vector<Removal> removals;
  for (int t = 0; t < 12; ++t) {
    r = estimator.addKeyframe(scene.keyframe(t, {banana, block}));
    removals.insert(removals.end(), r.removals.begin(), r.removals.end());
  }
  EXPECT_TRUE(removals.empty()) << removals.size() << " removals, the first "
                                << toString(removals.front().reason);
  ASSERT_EQ(r.objects.size(), 2u);
  for (const ObjectEstimate& o : r.objects) {
    const int i = o.model->name == "011_banana" ? banana : block;
    EXPECT_LT((o.T_map_obj.translation() - scene.object(i).T_world_obj.translation()).norm(), 0.015)
        << o.model->name;
  }
}

// Convex parts: a convex model keeps its hull as its one part; a curved one's parts cover its
// surface and fill less than its hull.
TEST(ObjectOverlap, ConvexPartsCoverTheShapeAndFillLessThanTheHull) {
  const ModelSet primitives = ModelSet::builtinPrimitives();
  for (const auto& m : primitives.models()) {
    ASSERT_EQ(m->collision_parts.size(), 1u) << m->name;
    EXPECT_EQ(m->collision_parts.front().vertices, m->collision_hull.vertices) << m->name;
  }
  if (!test::haveYcb()) GTEST_SKIP() << "YCB-Video models not found at " << test::ycbDir();
  ModelSet ycb;
  std::vector<std::string> errors;
  ASSERT_TRUE(test::loadYcbModels(&ycb, &errors)) << errors.front();
  for (const char* name : {"011_banana", "051_large_clamp", "025_mug"}) {
    const ObjectModel& m = *ycb.find(name);
    double parts_volume = 0.0;
    for (const TriangleMesh& p : m.collision_parts) parts_volume += enclosedVolume(p);
    std::printf("%s: %zu parts, %.0f %% of the hull's volume\n", name, m.collision_parts.size(),
                100 * parts_volume / enclosedVolume(m.collision_hull));
    if (std::string(name) == "011_banana") {
      EXPECT_GT(m.collision_parts.size(), 1u);
      EXPECT_LT(parts_volume, 0.8 * enclosedVolume(m.collision_hull));
    }
    // The surface lies in the parts (2.5 mm: the simplification's 2 mm and a margin).
    int outside = 0, checked = 0;
    for (std::size_t k = 0; k < m.points.size(); k += 7, ++checked) {
      bool inside = false;
      for (const TriangleMesh& p : m.collision_parts) {
        bool in_part = !p.triangles.empty();
        for (const auto& t : p.triangles) {
          const Eigen::Vector3f a = p.vertices[t[0]], b = p.vertices[t[1]], c = p.vertices[t[2]];
          const Eigen::Vector3f n = (b - a).cross(c - a).normalized();
          if (n.dot(m.points[k] - a) > 0.0025f) {
            in_part = false;
            break;
          }
        }
        inside |= in_part;
      }
      outside += !inside;
    }
    EXPECT_LE(outside, checked / 100)
        << name << ": " << outside << " of " << checked << " surface points outside every part";
  }
}

// The lifecycle's steps on their own (object_lifecycle.h): tracks made by hand, the depth's
// verdict given, the collider the estimator's.
class LifecycleSteps : public ::testing::Test {
 protected:
  LifecycleSteps() : models(ModelSet::builtinPrimitives()) {}

  std::shared_ptr<const ObjectModel> model(const std::string& name) const {
    for (const auto& m : models.models())
      if (m->name == name) return m;
    ADD_FAILURE() << "no model " << name;
    return nullptr;
  }
  // A track measured at keyframes first..last, each measurement with consistency `c`.
  ObjectTrack track(const std::string& name, int id, const Eigen::Vector3d& at, int first, int last,
                    double c) const {
    ObjectTrack tr = makeTrack(id, model(name), Eigen::Isometry3d(Eigen::Translation3d(at)), first);
    for (int k = first; k <= last; ++k) {
      TrackObservation o;
      o.keyframe = k;
      o.consistency = c;
      tr.observations.push_back(o);
    }
    tr.best_consistency = c;
    tr.last_keyframe = last;
    return tr;
  }
  static std::vector<int> ids(const std::vector<ObjectTrack>& tracks) {
    std::vector<int> out;
    for (const ObjectTrack& tr : tracks) out.push_back(tr.id);
    return out;
  }

  ModelSet models;
  AssociationConfig association;
  LifecycleConfig lifecycle;
};

TEST_F(LifecycleSteps, ATrackIsConfirmedByItsScoreAndACandidateTimesOut) {
  std::vector<ObjectTrack> tracks = {
      track("005_tomato_soup_can", 0, {0, 0, 0}, 0, 3, 0.95),  // measured now, well supported
      track("003_cracker_box", 1, {0.3, 0, 0}, 0, 0, 0.3),     // weak candidate, long unseen
      track("025_mug", 2, {0.6, 0, 0}, 0, 0, 0.95)};           // confirmed earlier, long unseen
  tracks[2].confirmed = true;
  std::vector<Removal> removed;
  const int now = association.candidate_timeout_keyframes + 3;
  confirmOrTimeOut(&tracks, {0}, now, association, &removed);
  EXPECT_EQ(ids(tracks), (std::vector<int>{0, 2}));
  EXPECT_TRUE(tracks[0].confirmed);
  ASSERT_EQ(removed.size(), 1u);
  EXPECT_EQ(removed[0].id, 1);
  EXPECT_EQ(removed[0].reason, RemovalReason::kCandidateTimeout);
  // Within the timeout a weak candidate stays, unconfirmed.
  std::vector<ObjectTrack> recent = {track("003_cracker_box", 4, {0, 0, 0}, 5, 5, 0.3)};
  removed.clear();
  confirmOrTimeOut(&recent, {4}, 6, association, &removed);
  EXPECT_TRUE(removed.empty());
  ASSERT_EQ(recent.size(), 1u);
  EXPECT_FALSE(recent[0].confirmed);
}

TEST_F(LifecycleSteps, FreeSpaceRemovesAfterTheConfiguredKeyframesAndASightingResets) {
  std::vector<ObjectTrack> tracks = {track("005_tomato_soup_can", 0, {0, 0, 0}, 0, 0, 0.9),
                                     track("025_mug", 1, {0.3, 0, 0}, 0, 0, 0.9)};
  for (ObjectTrack& tr : tracks) tr.confirmed = true;
  ConsistencyResult free_space, seen;
  free_space.rendered = seen.rendered = 500;
  free_space.determined = seen.determined = true;
  free_space.r_out = 0.9;
  seen.r_in = 0.9;
  int looks = 0;
  auto look = [&](const ObjectTrack& tr) {
    ++looks;
    return tr.id == 0 ? free_space : seen;
  };
  std::vector<Removal> removed;
  for (int t = 1; t < lifecycle.free_space_keyframes; ++t) {
    removeSeenAbsent(&tracks, {}, t, lifecycle, look, &removed);
    EXPECT_TRUE(removed.empty()) << "removed after " << t << " keyframes";
  }
  removeSeenAbsent(&tracks, {}, lifecycle.free_space_keyframes, lifecycle, look, &removed);
  ASSERT_EQ(removed.size(), 1u);
  EXPECT_EQ(removed[0].id, 0);
  EXPECT_EQ(removed[0].reason, RemovalReason::kSeenAbsent);
  EXPECT_EQ(ids(tracks), (std::vector<int>{1}));
  EXPECT_EQ(looks, 2 * lifecycle.free_space_keyframes);
  // Measured by a detection, an object is not looked at and its count restarts.
  tracks[0].free_space_keyframes = lifecycle.free_space_keyframes - 1;
  looks = 0;
  removeSeenAbsent(&tracks, {1}, 10, lifecycle, look, &removed);
  EXPECT_EQ(looks, 0);
  EXPECT_EQ(tracks[0].free_space_keyframes, 0);
}

TEST_F(LifecycleSteps, FreeSpaceChecksAreBoundedLeastRecentlyCheckedFirstAndOutOfViewIsFree) {
  std::vector<ObjectTrack> tracks;
  for (int i = 0; i < 5; ++i) {
    tracks.push_back(track("005_tomato_soup_can", i, {0.2 * i, 0, 0}, 0, 0, 0.9));
    tracks.back().confirmed = true;
    tracks.back().last_checked = 10 - i;  // 4 was checked longest ago
  }
  lifecycle.max_checks_per_keyframe = 2;
  ConsistencyResult in_view;
  in_view.rendered = 100;
  std::vector<int> looked;
  auto look = [&](const ObjectTrack& tr) {
    looked.push_back(tr.id);
    return tr.id == 4 ? ConsistencyResult() : in_view;  // 4 is out of view: rendered 0
  };
  std::vector<Removal> removed;
  removeSeenAbsent(&tracks, {}, 20, lifecycle, look, &removed);
  EXPECT_EQ(looked, (std::vector<int>{4, 3, 2}));  // 4 cost no check
  EXPECT_EQ(tracks[4].last_checked, 6);
  EXPECT_EQ(tracks[3].last_checked, 20);
  EXPECT_EQ(tracks[2].last_checked, 20);
}

TEST_F(LifecycleSteps, OneObjectMappedTwiceIsMergedIntoTheBetterOneWithItsObservations) {
  HullCollider collider;
  std::vector<ObjectTrack> tracks = {track("005_tomato_soup_can", 0, {0, 0, 0}, 0, 4, 0.6),
                                     track("005_tomato_soup_can", 1, {0.005, 0, 0}, 3, 6, 0.95),
                                     track("003_cracker_box", 2, {0.4, 0, 0}, 0, 6, 0.9)};
  std::vector<Removal> removed;
  const TrackPose pose = [](const ObjectTrack& tr) -> const Eigen::Isometry3d& {
    return tr.T_stage_one;
  };
  mergeOverlapping(
      &tracks, association, &collider, pose, [](const ObjectTrack&) { return true; }, &removed);
  // The better track (1) stays under the older id (0, mapped first): the duplicate's id goes.
  EXPECT_EQ(ids(tracks), (std::vector<int>{0, 2}));
  ASSERT_EQ(removed.size(), 1u);
  EXPECT_EQ(removed[0].id, 1);
  EXPECT_EQ(removed[0].reason, RemovalReason::kMerged);
  EXPECT_EQ(removed[0].into, 0);
  // One measurement a keyframe: 0..6, the kept track's own at 3 and 4.
  ASSERT_EQ(tracks[0].observations.size(), 7u);
  for (int k = 0; k < 7; ++k) EXPECT_EQ(tracks[0].observations[k].keyframe, k);
  EXPECT_DOUBLE_EQ(tracks[0].observations[3].consistency, 0.95);
  EXPECT_EQ(tracks[0].first_keyframe, 0);
  EXPECT_EQ(tracks[0].last_keyframe, 6);
  // A resumed object (mapped before the restart, no observations since) found again as a new
  // duplicate: the map's id and its measurements before the restart stay.
  std::vector<ObjectTrack> resumed = {track("005_tomato_soup_can", 3, {0, 0, 0}, 0, -1, 0.7),
                                      track("005_tomato_soup_can", 9, {0.004, 0, 0}, 12, 14, 0.9)};
  resumed[0].first_keyframe = -1, resumed[0].prior_measurements = 20;
  removed.clear();
  mergeOverlapping(
      &resumed, association, &collider, pose, [](const ObjectTrack&) { return true; }, &removed);
  EXPECT_EQ(ids(resumed), std::vector<int>{3});
  EXPECT_EQ(resumed[0].measurementCount(), 23);
  EXPECT_DOUBLE_EQ(resumed[0].best_consistency, 0.9);
  // Neither seen recently: not checked again.
  std::vector<ObjectTrack> stale = {track("005_tomato_soup_can", 5, {0, 0, 0}, 0, 1, 0.6),
                                    track("005_tomato_soup_can", 6, {0.005, 0, 0}, 0, 1, 0.9)};
  removed.clear();
  mergeOverlapping(
      &stale, association, &collider, pose, [](const ObjectTrack&) { return false; }, &removed);
  EXPECT_EQ(stale.size(), 2u);
}

TEST_F(LifecycleSteps, AcrossClassesTheDepthsSupportDecidesAndAFewMillimetresIsContact) {
  HullCollider collider;
  const TrackPose pose = [](const ObjectTrack& tr) -> const Eigen::Isometry3d& {
    return tr.T_stage_one;
  };
  auto always = [](const ObjectTrack&) { return true; };
  // A look-alike reported in the object's place: the one the depth supported more stays, and
  // takes none of the other's observations.
  std::vector<ObjectTrack> swapped = {track("004_sugar_box", 0, {0, 0, 0}, 0, 2, 0.7),
                                      track("003_cracker_box", 1, {0, 0, 0}, 0, 9, 0.9)};
  std::vector<Removal> removed;
  mergeOverlapping(&swapped, association, &collider, pose, always, &removed);
  EXPECT_EQ(ids(swapped), (std::vector<int>{1}));
  ASSERT_EQ(removed.size(), 1u);
  EXPECT_EQ(removed[0].into, 1);
  EXPECT_EQ(swapped[0].observations.size(), 10u);
  // A pudding box with a gelatin box sunk 10 mm into its top: two classes in contact, kept.
  const Eigen::AlignedBox3f pudding = boxOf(*model("008_pudding_box"));
  const Eigen::AlignedBox3f gelatin = boxOf(*model("009_gelatin_box"));
  const double z = pudding.max().z() - gelatin.min().z() - 0.010;
  std::vector<ObjectTrack> stacked = {track("008_pudding_box", 0, {0, 0, 0}, 0, 5, 0.9),
                                      track("009_gelatin_box", 1, {0, 0, z}, 0, 5, 0.9)};
  ASSERT_GT(collider.penetration(stacked[0].model, stacked[0].T_stage_one, stacked[1].model,
                                 stacked[1].T_stage_one),
            0.008);
  removed.clear();
  mergeOverlapping(&stacked, association, &collider, pose, always, &removed);
  EXPECT_TRUE(removed.empty());
  // The same sunk pair of one class is one object mapped twice.
  stacked[1].model = stacked[0].model;
  stacked[1].box_half = stacked[0].box_half;
  stacked[1].box_centre = stacked[0].box_centre;
  stacked[1].T_stage_one.translation().z() = 0.010;
  mergeOverlapping(&stacked, association, &collider, pose, always, &removed);
  EXPECT_EQ(removed.size(), 1u);
}

// Issue 45 (bench_03): a pair of scissors mapped for 66 keyframes beside a pudding box was
// merged away when a pose update tipped the box a few millimetres into it: for a thin object the
// cross-class bound is a share of its thickness. Objects the depth supported together, keyframe
// after keyframe, are two objects: only merge_min_penetration_m merges them; one deep inside the
// other still merges.
TEST_F(LifecycleSteps, TwoClassesTheDepthSupportedTogetherAreTwoObjectsHoweverThin) {
  ModelSet thin_set;
  ObjectModel thin;
  thin.name = "037_scissors";
  thin.id = 17;
  thin.mesh = makeBox(Eigen::Vector3d(0.20, 0.08, 0.012));  // a thin flat object
  thin_set.add(std::move(thin));
  HullCollider collider;
  const TrackPose pose = [](const ObjectTrack& tr) -> const Eigen::Isometry3d& {
    return tr.T_stage_one;
  };
  auto always = [](const ObjectTrack&) { return true; };
  const Eigen::AlignedBox3f pudding = boxOf(*model("008_pudding_box"));
  // The box's bottom 7 mm into the scissors' top, over half their width: past the thin bound
  // (0.5 x 12 mm), short of merge_min_penetration_m (10 mm).
  auto pair = [&](double sink, int last_scissors, double c_scissors) {
    ObjectTrack scissors = track("008_pudding_box", 0, {0, 0, 0}, 0, last_scissors, c_scissors);
    scissors.model = thin_set.models()[0];
    const Eigen::AlignedBox3f b = boxOf(*scissors.model);
    scissors.box_centre = b.center().cast<double>();
    scissors.box_half = (0.5f * b.diagonal()).cast<double>();
    const double z = b.max().z() - pudding.min().z() - sink;
    return std::vector<ObjectTrack>{scissors,
                                    track("008_pudding_box", 1, {0.0, 0.02, z}, 0, 20, 0.95)};
  };
  std::vector<Removal> removed;
  // Measured together with depth support at 21 keyframes: two objects.
  std::vector<ObjectTrack> side_by_side = pair(0.007, 20, 0.9);
  EXPECT_EQ(coMeasuredKeyframes(side_by_side[0], side_by_side[1]), 21);
  mergeOverlapping(&side_by_side, association, &collider, pose, always, &removed);
  EXPECT_TRUE(removed.empty()) << "the scissors were merged into the box";
  // The rule as before (off): merged at 7 mm.
  AssociationConfig before = association;
  before.merge_co_measured_keyframes = 0;
  std::vector<ObjectTrack> old_rule = pair(0.007, 20, 0.9);
  mergeOverlapping(&old_rule, before, &collider, pose, always, &removed);
  EXPECT_EQ(removed.size(), 1u) << "the case is not exercised: the old rule keeps both";
  // The depth refuted the scissors' measurements (f_gc 0: a look-alike reported where the box
  // is): not seen together, merged at 7 mm as before.
  removed.clear();
  std::vector<ObjectTrack> refuted = pair(0.007, 20, 0.0);
  EXPECT_EQ(coMeasuredKeyframes(refuted[0], refuted[1]), 0);
  mergeOverlapping(&refuted, association, &collider, pose, always, &removed);
  EXPECT_EQ(removed.size(), 1u);
  // Seen together but one 15 mm inside the other: merged.
  removed.clear();
  std::vector<ObjectTrack> inside = pair(0.015, 20, 0.9);
  mergeOverlapping(&inside, association, &collider, pose, always, &removed);
  EXPECT_EQ(removed.size(), 1u);
}

}  // namespace
}  // namespace geofusion
