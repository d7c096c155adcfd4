// The tests' generated clutter sequence (one implementation for the estimator's tests): the demo
// suite's first scene, 40 keyframes at 5 Hz, DenseFusion-like detections, drifting odometry.
#pragma once

#include "geofusion/simulation/dataset.h"

#include <gtest/gtest.h>

#include <random>
#include <string>
#include <vector>

namespace geofusion {

struct DemoSequence {
  ModelSet models;
  ClutterScene scene;
  std::vector<FramePose> poses;
  std::vector<SequenceFrame> frames;
};

/// The sequence of `models` with `objects` objects and `false_positives` phantoms a keyframe.
inline DemoSequence* makeDemoSequence(ModelSet models, int objects, double false_positives) {
  auto* s = new DemoSequence();
  s->models = std::move(models);
  SuiteSpec suite;
  suiteByName("demo", &suite);
  SceneSpec spec = suite.scenes[0];
  spec.num_objects = objects;
  std::string report;
  unsigned used = 0;
  if (!makeSuiteScene(suite, spec, s->models, &s->scene, &used, &report)) {
    ADD_FAILURE() << report;
    return s;
  }
  TrajectoryConfig traj;
  traj.frames = 40;
  s->poses = makeTrajectory(s->scene, traj, 3);
  addOdometryDrift(&s->poses, OdometryNoise(), 4);
  SequenceRenderer renderer(s->scene, PinholeIntrinsics());
  std::mt19937 rng(5);
  DetectorModel detector = DetectorModel::denseFusion();
  detector.false_positives_per_frame = false_positives;
  for (const FramePose& p : s->poses)
    s->frames.push_back(renderer.render(p, DepthNoise(), detector, s->models, rng));
  return s;
}

}  // namespace geofusion
