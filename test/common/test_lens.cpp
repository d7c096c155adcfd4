// Lens distortion warps (common/lens.h): a point lands where the plumb_bob model (written out
// here, independently of OpenCV) puts it; raw -> pinhole undoes pinhole -> raw; depth is never
// mixed across an edge; bad input is refused without a change.
#include "geofusion/common/lens.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

namespace geofusion {
namespace {

// The plumb_bob model: normalised pinhole (x, y) -> normalised distorted coordinates.
Eigen::Vector2d plumbBob(const LensDistortion& lens, double x, double y) {
  const double k1 = lens.D[0], k2 = lens.D[1], p1 = lens.D[2], p2 = lens.D[3], k3 = lens.D[4];
  const double r2 = x * x + y * y;
  const double radial = 1.0 + k1 * r2 + k2 * r2 * r2 + k3 * r2 * r2 * r2;
  return {x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x),
          y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y};
}

// A black rgb image with a white 3x3 dot centred on each pixel of `dots`.
std::vector<std::uint8_t> dotImage(const PinholeIntrinsics& K,
                                   const std::vector<Eigen::Vector2i>& dots) {
  std::vector<std::uint8_t> rgb(static_cast<std::size_t>(K.width) * K.height * 3, 0);
  for (const Eigen::Vector2i& d : dots)
    for (int dv = -1; dv <= 1; ++dv)
      for (int du = -1; du <= 1; ++du)
        for (int c = 0; c < 3; ++c)
          rgb[(static_cast<std::size_t>(d.y() + dv) * K.width + d.x() + du) * 3 + c] = 255;
  return rgb;
}

// The intensity-weighted centre of the red channel within `radius` pixels of `near`.
Eigen::Vector2d centroidNear(const PinholeIntrinsics& K, const std::vector<std::uint8_t>& rgb,
                             const Eigen::Vector2d& near, int radius) {
  double sw = 0.0;
  Eigen::Vector2d s = Eigen::Vector2d::Zero();
  for (int v = static_cast<int>(near.y()) - radius; v <= near.y() + radius; ++v) {
    for (int u = static_cast<int>(near.x()) - radius; u <= near.x() + radius; ++u) {
      if (u < 0 || v < 0 || u >= K.width || v >= K.height) continue;
      const double w = rgb[(static_cast<std::size_t>(v) * K.width + u) * 3];
      sw += w;
      s += w * Eigen::Vector2d(u, v);
    }
  }
  return sw > 0.0 ? Eigen::Vector2d(s / sw) : Eigen::Vector2d(-1.0, -1.0);
}

TEST(LensWarp, DistortedPointsLandWhereThePlumbBobModelPutsThem) {
  const PinholeIntrinsics K;
  const LensDistortion lens = LensDistortion::primesense();
  const std::vector<Eigen::Vector2i> dots = {{320, 240}, {30, 30},   {560, 60},
                                             {60, 420},  {610, 450}, {320, 40}};
  std::vector<std::uint8_t> rgb = dotImage(K, dots);
  LensWarp warp;
  ASSERT_TRUE(warp.distortRgb(K, lens, &rgb));
  double largest_shift = 0.0;
  for (const Eigen::Vector2i& d : dots) {
    const Eigen::Vector2d n = plumbBob(lens, (d.x() - K.cx) / K.fx, (d.y() - K.cy) / K.fy);
    const Eigen::Vector2d expected(K.fx * n.x() + K.cx, K.fy * n.y() + K.cy);
    largest_shift = std::max(largest_shift, (expected - d.cast<double>()).norm());
    const Eigen::Vector2d seen = centroidNear(K, rgb, expected, 6);
    EXPECT_LT((seen - expected).norm(), 0.3)
        << "dot at " << d.transpose() << ": expected at " << expected.transpose() << ", seen at "
        << seen.transpose();
  }
  EXPECT_GT(largest_shift, 10.0) << "the lens must move the corners' dots by many pixels";
}

TEST(LensWarp, RectifyingUndoesDistortingAndNeverMixesDepths) {
  const PinholeIntrinsics K;
  const LensDistortion lens = LensDistortion::primesense();
  // A step: the left sixth of the image at 0.5 m, the rest at 1.2 m (an edge off the centre:
  // a line through the centre stays straight under a radial distortion).
  std::vector<float> depth(static_cast<std::size_t>(K.width) * K.height);
  for (int v = 0; v < K.height; ++v)
    for (int u = 0; u < K.width; ++u)
      depth[static_cast<std::size_t>(v) * K.width + u] = u < K.width / 6 ? 0.5f : 1.2f;
  const std::vector<float> pinhole = depth;
  LensWarp warp;
  ASSERT_TRUE(warp.distortDepth(K, lens, &depth));
  int changed = 0;
  for (std::size_t i = 0; i < depth.size(); ++i) {
    EXPECT_TRUE(depth[i] == 0.f || depth[i] == 0.5f || depth[i] == 1.2f) << "a mixed depth";
    changed += depth[i] != pinhole[i];
  }
  EXPECT_GT(changed, 1000) << "the step's edge must bend";
  ASSERT_TRUE(warp.rectifyDepth(K, lens, &depth));
  int agree = 0, valid = 0;
  for (std::size_t i = 0; i < depth.size(); ++i) {
    if (depth[i] == 0.f) continue;
    ++valid;
    agree += depth[i] == pinhole[i];
  }
  // The round trip loses only the rim whose rays the raw image does not see, and moves the edge
  // by at most a pixel (two nearest-pixel look-ups).
  EXPECT_GT(valid, static_cast<int>(0.9 * depth.size()));
  EXPECT_GT(agree, valid - 2 * K.height);
}

TEST(LensWarp, RectifiedDotsAreBackWhereThePinholeModelPutsThem) {
  const PinholeIntrinsics K;
  const LensDistortion lens = LensDistortion::primesense();
  const std::vector<Eigen::Vector2i> dots = {{320, 240}, {120, 100}, {520, 380}, {560, 90}};
  std::vector<std::uint8_t> rgb = dotImage(K, dots);
  LensWarp warp;
  ASSERT_TRUE(warp.distortRgb(K, lens, &rgb));
  // The grey image of the raw frame (the red channel), rectified as the visual odometry does.
  std::vector<std::uint8_t> grey(static_cast<std::size_t>(K.width) * K.height);
  for (std::size_t i = 0; i < grey.size(); ++i) grey[i] = rgb[i * 3];
  ASSERT_TRUE(warp.rectifyGrey(K, lens, &grey));
  for (std::size_t i = 0; i < grey.size(); ++i) rgb[i * 3] = grey[i];
  for (const Eigen::Vector2i& d : dots) {
    const Eigen::Vector2d seen = centroidNear(K, rgb, d.cast<double>(), 6);
    EXPECT_LT((seen - d.cast<double>()).norm(), 0.35) << "dot at " << d.transpose();
  }
}

TEST(LensWarp, NoDistortionLeavesImagesAsTheyAreAndBadInputIsRefused) {
  const PinholeIntrinsics K;
  std::vector<float> depth(static_cast<std::size_t>(K.width) * K.height, 0.8f);
  depth[12345] = 0.f;
  const std::vector<float> before = depth;
  LensWarp warp;
  EXPECT_TRUE(warp.rectifyDepth(K, LensDistortion{}, &depth));
  const LensDistortion zeros{{0, 0, 0, 0, 0}};
  const LensDistortion three{{0.1, 0.2, 0.3}};
  EXPECT_TRUE(warp.rectifyDepth(K, zeros, &depth));
  EXPECT_EQ(depth, before);
  EXPECT_FALSE(warp.rectifyDepth(K, three, &depth));  // 3 coefficients
  const LensDistortion nan{{NAN, 0, 0, 0, 0}};
  EXPECT_FALSE(warp.rectifyDepth(K, nan, &depth));
  std::vector<float> small(100, 0.8f);
  EXPECT_FALSE(warp.rectifyDepth(K, LensDistortion::primesense(), &small));  // not K's size
  EXPECT_EQ(depth, before);
  EXPECT_EQ(small, std::vector<float>(100, 0.8f));
  EXPECT_FALSE(three.problem().empty());
  EXPECT_TRUE(LensDistortion::primesense().problem().empty());
  EXPECT_EQ(LensDistortion{}.describe(), "none");
}

}  // namespace
}  // namespace geofusion
