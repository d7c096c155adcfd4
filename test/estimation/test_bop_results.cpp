// Issue 51: the map as BOP results (bop_results.h). The rows of a keyframe's map and of the final
// map seen from every keyframe: which objects are written (the camera sees their box: the
// evaluation's rule, common/image_box.h), the pose in the camera frame and BOP's model frame in
// mm, the ids and the time; the CSV parsed back as bop_toolkit's load_bop_results reads it.
#include "geofusion/estimation/bop_results.h"
#include "geofusion/model/object_model.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <sstream>

namespace geofusion {
namespace {

struct Row {
  int scene = -1, image = -1, object = -1;
  double score = 0.0, time = 0.0;
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
};

// bop_toolkit's inout.load_bop_results: the header, then 7 comma-separated fields a row.
std::vector<Row> parse(const std::string& csv) {
  std::istringstream in(csv);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "scene_id,im_id,obj_id,score,R,t,time");
  std::vector<Row> rows;
  while (std::getline(in, line)) {
    std::vector<std::string> fields;
    std::stringstream ss(line);
    for (std::string f; std::getline(ss, f, ',');) fields.push_back(f);
    EXPECT_EQ(fields.size(), 7u) << line;
    if (fields.size() != 7) continue;
    Row r;
    r.scene = std::stoi(fields[0]);
    r.image = std::stoi(fields[1]);
    r.object = std::stoi(fields[2]);
    r.score = std::stod(fields[3]);
    std::istringstream R(fields[4]), t(fields[5]);
    for (int i = 0; i < 9; ++i) R >> r.R(i / 3, i % 3);
    t >> r.t.x() >> r.t.y() >> r.t.z();
    EXPECT_FALSE(R.fail() || t.fail()) << line;
    r.time = std::stod(fields[6]);
    rows.push_back(r);
  }
  return rows;
}

ObjectEstimate estimate(const ObjectModel& model, const Eigen::Isometry3d& T_map_obj,
                        double score) {
  ObjectEstimate o;
  o.model = std::make_shared<ObjectModel>(model);
  o.T_map_obj = T_map_obj;
  o.existence = score;
  return o;
}

class BopResults : public ::testing::Test {
 protected:
  void SetUp() override {
    const ModelSet primitives = ModelSet::builtinPrimitives();
    ObjectModel can = *primitives.find("007_tuna_fish_can");
    can.bop_origin = Eigen::Vector3d(0.0, 0.0, 0.01);  // BOP's frame 1 cm up the axis
    ObjectModel box = *primitives.find("003_cracker_box");
    // The camera at 1 m looking down the map's z; the can in front, the box far to the side
    // (outside the image), both on the second keyframe; the first keyframe sees only the can.
    Eigen::Isometry3d T_map_cam = Eigen::Isometry3d::Identity();
    T_map_cam.translation() = Eigen::Vector3d(0.0, 0.0, -1.0);
    Eigen::Isometry3d T_can = Eigen::Isometry3d::Identity();
    T_can.linear() = Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitX()).toRotationMatrix();
    T_can.translation() = Eigen::Vector3d(0.05, -0.02, 0.0);
    Eigen::Isometry3d T_box = Eigen::Isometry3d::Identity();
    T_box.translation() = Eigen::Vector3d(3.0, 0.0, 0.0);
    KeyframeResult k0, k1;
    k0.keyframe = 0;
    k0.T_map_cam = T_map_cam;
    k0.timings.total_ms = 40.0;
    k0.objects = {estimate(can, T_can, 0.7)};
    k1 = k0;
    k1.keyframe = 1;
    k1.T_map_cam.translation().x() = 0.1;
    k1.timings.total_ms = 60.0;
    k1.objects = {estimate(can, T_can, 0.9), estimate(box, T_box, 0.8)};
    results.keyframes = {k0, k1};
    results.final_map = k1;
    results.trajectory = {k0.T_map_cam, k1.T_map_cam};
    can_model = can;
    T_map_can = T_can;
  }
  RunResults results;
  ObjectModel can_model;
  Eigen::Isometry3d T_map_can;
  PinholeIntrinsics K;
};

TEST_F(BopResults, EachKeyframesMapInItsCameraFrameAndBopsModelFrame) {
  BopIds ids;
  ids.scene_id = 7;
  ids.image_of_keyframe[1] = 42;
  ids.object_of_class["007_tuna_fish_can"] = 5;
  const std::vector<Row> rows = parse(bopResultsCsv(keyframeMapImages(results), K, ids));
  ASSERT_EQ(rows.size(), 2u);  // the box is outside the image: not written
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const KeyframeResult& k = results.keyframes[i];
    const Row& r = rows[i];
    EXPECT_EQ(r.scene, 7);
    EXPECT_EQ(r.image, i == 0 ? 0 : 42);
    EXPECT_EQ(r.object, 5);
    EXPECT_NEAR(r.score, k.objects[0].existence, 1e-6);
    EXPECT_NEAR(r.time, k.timings.total_ms / 1000.0, 1e-6);  // the keyframe's time, every row
    const Eigen::Isometry3d T = k.T_map_cam.inverse() * T_map_can;
    EXPECT_TRUE(r.R.isApprox(T.linear(), 1e-8));
    // BOP's origin is 1 cm up the can's axis: t = T (0, 0, 0.01), in mm.
    EXPECT_TRUE(r.t.isApprox(1000.0 * (T * Eigen::Vector3d(0.0, 0.0, 0.01)), 1e-6))
        << r.t.transpose();
  }
}

TEST_F(BopResults, TheFinalMapFromEveryKeyframeUntimed) {
  // The final map moved the can 2 cm: both images carry the final pose, time -1 (not known).
  results.final_map.objects[0].T_map_obj.translation().y() += 0.02;
  const std::vector<Row> rows = parse(bopResultsCsv(finalMapImages(results), K, BopIds()));
  ASSERT_EQ(rows.size(), 2u);
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(rows[i].image, i);
    EXPECT_EQ(rows[i].object, can_model.id);  // default: the class id
    EXPECT_EQ(rows[i].time, -1.0);
    const Eigen::Isometry3d T =
        results.trajectory[i].inverse() * results.final_map.objects[0].T_map_obj;
    EXPECT_TRUE(rows[i].t.isApprox(1000.0 * (T * Eigen::Vector3d(0.0, 0.0, 0.01)), 1e-6));
  }
}

TEST_F(BopResults, NothingBehindTheCameraNorNotFinite) {
  results.keyframes[0].objects[0].T_map_obj.translation().z() = -2.0;  // behind the camera
  results.keyframes[1].objects[0].T_map_obj.translation().x() = std::nan("");
  EXPECT_TRUE(parse(bopResultsCsv(keyframeMapImages(results), K, BopIds())).empty());
  // An object whose origin projects outside the image while its box is in it is written (the
  // evaluation scores it): the can moved so its centre is just past the image's right edge.
  results.keyframes[0].objects[0].T_map_obj = Eigen::Isometry3d::Identity();
  const double edge_x = (K.width - K.cx) / K.fx;  // at 1 m depth
  results.keyframes[0].objects[0].T_map_obj.translation() = Eigen::Vector3d(edge_x + 0.01, 0, 0);
  EXPECT_EQ(parse(bopResultsCsv(keyframeMapImages(results), K, BopIds())).size(), 1u);
}

TEST_F(BopResults, WrittenAtomicallyAndReportedWhenItCannotBe) {
  const std::string path = ::testing::TempDir() + "/geofusion_bop_results.csv";
  std::string error;
  ASSERT_TRUE(writeBopResults(path, keyframeMapImages(results), K, BopIds(), &error)) << error;
  std::ifstream f(path);
  std::stringstream text;
  text << f.rdbuf();
  EXPECT_EQ(text.str(), bopResultsCsv(keyframeMapImages(results), K, BopIds()));
  std::remove(path.c_str());
  EXPECT_FALSE(writeBopResults("/nonexistent-folder/x.csv", keyframeMapImages(results), K, BopIds(),
                               &error));
  EXPECT_FALSE(error.empty());
}

}  // namespace
}  // namespace geofusion
