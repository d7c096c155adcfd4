#include "fuzz_targets.h"

#include "geofusion/estimation/frame_by_frame.h"
#include "geofusion/model/object_model.h"
#include "geofusion/ros/conversions.h"

#include <geofusion/DetectionArray.h>
#include <ros/serialization.h>

#include <set>
#include <string>

namespace geofusion {
namespace fuzz {

namespace {

// A serialised Detection takes at least 85 bytes: class_name's length (4), class_id (4), score
// (4), pose (7 doubles) and box (4 uint32 and a bool).
constexpr std::size_t kMinDetectionBytes = 4 + 4 + 4 + 7 * 8 + 4 * 4 + 1;

// ROS 1 deserialisation sizes an array from its length field before it reads the elements, so
// a length the bytes cannot hold would first allocate (up to 4G elements) and only then fail with
// a stream overrun. Such input is rejected here, as the deserialiser would eventually reject it.
bool plausibleLength(const std::uint8_t* data, std::size_t size) {
  auto u32 = [&](std::size_t at) {
    return static_cast<std::uint32_t>(data[at]) | static_cast<std::uint32_t>(data[at + 1]) << 8 |
           static_cast<std::uint32_t>(data[at + 2]) << 16 |
           static_cast<std::uint32_t>(data[at + 3]) << 24;
  };
  std::size_t at = 4 + 8;                       // header.seq, header.stamp
  if (size < at + 4) return true;               // the deserialiser's overrun
  at += 4 + static_cast<std::size_t>(u32(at));  // header.frame_id
  if (size < at + 4) return true;
  const std::size_t count = u32(at);
  return count <= (size - at - 4) / kMinDetectionBytes;
}

}  // namespace

int fuzzDetections(const std::uint8_t* data, std::size_t size) {
  // The estimator's checks with the model set's classes, as EstimatorPipeline sets them up.
  static const std::set<std::string> classes = [] {
    const ModelSet models = ModelSet::builtinPrimitives();
    std::set<std::string> names;
    for (const auto& model : models.models()) names.insert(model->name);
    return names;
  }();
  if (!plausibleLength(data, size)) return 0;
  geofusion::DetectionArray msg;
  try {
    ros::serialization::IStream stream(const_cast<std::uint8_t*>(data),
                                       static_cast<std::uint32_t>(size));
    ros::serialization::deserialize(stream, msg);
  } catch (const ros::serialization::StreamOverrunException&) {
    return 0;  // not a DetectionArray: the subscriber would never see it
  }
  FrameByFrame checker{FrameByFrame::Config()};
  checker.setKnownClasses(classes);
  DetectionTally tally;
  Eigen::Isometry3d T_odom_cam = Eigen::Isometry3d::Identity();
  T_odom_cam.translate(Eigen::Vector3d(0.5, -0.2, 1.1));
  T_odom_cam.rotate(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()));
  const std::vector<RawDetection> raw = fromMsg(msg);
  FUZZ_CHECK(raw.size() == msg.detections.size());
  const std::vector<WorldDetection> used = checker.process(raw, T_odom_cam, &tally);
  // Every detection is either used or skipped for one reason; what is used is finite, in range
  // and of a known class.
  FUZZ_CHECK(tally.frames == 1);
  FUZZ_CHECK(tally.accepted == used.size());
  FUZZ_CHECK(tally.accepted + tally.totalSkipped() == raw.size());
  FUZZ_CHECK(used.size() <= static_cast<std::size_t>(checker.config().max_detections));
  for (const WorldDetection& d : used) {
    FUZZ_CHECK(classes.count(d.measurement.class_name) == 1);
    FUZZ_CHECK(d.measurement.score >= 0.0 && d.measurement.score <= 1.0);
    FUZZ_CHECK(d.measurement.T_cam_obj.matrix().allFinite());
    FUZZ_CHECK(d.T_world_obj.matrix().allFinite());
    FUZZ_CHECK(d.measurement.T_cam_obj.translation().norm() <= checker.config().max_range_m);
  }
  FUZZ_CHECK(!tally.summary().empty());
  return 0;
}

}  // namespace fuzz
}  // namespace geofusion

#ifdef GEOFUSION_LIBFUZZER
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return geofusion::fuzz::fuzzDetections(data, size);
}
#endif
