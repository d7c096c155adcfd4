// camera_info's lens (ros/conversions.h): which distortion models are rectified, which refused,
// and the odometry's image preparation on distorted and pinhole cameras. No master.
#include "geofusion/ros/conversions.h"

#include <gtest/gtest.h>
#include <sensor_msgs/image_encodings.h>

#include <cmath>
#include <string>
#include <vector>

namespace geofusion {
namespace {

sensor_msgs::CameraInfo cameraInfo(const std::string& model, std::vector<double> D,
                                   unsigned width = 640, unsigned height = 480) {
  sensor_msgs::CameraInfo info;
  info.width = width;
  info.height = height;
  info.K = {554.25, 0, 320.5, 0, 554.25, 240.5, 0, 0, 1};
  info.distortion_model = model;
  info.D = std::move(D);
  return info;
}

TEST(CameraInfoLens, SupportedModelsAreReadAndOthersRefusedWithTheReason) {
  LensDistortion lens;
  std::string error;
  ASSERT_TRUE(
      lensFromCameraInfo(cameraInfo("plumb_bob", LensDistortion::primesense().D), &lens, &error));
  EXPECT_EQ(lens.D, LensDistortion::primesense().D);
  ASSERT_TRUE(lensFromCameraInfo(
      cameraInfo("rational_polynomial", {0.5, -0.1, 0.001, 0.0, 0.02, 0.8, -0.05, 0.01}), &lens,
      &error));
  EXPECT_EQ(lens.D.size(), 8u);
  // Zero (or no) coefficients: no distortion, whatever the model says.
  ASSERT_TRUE(lensFromCameraInfo(cameraInfo("equidistant", {0, 0, 0, 0}), &lens, &error));
  EXPECT_FALSE(lens.any());
  ASSERT_TRUE(lensFromCameraInfo(cameraInfo("", {}), &lens, &error));
  EXPECT_FALSE(lens.any());

  EXPECT_FALSE(lensFromCameraInfo(cameraInfo("equidistant", {0.1, 0, 0, 0}), &lens, &error));
  EXPECT_NE(error.find("'equidistant' is not supported"), std::string::npos) << error;
  EXPECT_FALSE(lensFromCameraInfo(cameraInfo("plumb_bob", {0.1, 0.2, 0, 0, 0, 0}), &lens, &error));
  EXPECT_NE(error.find("it takes 5"), std::string::npos) << error;
  EXPECT_FALSE(lensFromCameraInfo(cameraInfo("plumb_bob", {NAN, 0, 0, 0, 0}), &lens, &error));
  EXPECT_NE(error.find("not finite"), std::string::npos) << error;
}

TEST(CameraInfoLens, TheRectifierRefusesWhatItCannotUse) {
  CameraRectifier camera;
  std::string error;
  EXPECT_TRUE(camera.update(cameraInfo("plumb_bob", LensDistortion::primesense().D), &error));
  EXPECT_TRUE(camera.lens().any());
  sensor_msgs::CameraInfo no_focal = cameraInfo("plumb_bob", {0, 0, 0, 0, 0});
  no_focal.K[0] = 0.0;
  EXPECT_FALSE(camera.update(no_focal, &error));
  EXPECT_NE(error.find("not a camera"), std::string::npos) << error;
  sensor_msgs::CameraInfo nan_centre = cameraInfo("plumb_bob", {0, 0, 0, 0, 0});
  nan_centre.K[2] = NAN;
  EXPECT_FALSE(camera.update(nan_centre, &error));
  // OpenCV cannot warp a 40000 pixel wide image: refused with a lens, used as it is without.
  EXPECT_FALSE(
      camera.update(cameraInfo("plumb_bob", LensDistortion::primesense().D, 40000, 1), &error));
  EXPECT_NE(error.find("too large"), std::string::npos) << error;
  EXPECT_TRUE(camera.update(cameraInfo("plumb_bob", {0, 0, 0, 0, 0}, 40000, 1), &error));
  std::vector<float> row(40000, 1.f);
  EXPECT_TRUE(camera.rectifyDepth(&row));
  // The last good calibration is kept by a refused update.
  ASSERT_TRUE(camera.update(cameraInfo("plumb_bob", LensDistortion::primesense().D), &error));
  EXPECT_FALSE(camera.update(cameraInfo("equidistant", {0.1, 0, 0, 0}), &error));
  EXPECT_EQ(camera.K().width, 640);
  EXPECT_TRUE(camera.lens().any());
}

sensor_msgs::Image image(const std::string& encoding, unsigned width, unsigned height,
                         unsigned char value) {
  sensor_msgs::Image im;
  im.width = width;
  im.height = height;
  im.encoding = encoding;
  const unsigned bytes = encoding == sensor_msgs::image_encodings::RGB8 ? 3 : 2;
  im.step = width * bytes;
  im.data.assign(static_cast<std::size_t>(im.step) * height, value);
  return im;
}

TEST(CameraInfoLens, OdometryImagesAreMadePinholeOrRefusedWithTheReason) {
  const sensor_msgs::Image rgb = image(sensor_msgs::image_encodings::RGB8, 640, 480, 200);
  const sensor_msgs::Image depth = image(sensor_msgs::image_encodings::TYPE_16UC1, 640, 480, 4);
  CameraRectifier camera;
  std::vector<std::uint8_t> grey;
  std::vector<float> metres;
  std::string error;
  ASSERT_TRUE(odometryImages(rgb, depth, cameraInfo("plumb_bob", LensDistortion::primesense().D),
                             &camera, &grey, &metres, &error))
      << error;
  // A barrel-pincushion lens leaves the pinhole image's corners unseen: no reading there, the
  // centre as it was.
  EXPECT_EQ(grey[0], 0);
  EXPECT_EQ(metres[0], 0.f);
  EXPECT_EQ(grey[240 * 640 + 320], 200);
  EXPECT_NEAR(metres[240 * 640 + 320], 1.028f, 1e-6f);  // 0x0404 mm
  ASSERT_TRUE(odometryImages(rgb, depth, cameraInfo("plumb_bob", {0, 0, 0, 0, 0}), &camera, &grey,
                             &metres, &error));
  EXPECT_EQ(grey[0], 200);
  EXPECT_FALSE(odometryImages(rgb, image(sensor_msgs::image_encodings::TYPE_16UC1, 320, 240, 4),
                              cameraInfo("plumb_bob", {0, 0, 0, 0, 0}), &camera, &grey, &metres,
                              &error));
  EXPECT_EQ(error, "RGB and depth sizes differ");
  EXPECT_FALSE(odometryImages(rgb, depth, cameraInfo("plumb_bob", {0, 0, 0, 0, 0}, 320, 240),
                              &camera, &grey, &metres, &error));
  EXPECT_NE(error.find("not the size camera_info says"), std::string::npos) << error;
  EXPECT_FALSE(odometryImages(rgb, depth, cameraInfo("fisheye", {0.2, 0, 0, 0}), &camera, &grey,
                              &metres, &error));
  EXPECT_NE(error.find("not supported"), std::string::npos) << error;
}

}  // namespace
}  // namespace geofusion
