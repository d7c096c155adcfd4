// Issue 51: a recording's ground truth as a BOP dataset folder (bop_dataset.h), the files BOP's
// toolkit reads beside the package's BOP results: poses in BOP's model frame and mm, models_info
// with the appearance symmetries about BOP's origin, BOP19's targets, the id mapping; several
// scenes in one folder; a corrupt file reported, not overwritten.
#include "geofusion/evaluation/bop_dataset.h"
#include "geofusion/evaluation/bop_metrics.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace geofusion {
namespace {

using nlohmann::json;

json readJson(const std::string& path) {
  std::ifstream f(path);
  EXPECT_TRUE(f.good()) << path;
  json j;
  if (f) f >> j;
  return j;
}

Eigen::Isometry3d pose(const json& gt) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (int i = 0; i < 9; ++i) T.linear()(i / 3, i % 3) = gt["cam_R_m2c"][i].get<double>();
  for (int i = 0; i < 3; ++i) T.translation()[i] = gt["cam_t_m2c"][i].get<double>() / 1000.0;
  return T;
}

class BopDataset : public ::testing::Test {
 protected:
  void SetUp() override {
    char pattern[] = "/tmp/geofusion_bop_dataset_XXXXXX";
    ASSERT_NE(::mkdtemp(pattern), nullptr);
    folder = pattern;
    root = folder + "/ycbv";
    const ModelSet primitives = ModelSet::builtinPrimitives();
    auto can = std::make_shared<ObjectModel>(*primitives.find("007_tuna_fish_can"));
    can->bop_origin = Eigen::Vector3d(0.0, 0.0, 0.01);
    can->appearance_symmetry.type = Symmetry::Type::kDiscrete;
    can->appearance_symmetry.rotations = {
        Eigen::Quaterniond(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitZ()))};
    auto box = std::make_shared<ObjectModel>(*primitives.find("003_cracker_box"));
    models.add(*can);
    models.add(*box);
    models.add(*primitives.find("005_tomato_soup_can"));  // a class no true object has
    SceneObject a, b;
    a.model = can;
    a.T_world_obj.translation() = Eigen::Vector3d(0.05, 0.0, 0.0);
    b.model = box;
    b.T_world_obj.translation() = Eigen::Vector3d(-0.1, 0.05, 0.05);
    b.present_until_frame = 5;  // taken away after frame 4
    gt.scene_name = "bench_03";
    gt.scene.objects = {a, b};
    for (int i = 0; i < 2; ++i) {
      GroundTruthFrame f;
      f.index = 4 * i;
      f.stamp_s = 100.0 + i;
      f.keyframe = true;
      f.T_map_optical.translation() = Eigen::Vector3d(0.02 * i, 0.0, -1.0);
      f.visible_fraction = {0.8, 0.05};
      f.visible_pixels = {2000, 100};
      f.visible_boxes = {PixelBox{300, 200, 40, 50}, PixelBox{100, 100, 10, 10}};
      gt.frames.push_back(f);
      KeyframeResult k;
      k.keyframe = i;
      k.stamp_s = f.stamp_s + 0.0005;
      results.keyframes.push_back(k);
    }
    gt.frames[1].index = 8;  // the box is gone at the second keyframe
  }
  void TearDown() override { std::system(("rm -rf " + folder).c_str()); }
  std::string folder, root;
  ModelSet models;
  GroundTruth gt;
  RunResults results;
};

TEST_F(BopDataset, TheGroundTruthAsBopsToolkitReadsIt) {
  BopIds ids;
  ids.scene_id = 3;
  std::string error;
  ASSERT_TRUE(writeBopDataset(root, models, gt, results, ids, 1e-3, &error)) << error;
  const json camera = readJson(root + "/test/000003/scene_camera.json");
  const json scene_gt = readJson(root + "/test/000003/scene_gt.json");
  const json info = readJson(root + "/test/000003/scene_gt_info.json");
  ASSERT_EQ(scene_gt.size(), 2u);
  EXPECT_NEAR(camera["0"]["cam_K"][0].get<double>(), gt.intrinsics.fx, 1e-9);
  EXPECT_NEAR(camera["1"]["cam_K"][5].get<double>(), gt.intrinsics.cy, 1e-9);
  ASSERT_EQ(scene_gt["0"].size(), 2u);  // both objects at frame 0
  ASSERT_EQ(scene_gt["1"].size(), 1u);  // the box is gone at frame 8
  // The can in the camera frame, in BOP's frame (1 cm up its axis), t in mm.
  const Eigen::Isometry3d T_expected = gt.frames[1].T_map_optical.inverse() *
                                       gt.scene.objects[0].T_world_obj *
                                       Eigen::Translation3d(0.0, 0.0, 0.01);
  EXPECT_TRUE(pose(scene_gt["1"][0]).isApprox(T_expected, 1e-9));
  EXPECT_EQ(scene_gt["1"][0]["obj_id"].get<int>(), gt.scene.objects[0].model->id);
  EXPECT_NEAR(info["0"][0]["visib_fract"].get<double>(), 0.8, 1e-12);
  EXPECT_EQ(info["0"][0]["px_count_all"].get<int>(), 2500);
  EXPECT_EQ(info["0"][0]["bbox_visib"], json({300, 200, 40, 50}));
  EXPECT_GT(info["0"][0]["bbox_obj"][2].get<int>(), 0);
  // Targets: the can in both images; the box (5 % visible) in none.
  const json targets = readJson(root + "/test_targets_bop19.json");
  ASSERT_EQ(targets.size(), 2u);
  for (const json& t : targets) {
    EXPECT_EQ(t["scene_id"].get<int>(), 3);
    EXPECT_EQ(t["obj_id"].get<int>(), gt.scene.objects[0].model->id);
    EXPECT_EQ(t["inst_count"].get<int>(), 1);
  }
  // The mapping: image -> keyframe, stamp and frame; gt_id -> object index; obj_id -> class.
  const json ids_file = readJson(root + "/geofusion_ids.json");
  EXPECT_EQ(ids_file["scenes"]["3"]["name"], "bench_03");
  EXPECT_EQ(ids_file["scenes"]["3"]["images"]["1"]["frame"].get<int>(), 8);
  EXPECT_EQ(ids_file["scenes"]["3"]["gt_objects"]["0"], json({0, 1}));
  EXPECT_EQ(ids_file["obj_ids"][std::to_string(gt.scene.objects[1].model->id)], "003_cracker_box");
  // Every class of the model set has its model (an estimate of any class can be scored).
  const int soup = models.find("005_tomato_soup_can")->id;
  EXPECT_EQ(ids_file["obj_ids"][std::to_string(soup)], "005_tomato_soup_can");
  char ply[64];
  std::snprintf(ply, sizeof(ply), "/models_eval/obj_%06d.ply", soup);
  EXPECT_TRUE(std::ifstream(root + ply).good()) << ply;
}

TEST_F(BopDataset, ModelsInfoInBopsFrameWithTheAppearanceSymmetries) {
  std::string error;
  ASSERT_TRUE(writeBopDataset(root, models, gt, results, BopIds(), 1e-3, &error)) << error;
  const ObjectModel& can = *gt.scene.objects[0].model;
  const json info = readJson(root + "/models_eval/models_info.json")[std::to_string(can.id)];
  const BopModel bop = bopModelOf(can);
  EXPECT_NEAR(info["diameter"].get<double>(), 1000.0 * bop.diameter_m, 1e-6);
  // The box in BOP's frame: its centre 1 cm below the model origin's box centre.
  const Eigen::Vector3d centre_mm = 1000.0 * (bop.centre - can.bop_origin);
  EXPECT_NEAR(info["min_z"].get<double>() + 0.5 * info["size_z"].get<double>(), centre_mm.z(),
              1e-3);
  // The half turn about z through the box centre, as a 4x4 in mm: it maps the points onto
  // themselves (up to the points' sampling) and fixes the centre.
  ASSERT_EQ(info["symmetries_discrete"].size(), 1u);
  Eigen::Matrix4d S;
  for (int i = 0; i < 16; ++i) S(i / 4, i % 4) = info["symmetries_discrete"][0][i].get<double>();
  EXPECT_TRUE(
      (S.topLeftCorner<3, 3>() * centre_mm + S.topRightCorner<3, 1>()).isApprox(centre_mm, 1e-9));
  EXPECT_NEAR(S(0, 0), -1.0, 1e-12);
  EXPECT_FALSE(info.contains("symmetries_continuous"));
  // The primitive box (untextured: it looks as symmetric as it is) lists its turns.
  const ObjectModel& box_model = *gt.scene.objects[1].model;
  const json box = readJson(root + "/models_eval/models_info.json")[std::to_string(box_model.id)];
  ASSERT_EQ(box_model.appearance_symmetry.type, Symmetry::Type::kDiscrete);
  EXPECT_EQ(box["symmetries_discrete"].size(), box_model.appearance_symmetry.rotations.size());
  // The points, mm, in BOP's frame.
  std::ifstream ply(root + "/models_eval/obj_" + [&] {
    char b[8];
    std::snprintf(b, sizeof(b), "%06d", can.id);
    return std::string(b);
  }() + ".ply");
  std::string line;
  int vertices = -1;
  while (std::getline(ply, line) && line != "end_header")
    if (line.rfind("element vertex ", 0) == 0) vertices = std::stoi(line.substr(15));
  EXPECT_EQ(vertices, static_cast<int>(can.points.size()));
  double x, y, z;
  ply >> x >> y >> z;
  EXPECT_NEAR(z, 1000.0 * (can.points[0].z() - 0.01), 1e-3);
}

TEST_F(BopDataset, ScenesShareAFolderAndACorruptFileIsReported) {
  BopIds first, second;
  first.scene_id = 3;
  second.scene_id = 4;
  std::string error;
  ASSERT_TRUE(writeBopDataset(root, models, gt, results, first, 1e-3, &error)) << error;
  ASSERT_TRUE(writeBopDataset(root, models, gt, results, second, 1e-3, &error)) << error;
  ASSERT_TRUE(writeBopDataset(root, models, gt, results, second, 1e-3, &error)) << error;  // again
  EXPECT_EQ(readJson(root + "/test_targets_bop19.json").size(), 4u);  // 2 a scene, not 6
  EXPECT_EQ(readJson(root + "/geofusion_ids.json")["scenes"].size(), 2u);
  // No keyframe of the results at a ground-truth stamp: nothing to write.
  RunResults shifted = results;
  for (KeyframeResult& k : shifted.keyframes) k.stamp_s += 1.5;
  EXPECT_FALSE(writeBopDataset(root, models, gt, shifted, first, 1e-3, &error));
  EXPECT_NE(error.find("no keyframe"), std::string::npos) << error;
  // A corrupt targets file is reported and left as it is.
  { std::ofstream(root + "/test_targets_bop19.json") << "[{"; }
  EXPECT_FALSE(writeBopDataset(root, models, gt, results, first, 1e-3, &error));
  EXPECT_NE(error.find("not JSON"), std::string::npos) << error;
  std::ifstream f(root + "/test_targets_bop19.json");
  std::stringstream text;
  text << f.rdbuf();
  EXPECT_EQ(text.str(), "[{");
}

}  // namespace
}  // namespace geofusion
