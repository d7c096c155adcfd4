// The background OctoMap: depth minus the map's objects, ray cast from the camera.
#include "geofusion/background/background_map.h"
#include "geofusion/background/background_worker.h"
#include "geofusion/render/renderer.h"
#include "test_geometry.h"

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <tuple>

namespace geofusion {
namespace {

using namespace test;  // NOLINT: the shared test helpers

struct TableWithBox {
  std::shared_ptr<OffscreenRenderer> renderer = std::make_shared<OffscreenRenderer>();
  std::shared_ptr<ObjectModel> box = std::make_shared<ObjectModel>(boxModel(0.1, 0.1, 0.2));
  Eigen::Isometry3d T_box = at(0.0, 0.0, 0.85);
  PinholeIntrinsics K;
  std::vector<Eigen::Isometry3d> cameras;
  std::vector<RenderedImages> frames;
  TableWithBox() {
    const MeshHandle table = renderer->addMesh(makeBox(Eigen::Vector3d(1.2, 0.8, 0.04)));
    const MeshHandle b = renderer->addMesh(box->mesh);
    for (double a : {-0.4, 0.0, 0.4}) {
      const Eigen::Isometry3d T_map_cam =
          lookAt(Eigen::Vector3d(-0.9 * std::cos(a), 0.9 * std::sin(a), 1.35),
                 Eigen::Vector3d(0, 0, 0.75));
      const Eigen::Isometry3d T_cam_map = T_map_cam.inverse();
      RenderedImages out;
      renderer->render(K, {{table, T_cam_map * at(0, 0, 0.73), 1}, {b, T_cam_map * T_box, 2}}, &out,
                       PixelBox{}, OffscreenRenderer::kDepth);
      cameras.push_back(T_map_cam);
      frames.push_back(out);
    }
  }
};

// Issue 22: a region bounds the map: nothing is mapped outside it, however far the rays reach.
TEST(BackgroundMap, ARegionBoundsTheMap) {
  TableWithBox scene;
  ASSERT_TRUE(scene.renderer->ok());
  BackgroundMapConfig config;
  config.region_half_extent_m = 0.25;  // the table's middle (it is 1.2 x 0.8 m)
  BackgroundMap bounded(config, scene.renderer);
  BackgroundMap unbounded(BackgroundMapConfig(), scene.renderer);
  for (std::size_t k = 0; k < scene.frames.size(); ++k) {
    const DepthImageView depth{scene.frames[k].depth.data(), scene.K.width, scene.K.height};
    bounded.insert(depth, scene.K, scene.cameras[k], {});
    unbounded.insert(depth, scene.K, scene.cameras[k], {});
  }
  const double half = 0.25 + config.resolution_m;
  int outside = 0, inside = 0;
  for (const Eigen::Vector3d& p : bounded.occupiedCentres()) {
    const bool in = p.head<2>().cwiseAbs().maxCoeff() <= half;
    inside += in;
    outside += !in;
  }
  EXPECT_EQ(outside, 0);
  EXPECT_GT(inside, 100);
  EXPECT_LT(bounded.numLeaves(), unbounded.numLeaves() / 2);
  EXPECT_TRUE(bounded.isOccupied(Eigen::Vector3d(0.2, 0.2, 0.745)));
  EXPECT_FALSE(bounded.isOccupied(Eigen::Vector3d(-0.45, 0.2, 0.745)));
  EXPECT_TRUE(unbounded.isOccupied(Eigen::Vector3d(-0.45, 0.2, 0.745)));
}

TEST(BackgroundMap, TableInObjectsOut) {
  TableWithBox scene;
  ASSERT_TRUE(scene.renderer->ok());
  BackgroundMap masked(BackgroundMapConfig(), scene.renderer);
  BackgroundMap unmasked(BackgroundMapConfig(), scene.renderer);
  for (std::size_t k = 0; k < scene.frames.size(); ++k) {
    const DepthImageView depth{scene.frames[k].depth.data(), scene.K.width, scene.K.height};
    EXPECT_GT(masked.insert(depth, scene.K, scene.cameras[k], {{scene.box, scene.T_box}}), 1000);
    unmasked.insert(depth, scene.K, scene.cameras[k], {});
  }
  // The table top beside the box is occupied, in both.
  int table_hits = 0;
  for (double x : {-0.3, -0.2, 0.2}) {
    for (double y : {-0.2, 0.2}) {
      table_hits += masked.isOccupied(Eigen::Vector3d(x, y, 0.745));
    }
  }
  EXPECT_GE(table_hits, 4);
  // The box's visible faces are in the unmasked map only.
  int box_masked = 0, box_unmasked = 0;
  for (const Eigen::Vector3d& p : unmasked.occupiedCentres()) {
    const Eigen::Vector3d q = scene.T_box.inverse() * p;
    box_unmasked +=
        std::abs(q.x()) < 0.06 && std::abs(q.y()) < 0.06 && q.z() > -0.09 && q.z() < 0.11;
  }
  for (const Eigen::Vector3d& p : masked.occupiedCentres()) {
    const Eigen::Vector3d q = scene.T_box.inverse() * p;
    box_masked += std::abs(q.x()) < 0.06 && std::abs(q.y()) < 0.06 && q.z() > -0.09 && q.z() < 0.11;
  }
  EXPECT_GT(box_unmasked, 20);
  EXPECT_EQ(box_masked, 0);
  // An object that joins the map later is carved out of what was inserted before it.
  const DepthImageView last{scene.frames[0].depth.data(), scene.K.width, scene.K.height};
  unmasked.insert(last, scene.K, scene.cameras[0], {{scene.box, scene.T_box}});
  int box_after = 0;
  for (const Eigen::Vector3d& p : unmasked.occupiedCentres()) {
    const Eigen::Vector3d q = scene.T_box.inverse() * p;
    box_after += std::abs(q.x()) < 0.06 && std::abs(q.y()) < 0.06 && q.z() > -0.09 && q.z() < 0.11;
  }
  EXPECT_EQ(box_after, 0);
  // The .bt file is written whole.
  const std::string path = ::testing::TempDir() + "/geofusion_background.bt";
  std::string error;
  ASSERT_TRUE(masked.writeBinary(path, &error)) << error;
  std::ifstream in(path);
  std::string first;
  std::getline(in, first);
  EXPECT_NE(first.find("Octomap"), std::string::npos) << first;
  std::remove(path.c_str());
  // The message payload (octomap_msgs/Octomap data) reads back into the same occupied voxels.
  const std::string data = masked.binaryData();
  ASSERT_FALSE(data.empty());
  std::istringstream payload(data, std::ios::binary);
  octomap::OcTree back(masked.config().resolution_m);
  ASSERT_TRUE(back.readBinaryData(payload));
  std::size_t leaves = 0;
  for (auto it = back.begin_leafs(); it != back.end_leafs(); ++it) {
    if (!back.isNodeOccupied(*it)) continue;
    ++leaves;
    EXPECT_TRUE(masked.isOccupied(Eigen::Vector3d(it.getX(), it.getY(), it.getZ())));
  }
  EXPECT_GT(leaves, 0u);
  for (const Eigen::Vector3d& p : masked.occupiedCentres()) {
    const octomap::OcTreeNode* node = back.search(p.x(), p.y(), p.z());
    ASSERT_NE(node, nullptr);
    EXPECT_TRUE(back.isNodeOccupied(node));
  }
  // Bad input inserts nothing.
  EXPECT_EQ(masked.insert(DepthImageView{}, scene.K, scene.cameras[0], {}), 0);
}

std::set<std::tuple<long, long, long>> voxels(const std::vector<Eigen::Vector3d>& centres) {
  std::set<std::tuple<long, long, long>> out;
  for (const Eigen::Vector3d& p : centres)
    out.emplace(std::lround(p.x() * 1000), std::lround(p.y() * 1000), std::lround(p.z() * 1000));
  return out;
}

// Issue 33: the worker (own thread, own renderer) builds the map the estimator's thread would,
// keyframe by keyframe when asked to wait; its listener runs on its thread after each insertion.
TEST(BackgroundWorker, ThreadedAndWaitingIsTheSameMap) {
  TableWithBox scene;
  ASSERT_TRUE(scene.renderer->ok());
  BackgroundMap direct(BackgroundMapConfig(), scene.renderer);
  BackgroundWorker worker(BackgroundMapConfig{});  // threaded by default
  worker.setWait(true);
  std::vector<std::size_t> heard;
  std::thread::id listener_thread;
  worker.setListener([&](const BackgroundMap& map, double stamp, std::size_t n) {
    EXPECT_DOUBLE_EQ(stamp, static_cast<double>(n));
    heard.push_back(map.numLeaves() > 0 ? n : 0);
    listener_thread = std::this_thread::get_id();
  });
  for (std::size_t k = 0; k < scene.frames.size(); ++k) {
    const DepthImageView depth{scene.frames[k].depth.data(), scene.K.width, scene.K.height};
    direct.insert(depth, scene.K, scene.cameras[k], {{scene.box, scene.T_box}});
    worker.submit(depth, scene.K, scene.cameras[k], {{scene.box, scene.T_box}},
                  static_cast<double>(k + 1));
  }
  EXPECT_EQ(heard, (std::vector<std::size_t>{1, 2, 3}));
  EXPECT_NE(listener_thread, std::this_thread::get_id());
  std::vector<Eigen::Vector3d> centres;
  worker.withMap([&](BackgroundMap& map) { centres = map.occupiedCentres(); });
  EXPECT_GT(centres.size(), 100u);
  EXPECT_EQ(voxels(centres), voxels(direct.occupiedCentres()));
  const BackgroundStats stats = worker.stats();
  EXPECT_EQ(stats.submitted, 3u);
  EXPECT_EQ(stats.inserted, 3u);
  EXPECT_EQ(stats.skipped, 0u);
  EXPECT_GT(stats.total_ms, 0.0);
  EXPECT_NEAR(stats.amortisedMs(), stats.total_ms / 3, 1e-9);
  EXPECT_LE(stats.p50_ms, stats.max_ms);
}

// Keyframes handed over faster than they are inserted: the one waiting is replaced by the newer
// one, counted; nothing is lost uncounted and the newest always goes in.
TEST(BackgroundWorker, ANewerKeyframeReplacesTheOneWaiting) {
  TableWithBox scene;
  ASSERT_TRUE(scene.renderer->ok());
  BackgroundMapConfig config;
  config.max_interval_keyframes = 1;  // every keyframe wanted: only the replacement at work
  BackgroundWorker worker(config);
  std::vector<double> stamps;
  worker.setListener([&](const BackgroundMap&, double stamp, std::size_t) {
    stamps.push_back(stamp);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));  // a slow insertion
  });
  const int n = 30;
  for (int k = 0; k < n; ++k) {
    const std::size_t f = static_cast<std::size_t>(k) % scene.frames.size();
    const DepthImageView depth{scene.frames[f].depth.data(), scene.K.width, scene.K.height};
    worker.submit(depth, scene.K, scene.cameras[f], {}, k);
  }
  worker.waitIdle();
  const BackgroundStats stats = worker.stats();
  EXPECT_EQ(stats.submitted, static_cast<std::size_t>(n));
  EXPECT_EQ(stats.inserted + stats.skipped, stats.submitted);
  EXPECT_EQ(stats.still, 0u);
  EXPECT_GT(stats.skipped, 0u);
  ASSERT_FALSE(stamps.empty());
  EXPECT_DOUBLE_EQ(stamps.back(), n - 1.0);
  EXPECT_TRUE(std::is_sorted(stamps.begin(), stamps.end()));
  // Cleared: no map, counts from zero.
  worker.clear();
  EXPECT_EQ(worker.stats().submitted, 0u);
  std::size_t leaves = 1;
  worker.withMap([&](BackgroundMap& map) { leaves = map.numLeaves(); });
  EXPECT_EQ(leaves, 0u);
}

// A camera that hardly moves adds little: its keyframes are passed over (counted), except every
// max_interval_keyframes-th; a move or a turn past the thresholds is inserted at once.
TEST(BackgroundMap, AStillCameraIsPassedOver) {
  BackgroundMapConfig config;
  config.min_translation_m = 0.03;
  config.min_rotation_deg = 3.0;
  config.max_interval_keyframes = 4;
  TableWithBox scene;
  BackgroundMap map(config, scene.renderer);
  const Eigen::Isometry3d T = scene.cameras[1];
  const DepthImageView depth{scene.frames[1].depth.data(), scene.K.width, scene.K.height};
  EXPECT_TRUE(map.wanted(T));  // nothing inserted yet
  map.insert(depth, scene.K, T, {});
  Eigen::Isometry3d nudged = T;
  nudged.translation().x() += 0.02;
  EXPECT_FALSE(map.wanted(nudged));
  EXPECT_FALSE(map.wanted(T));
  EXPECT_FALSE(map.wanted(T));
  EXPECT_TRUE(map.wanted(T));  // the 4th keyframe since the last insertion
  map.insert(depth, scene.K, T, {});
  Eigen::Isometry3d moved = T;
  moved.translation().y() += 0.035;
  EXPECT_TRUE(map.wanted(moved));
  const Eigen::Isometry3d turned =
      T * Eigen::AngleAxisd(4.0 * M_PI / 180, Eigen::Vector3d::UnitY());
  EXPECT_TRUE(map.wanted(turned));
  const Eigen::Isometry3d barely =
      T * Eigen::AngleAxisd(2.0 * M_PI / 180, Eigen::Vector3d::UnitY());
  EXPECT_FALSE(map.wanted(barely));
  map.clear();
  EXPECT_TRUE(map.wanted(T));  // an empty map wants anything
  // The worker counts them.
  BackgroundWorker worker(config);
  worker.setWait(true);
  for (int k = 0; k < 8; ++k) worker.submit(depth, scene.K, T, {}, k);
  const BackgroundStats stats = worker.stats();
  EXPECT_EQ(stats.inserted, 2u);  // the first and the 4th after it
  EXPECT_EQ(stats.still, 6u);
  EXPECT_EQ(stats.skipped, 0u);
}

// Unthreaded, every keyframe is inserted before submit returns.
TEST(BackgroundWorker, UnthreadedInsertsAtOnce) {
  TableWithBox scene;
  BackgroundMapConfig config;
  config.threaded = false;
  BackgroundWorker worker(config);
  const DepthImageView depth{scene.frames[0].depth.data(), scene.K.width, scene.K.height};
  worker.submit(depth, scene.K, scene.cameras[0], {}, 0.0);
  EXPECT_EQ(worker.stats().inserted, 1u);
  bool occupied = false;
  worker.withMap(
      [&](BackgroundMap& map) { occupied = map.isOccupied(Eigen::Vector3d(0.2, 0.2, 0.745)); });
  EXPECT_TRUE(occupied);
}

}  // namespace
}  // namespace geofusion
