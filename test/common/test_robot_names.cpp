// The robot's names live in one place for the code (robot_names.h) and one for launch files and
// Python (config/robots/fetch.yaml): they must agree, name for name.
#include "geofusion/common/robot_names.h"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <string>

namespace geofusion {
namespace {

TEST(RobotNames, TheLaunchFilesRobotFileMatchesTheCodesDefaults) {
  const YAML::Node robot =
      YAML::LoadFile(std::string(GEOFUSION_SOURCE_DIR) + "/config/robots/fetch.yaml");
  const std::pair<const char*, const char*> names[] = {
      {"rgb_topic", kRgbTopic},
      {"camera_info_topic", kCameraInfoTopic},
      {"depth_topic", kDepthTopic},
      {"detections_topic", kDetectionsTopic},
      {"wheel_odom_topic", kOdomTopic},
      {"map_frame", kMapFrame},
      {"odom_frame", kOdomFrame},
      {"base_frame", kBaseFrame},
      {"camera_link_frame", kCameraLinkFrame},
      {"camera_frame", kOpticalFrame},
  };
  for (const auto& [key, value] : names) {
    ASSERT_TRUE(robot[key]) << key << " missing from config/robots/fetch.yaml";
    EXPECT_EQ(robot[key].as<std::string>(), value) << key;
  }
  EXPECT_EQ(robot.size(), sizeof(names) / sizeof(names[0]))
      << "config/robots/fetch.yaml has a name robot_names.h does not";
}

// The cameras' files (launch argument camera:=) name the same things as the Fetch's.
TEST(RobotNames, EveryCameraFileNamesWhatTheFetchFileNames) {
  const std::string dir = std::string(GEOFUSION_SOURCE_DIR) + "/config/robots/";
  const YAML::Node fetch = YAML::LoadFile(dir + "fetch.yaml");
  for (const char* camera : {"realsense", "azure_kinect", "openni2", "zed"}) {
    const YAML::Node file = YAML::LoadFile(dir + camera + ".yaml");
    EXPECT_EQ(file.size(), fetch.size()) << camera;
    for (const auto& entry : fetch) {
      const std::string key = entry.first.as<std::string>();
      ASSERT_TRUE(file[key]) << key << " missing from config/robots/" << camera << ".yaml";
      EXPECT_FALSE(file[key].as<std::string>().empty()) << camera << ": " << key;
    }
  }
}

}  // namespace
}  // namespace geofusion
