#include "geofusion/model/mesh.h"
#include "geofusion/model/surface_features.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace geofusion {
namespace {

std::vector<double> sortedEdgeLengths(const SurfaceFeatures& f) {
  std::vector<double> out;
  for (const auto& c : f.curves) {
    if (c.radius_m == 0.0) out.push_back(c.length());
  }
  std::sort(out.begin(), out.end());
  return out;
}

const PlaneFeature* planeAlong(const SurfaceFeatures& f, const Eigen::Vector3d& n,
                               double cos_tol = 0.98) {
  for (const auto& p : f.planes) {
    if (p.normal.dot(n) > cos_tol) return &p;
  }
  return nullptr;
}

TEST(SurfaceFeatures, BoxGivesSixPlanesAndTwelveEdges) {
  const Eigen::Vector3d size(0.1, 0.2, 0.3);
  const SurfaceFeatures f = extractSurfaceFeatures(makeBox(size));
  ASSERT_EQ(f.planes.size(), 6u) << describe(f);
  ASSERT_EQ(f.curves.size(), 12u) << describe(f);
  for (int axis = 0; axis < 3; ++axis) {
    for (double sign : {-1.0, 1.0}) {
      const Eigen::Vector3d n = sign * Eigen::Vector3d::Unit(axis);
      const PlaneFeature* p = planeAlong(f, n, 0.9999);
      ASSERT_NE(p, nullptr) << "no plane along " << n.transpose();
      EXPECT_LT((p->center - 0.5 * size[axis] * n).norm(), 1e-6);
      const double area = size.prod() / size[axis];
      EXPECT_NEAR(p->area_m2, area, 1e-7);  // float vertices
      EXPECT_EQ(p->boundary.size(), 4u);
    }
  }
  const std::vector<double> lengths = sortedEdgeLengths(f);
  const std::vector<double> expected = {0.1, 0.1, 0.1, 0.1, 0.2, 0.2, 0.2, 0.2, 0.3, 0.3, 0.3, 0.3};
  for (std::size_t i = 0; i < 12; ++i) EXPECT_NEAR(lengths[i], expected[i], 1e-6);
  // Each edge lies on the box surface: |coordinates| at the half sizes on two axes.
  for (const auto& c : f.curves) {
    const Eigen::Vector3d rel = c.center.cwiseAbs().cwiseQuotient(0.5 * size);
    EXPECT_EQ((rel.array() > 0.999).count(), 2) << c.center.transpose();
  }
}

TEST(SurfaceFeatures, CylinderGivesTwoPlanesAndOneCurvedSurface) {
  const SurfaceFeatures f = extractSurfaceFeatures(makeCylinder(0.04, 0.12));
  ASSERT_EQ(f.planes.size(), 2u) << describe(f);
  ASSERT_EQ(f.curves.size(), 1u) << describe(f);
  const CurvedFeature& side = f.curves[0];
  EXPECT_NEAR(side.radius_m, 0.04, 1e-6);
  EXPECT_NEAR(std::abs(side.axis.z()), 1.0, 1e-9);
  EXPECT_NEAR(side.length(), 0.12, 1e-6);
  EXPECT_LT(side.center.norm(), 1e-6);
  ASSERT_NE(planeAlong(f, Eigen::Vector3d::UnitZ()), nullptr);
  ASSERT_NE(planeAlong(f, -Eigen::Vector3d::UnitZ()), nullptr);
  EXPECT_NEAR(planeAlong(f, Eigen::Vector3d::UnitZ())->center.z(), 0.06, 1e-6);
}

class YcbFeatures : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!test::haveYcb()) GTEST_SKIP() << "YCB-Video models not found at " << test::ycbDir();
  }
  SurfaceFeatures features(const std::string& name, Eigen::Vector3f* extents) {
    TriangleMesh mesh;
    std::string error;
    EXPECT_TRUE(loadMesh(test::ycbDir() + "/" + name + "/textured.obj", &mesh, &error)) << error;
    *extents = mesh.extents();
    return extractSurfaceFeatures(mesh);
  }
};

TEST_F(YcbFeatures, BoxesGiveSixPlanesWhereTheirExtentsSay) {
  for (const char* name : {"003_cracker_box", "004_sugar_box", "061_foam_brick"}) {
    Eigen::Vector3f ext;
    const SurfaceFeatures f = features(name, &ext);
    EXPECT_EQ(f.planes.size(), 6u) << name << ": " << describe(f);
    for (int axis = 0; axis < 3; ++axis) {
      const PlaneFeature* top = planeAlong(f, Eigen::Vector3d::Unit(axis), 0.97);
      const PlaneFeature* bottom = planeAlong(f, -Eigen::Vector3d::Unit(axis), 0.97);
      ASSERT_TRUE(top && bottom) << name << " axis " << axis << ": " << describe(f);
      // Opposite faces are the object's extent apart along their normal (scanned faces bulge a
      // few millimetres, and the extent is taken at the bulge).
      EXPECT_NEAR((top->center - bottom->center)[axis], ext[axis], 0.008) << name;
    }
    EXPECT_GE(sortedEdgeLengths(f).size(), 8u) << name << ": " << describe(f);
  }
}

TEST_F(YcbFeatures, CansGiveTwoPlanesAndASideOfTheirRadius) {
  for (const char* name : {"005_tomato_soup_can", "007_tuna_fish_can"}) {
    Eigen::Vector3f ext;
    const SurfaceFeatures f = features(name, &ext);
    EXPECT_EQ(f.planes.size(), 2u) << name << ": " << describe(f);
    std::vector<CurvedFeature> sides;
    for (const auto& c : f.curves) {
      if (c.radius_m > 0) sides.push_back(c);
    }
    ASSERT_EQ(sides.size(), 1u) << name << ": " << describe(f);
    const double radius = 0.25 * (ext.x() + ext.y());
    EXPECT_NEAR(sides[0].radius_m, radius, 0.003) << name;
    EXPECT_GT(std::abs(sides[0].axis.z()), 0.99) << name;
    EXPECT_NEAR(sides[0].length(), ext.z(), 0.006) << name;
  }
}

}  // namespace
}  // namespace geofusion
