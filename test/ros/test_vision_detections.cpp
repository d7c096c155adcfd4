// The vision_msgs/Detection3DArray reader and converter (ros/vision_detections.h), no master.
#include "geofusion/model/object_model.h"
#include "geofusion/ros/vision_detections.h"

#include <gtest/gtest.h>

#include <cstring>
#include <map>
#include <string>

namespace geofusion {
namespace {

geometry_msgs::Pose poseAt(double x, double y, double z) {
  geometry_msgs::Pose p;
  p.position.x = x;
  p.position.y = y;
  p.position.z = z;
  p.orientation.w = 1.0;
  return p;
}

VisionHypothesis hypothesis(std::int64_t id, double score, double x) {
  VisionHypothesis h;
  h.id = id;
  h.score = score;
  h.pose = poseAt(x, 0.1, 0.8);
  return h;
}

VisionDetections twoDetections() {
  VisionDetections d;
  d.header.stamp = ros::Time(12, 500);
  d.header.frame_id = "head_camera_rgb_optical_frame";
  d.detections = {{hypothesis(2, 0.4, 0.1), hypothesis(4, 0.9, 0.2), hypothesis(99, 0.95, 0.3)},
                  {hypothesis(99, 0.8, 0.4)}};
  d.frames = {"a", "b"};
  return d;
}

TEST(VisionDetections, BytesReadBackAsWritten) {
  const VisionDetections in = twoDetections();
  const auto bytes = encodeVisionDetections(in);
  VisionDetections out;
  std::string error;
  ASSERT_TRUE(decodeVisionDetections(bytes.data(), bytes.size(), &out, &error)) << error;
  EXPECT_EQ(out.header.stamp, in.header.stamp);
  EXPECT_EQ(out.header.frame_id, in.header.frame_id);
  ASSERT_EQ(out.detections.size(), 2u);
  ASSERT_EQ(out.detections[0].size(), 3u);
  EXPECT_EQ(out.detections[0][1].id, 4);
  EXPECT_DOUBLE_EQ(out.detections[0][1].score, 0.9);
  EXPECT_DOUBLE_EQ(out.detections[0][2].pose.position.x, 0.3);
  EXPECT_EQ(out.frames, in.frames);
}

TEST(VisionDetections, TruncatedAndOverlongBytesAreRefused) {
  const auto bytes = encodeVisionDetections(twoDetections());
  VisionDetections out;
  std::string error;
  for (std::size_t cut : {std::size_t{0}, std::size_t{10}, bytes.size() / 2, bytes.size() - 1}) {
    EXPECT_FALSE(decodeVisionDetections(bytes.data(), cut, &out, &error)) << cut;
    EXPECT_NE(error.find("not a Noetic vision_msgs/Detection3DArray"), std::string::npos);
  }
  auto longer = bytes;
  longer.push_back(0);
  EXPECT_FALSE(decodeVisionDetections(longer.data(), longer.size(), &out, &error));
  // A detection count the bytes cannot hold is refused before anything is allocated for it.
  auto huge = bytes;
  const std::size_t count_at = 4 + 8 + 4 + twoDetections().header.frame_id.size();
  const std::uint32_t count = 0xFFFFFFF0u;
  std::memcpy(huge.data() + count_at, &count, 4);
  EXPECT_FALSE(decodeVisionDetections(huge.data(), huge.size(), &out, &error));
  EXPECT_NE(error.find("4294967280 detections"), std::string::npos) << error;
}

TEST(VisionDetections, ClassMapFollowsTheModelSetOrTheSetting) {
  const ModelSet models = ModelSet::builtinPrimitives();
  std::map<std::int64_t, ModelClass> map;
  std::string error;
  ASSERT_TRUE(makeVisionClassMap("", models, &map, &error)) << error;
  EXPECT_EQ(map.size(), models.size());
  for (const auto& m : models.models()) EXPECT_EQ(map.at(m->id).name, m->name);

  const std::string a = models.models()[0]->name, b = models.models()[1]->name;
  ASSERT_TRUE(makeVisionClassMap(" 7: " + a + ",12:" + b, models, &map, &error)) << error;
  ASSERT_EQ(map.size(), 2u);
  EXPECT_EQ(map.at(7).name, a);
  EXPECT_EQ(map.at(7).id, models.models()[0]->id);
  EXPECT_EQ(map.at(12).name, b);

  EXPECT_FALSE(makeVisionClassMap("7 " + a, models, &map, &error));
  EXPECT_NE(error.find("is not 'id: class_name'"), std::string::npos) << error;
  EXPECT_FALSE(makeVisionClassMap("x: " + a, models, &map, &error));
  EXPECT_FALSE(makeVisionClassMap("7: " + a + ", 7: " + b, models, &map, &error));
  EXPECT_NE(error.find("mapped twice"), std::string::npos) << error;
  EXPECT_FALSE(makeVisionClassMap("7: no_such_class", models, &map, &error));
  EXPECT_NE(error.find("no_such_class"), std::string::npos) << error;
}

TEST(VisionDetections, ConverterTakesTheBestMappedHypothesis) {
  const ModelSet models = ModelSet::builtinPrimitives();
  const std::string a = models.models()[0]->name, b = models.models()[1]->name;
  std::map<std::int64_t, ModelClass> map;
  std::string error;
  ASSERT_TRUE(makeVisionClassMap("2: " + a + ", 4: " + b, models, &map, &error)) << error;
  VisionDetectionConverter converter(map);
  const auto bytes = encodeVisionDetections(twoDetections());
  geofusion::DetectionArray out;
  ASSERT_TRUE(converter.convert(kVisionDetectionsType, kVisionDetectionsMd5, bytes.data(),
                                bytes.size(), &out, &error))
      << error;
  EXPECT_EQ(out.header.frame_id, "head_camera_rgb_optical_frame");
  EXPECT_EQ(out.header.stamp, ros::Time(12, 500));
  ASSERT_EQ(out.detections.size(), 1u);  // the second has only the unmapped id 99
  EXPECT_EQ(out.detections[0].class_name, b);
  EXPECT_EQ(out.detections[0].class_id, models.models()[1]->id);
  EXPECT_FLOAT_EQ(out.detections[0].score, 0.9f);
  EXPECT_DOUBLE_EQ(out.detections[0].pose.position.x, 0.2);
  EXPECT_EQ(converter.counts().detections, 1u);
  EXPECT_EQ(converter.counts().unmapped, 1u);
  EXPECT_EQ(converter.counts().unmapped_ids.at(99), 2u);
  EXPECT_NE(converter.droppedSummary().find("1 detections without a mapped class (ids 99 x2"),
            std::string::npos)
      << converter.droppedSummary();

  // Another type or layout is refused and counted, the output left alone.
  out.detections.clear();
  EXPECT_FALSE(converter.convert(kVisionDetectionsType, "7acb1221dbe749da0ef7b94550480c8f",
                                 bytes.data(), bytes.size(), &out, &error));
  EXPECT_NE(error.find(kVisionDetectionsMd5), std::string::npos) << error;
  EXPECT_FALSE(converter.convert("vision_msgs/Detection2DArray", kVisionDetectionsMd5, bytes.data(),
                                 bytes.size(), &out, &error));
  EXPECT_EQ(converter.counts().rejected, 2u);
  EXPECT_TRUE(out.detections.empty());
}

TEST(VisionDetections, EmptyArrayFrameFallsBackToTheFirstDetections) {
  VisionDetections in = twoDetections();
  in.header.frame_id.clear();
  const auto bytes = encodeVisionDetections(in);
  VisionDetectionConverter converter({});
  geofusion::DetectionArray out;
  std::string error;
  ASSERT_TRUE(converter.convert(kVisionDetectionsType, kVisionDetectionsMd5, bytes.data(),
                                bytes.size(), &out, &error));
  EXPECT_EQ(out.header.frame_id, "a");
  EXPECT_TRUE(out.detections.empty());
}

}  // namespace
}  // namespace geofusion
