#include "fuzz_targets.h"

#include "geofusion/estimation/frame_by_frame.h"
#include "geofusion/model/object_model.h"
#include "geofusion/ros/conversions.h"
#include "geofusion/ros/vision_detections.h"

#include <geofusion/DetectionArray.h>
#include <ros/serialization.h>
#include <rosbag/bag.h>
#include <rosbag/exceptions.h>
#include <rosbag/view.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <tf2_msgs/TFMessage.h>

#include <map>
#include <string>
#include <vector>

namespace geofusion {
namespace fuzz {

int fuzzBag(const std::uint8_t* data, std::size_t size) {
  const std::string path = writeScratchFile("input.bag", data, size);
  const FrameByFrame checker;
  static const std::map<std::int64_t, ModelClass> class_map = [] {
    std::map<std::int64_t, ModelClass> map;
    std::string error;
    FUZZ_CHECK(makeVisionClassMap("", ModelSet::builtinPrimitives(), &map, &error));
    return map;
  }();
  std::string error;
  VisionDetectionConverter vision(class_map);
  try {
    rosbag::Bag bag;
    bag.open(path, rosbag::bagmode::Read);
    // As run_offline: the whole recording's extent, then every message of the input types.
    rosbag::View view(bag);
    (void)(view.getEndTime() - view.getBeginTime()).toSec();
    std::size_t messages = 0;
    for (const rosbag::MessageInstance& m : view) {
      ++messages;
      const std::string topic = m.getTopic();
      (void)m.getTime().toSec();
      if (const auto image = m.instantiate<sensor_msgs::Image>()) {
        std::vector<float> metres;
        if (depthToMetres(*image, &metres))
          FUZZ_CHECK(metres.size() == static_cast<std::size_t>(image->width) * image->height);
        else
          FUZZ_CHECK(depthProblem(*image) != nullptr);
      } else if (const auto info = m.instantiate<sensor_msgs::CameraInfo>()) {
        // As the estimator and the odometry: K and the lens, a rectifier made from them (its
        // maps built only for a small, valid camera: a fuzzed 60000 x 60000 would be 29 GB).
        CameraRectifier camera;
        std::string error;
        if (camera.update(*info, &error)) {
          FUZZ_CHECK(camera.K().valid() && camera.lens().problem().empty());
          if (info->width <= 64 && info->height <= 64) {
            std::vector<float> depth(static_cast<std::size_t>(info->width) * info->height, 1.f);
            FUZZ_CHECK(camera.rectifyDepth(&depth));
          }
        } else {
          FUZZ_CHECK(!error.empty());
        }
      } else if (const auto detections = m.instantiate<geofusion::DetectionArray>()) {
        DetectionTally tally;
        checker.process(fromMsg(*detections), Eigen::Isometry3d::Identity(), &tally);
        FUZZ_CHECK(tally.accepted + tally.totalSkipped() == detections->detections.size());
      } else if (m.getDataType() == kVisionDetectionsType) {
        // As run_offline: the message's bytes through the hand-written vision_msgs reader.
        std::vector<std::uint8_t> bytes(m.size());
        ros::serialization::OStream stream(bytes.data(), static_cast<std::uint32_t>(bytes.size()));
        m.write(stream);
        geofusion::DetectionArray converted;
        const std::size_t before = vision.counts().messages + vision.counts().rejected;
        const bool ok = vision.convert(m.getDataType(), m.getMD5Sum(), bytes.data(), bytes.size(),
                                       &converted, &error);
        FUZZ_CHECK(vision.counts().messages + vision.counts().rejected == before + 1);
        if (ok) {
          DetectionTally tally;
          checker.process(fromMsg(converted), Eigen::Isometry3d::Identity(), &tally);
          FUZZ_CHECK(tally.accepted + tally.totalSkipped() == converted.detections.size());
        }
      } else if (const auto tf = m.instantiate<tf2_msgs::TFMessage>()) {
        for (const auto& t : tf->transforms) (void)t.header.stamp.toSec();
      }
    }
    FUZZ_CHECK(messages <= view.size());
  } catch (const rosbag::BagException&) {
    return 0;  // not a bag rosbag reads (run_offline says so and stops)
  } catch (const ros::serialization::StreamOverrunException&) {
    return 0;  // a message shorter than its type
  }
  return 0;
}

}  // namespace fuzz
}  // namespace geofusion

#ifdef GEOFUSION_LIBFUZZER
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return geofusion::fuzz::fuzzBag(data, size);
}
#endif
