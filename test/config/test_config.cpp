// The one configuration loader: nested keys into the modules' Config structs, type and range
// checks that name the file, the key and what is allowed, unknown keys with the nearest known key,
// and the effective configuration printed back.
#include "geofusion/config/config.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <set>
#include <string>

namespace geofusion {
namespace {

bool contains(const std::vector<std::string>& lines, const std::string& a,
              const std::string& b = "", const std::string& c = "") {
  for (const std::string& l : lines)
    if (l.find(a) != std::string::npos && l.find(b) != std::string::npos &&
        l.find(c) != std::string::npos)
      return true;
  return false;
}

std::string joined(const std::vector<std::string>& lines) {
  std::string out;
  for (const auto& l : lines) out += l + "\n";
  return out;
}

TEST(Config, TheTableIsSound) {
  // Every key bound to its own field, and every default inside its own allowed range.
  GeoFusionConfig c;
  std::set<void*> fields;
  std::set<std::string> keys;
  for (const Setting& s : settings()) {
    EXPECT_TRUE(keys.insert(s.key).second) << s.key << " listed twice";
    EXPECT_TRUE(fields.insert(s.field(c)).second) << s.key << " shares its field with another key";
    EXPECT_FALSE(s.doc.empty()) << s.key;
    if (s.type == Setting::Type::kDouble || s.type == Setting::Type::kInt) {
      const double v = configNumber(s, c);
      EXPECT_GE(v, s.min) << s.key;
      EXPECT_LE(v, s.max) << s.key;
    }
  }
  EXPECT_GT(settings().size(), 100u);
}

TEST(Config, DefaultsPrintAndReadBackUnchanged) {
  const GeoFusionConfig defaults;
  for (bool comments : {false, true}) {
    GeoFusionConfig back;
    ConfigReport report;
    ASSERT_TRUE(loadConfigText(configYaml(defaults, false, comments), "printed", &back, &report))
        << joined(report.errors);
    EXPECT_TRUE(report.warnings.empty()) << joined(report.warnings);
    EXPECT_EQ(configDiff(back), "defaults");
  }
  EXPECT_EQ(configYaml(defaults, true), "");
}

TEST(Config, NestedKeysReachTheModulesStructs) {
  GeoFusionConfig c;
  ConfigReport report;
  ASSERT_TRUE(loadConfigText(R"(
method: R-Front
model_set: {name: ycb_video, dir: /data/ycb}
association:
  eps_fp: 0.4
  joint_assignment: false
stage_one:
  window_keyframes: 42
  measurement_loss: {type: cauchy, scale: 1.5}
consistency:
  inlier: {centre: 0.7}
relations:
  gravity: [0, 0, -2]
visual_odometry:
  features: 800
)",
                             "test.yaml", &c, &report))
      << joined(report.errors);
  EXPECT_TRUE(report.warnings.empty()) << joined(report.warnings);
  EXPECT_EQ(c.method, "rfront");
  EXPECT_EQ(c.estimator.method, Method::kRobustFrontEnd);
  EXPECT_EQ(c.model_set.name, "ycb_video");
  EXPECT_EQ(c.model_set.dir, "/data/ycb");
  EXPECT_DOUBLE_EQ(c.estimator.association.eps_fp, 0.4);
  EXPECT_FALSE(c.estimator.association.joint_assignment);
  EXPECT_EQ(c.estimator.stage_one.window_keyframes, 42);
  EXPECT_EQ(c.estimator.stage_one.measurement_loss.type, "cauchy");
  EXPECT_DOUBLE_EQ(c.estimator.stage_one.measurement_loss.scale, 1.5);
  EXPECT_DOUBLE_EQ(c.estimator.consistency.inlier.centre, 0.7);
  EXPECT_TRUE(c.estimator.gravity.isApprox(Eigen::Vector3d(0, 0, -1)));  // normalised
  EXPECT_EQ(c.visual_odometry.features, 800);
  // Untouched settings keep their defaults.
  EXPECT_DOUBLE_EQ(c.estimator.association.eps_new, AssociationConfig().eps_new);
  const std::string diff = configDiff(c);
  EXPECT_NE(diff.find("association.eps_fp: 0.4 (default 0.55)"), std::string::npos) << diff;
  EXPECT_NE(diff.find("stage_one.window_keyframes: 42 (default 30)"), std::string::npos) << diff;
}

TEST(Config, UnknownKeysAreWarnedWithTheNearestKnownKey) {
  GeoFusionConfig c;
  ConfigReport report;
  ASSERT_TRUE(
      loadConfigText("association: {eps_fb: 0.3}\neps_fp: 0.2\nstage_two: {bogus_thing: 1}\n",
                     "user.yaml", &c, &report));
  EXPECT_TRUE(contains(report.warnings, "user.yaml", "association.eps_fb: unknown",
                       "did you mean association.eps_fp?"))
      << joined(report.warnings);
  // A flat key of the old parameter files: where it lives now.
  EXPECT_TRUE(contains(report.warnings, "eps_fp: unknown", "did you mean association.eps_fp?"))
      << joined(report.warnings);
  EXPECT_TRUE(contains(report.warnings, "stage_two.bogus_thing: unknown"))
      << joined(report.warnings);
  EXPECT_DOUBLE_EQ(c.estimator.association.eps_fp, AssociationConfig().eps_fp);  // not applied
}

TEST(Config, BadValuesAreErrorsNamingFileKeyAndAllowedRange) {
  struct Case {
    std::string yaml, key, allowed;
  };
  const Case cases[] = {
      {"association: {eps_fp: 3}", "association.eps_fp", "[0.001, 1]"},
      {"stage_one: {max_iterations: 2.5}", "stage_one.max_iterations", "an integer"},
      {"consistency: {eps_res: abc}", "consistency.eps_res", "a number"},
      {"method: orbslam", "method", "one of geofusion, rfront, bslam, fbf, fbfr"},
      {"association: {joint_assignment: maybe}", "association.joint_assignment", "true or false"},
      {"relations: {gravity: [0, 0]}", "relations.gravity", "[x, y, z]"},
      {"stage_two: {contact_loss: {type: l1}}", "stage_two.contact_loss.type", "huber"},
  };
  for (const Case& k : cases) {
    GeoFusionConfig c;
    ConfigReport report;
    EXPECT_FALSE(loadConfigText(k.yaml, "bad.yaml", &c, &report)) << k.yaml;
    EXPECT_TRUE(contains(report.errors, "bad.yaml", k.key, k.allowed)) << joined(report.errors);
    EXPECT_EQ(configDiff(c), "defaults") << "a failed load changed the configuration";
  }
  ConfigReport report;
  GeoFusionConfig c;
  EXPECT_FALSE(loadConfigFile("/nonexistent/params.yaml", &c, &report));
  EXPECT_TRUE(contains(report.errors, "/nonexistent/params.yaml", "cannot read"));
  EXPECT_FALSE(loadConfigText("[1, 2]", "list.yaml", &c, &report));
}

TEST(Config, SingleValuesAreCheckedLikeTheFile) {
  GeoFusionConfig c;
  std::string error;
  EXPECT_TRUE(setConfigValue("stage_one.every_n_keyframes", "5", &c, &error)) << error;
  EXPECT_EQ(c.estimator.stage_one.every_n_keyframes, 5);
  EXPECT_TRUE(setConfigValue("method", "fbf", &c, &error));
  EXPECT_EQ(c.estimator.method, Method::kFrameByFrame);
  EXPECT_FALSE(setConfigValue("stage_one.every_n_keyframes", "0", &c, &error));
  EXPECT_NE(error.find("[1, 100]"), std::string::npos) << error;
  EXPECT_FALSE(setConfigValue("association.eps_fb", "0.1", &c, &error));
  EXPECT_NE(error.find("did you mean association.eps_fp?"), std::string::npos) << error;
  const Setting* s = findReconfigurable("eps_fp");
  ASSERT_NE(s, nullptr);
  EXPECT_EQ(s->key, "association.eps_fp");
  EXPECT_TRUE(setConfigNumber(*s, 0.3, &c, &error));
  EXPECT_DOUBLE_EQ(c.estimator.association.eps_fp, 0.3);
  EXPECT_FALSE(setConfigNumber(*s, 0.0, &c, &error));
  EXPECT_DOUBLE_EQ(c.estimator.association.eps_fp, 0.3);
}

TEST(Config, ChangedOnlyPrintsJustTheChanges) {
  GeoFusionConfig c;
  std::string error;
  ASSERT_TRUE(setConfigValue("background.resolution_m", "0.05", &c, &error));
  EXPECT_EQ(configYaml(c, true), "background:\n  resolution_m: 0.05\n");
  EXPECT_EQ(configYaml(c, false, false, {"keyframes"}),
            "keyframes:\n  every_n_frames: 1\n  min_translation_m: 0\n  min_rotation_rad: 0\n");
}

}  // namespace
}  // namespace geofusion
