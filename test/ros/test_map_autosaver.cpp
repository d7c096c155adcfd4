// Issue 52: the map autosaved every N keyframes or T seconds by a writer thread (map_autosaver.h)
// through map_store's atomic save; a failed save is reported and leaves the previous one whole.
#include "geofusion/estimation/map_store.h"
#include "geofusion/model/object_model.h"
#include "geofusion/ros/map_autosaver.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace geofusion {
namespace {

namespace fs = std::filesystem;

class MapAutosaverTest : public ::testing::Test {
 protected:
  void SetUp() override {
    char pattern[] = "/tmp/geofusion_autosave_XXXXXX";
    ASSERT_NE(::mkdtemp(pattern), nullptr);
    dir = pattern;
    prefix = dir + "/autosave";
  }
  void TearDown() override { fs::remove_all(dir); }

  // A map of `keyframes` keyframes with one object, as the pipeline hands it over.
  RunResults map(int keyframes) const {
    RunResults r;
    r.method = "geofusion";
    r.model_set = models.name();
    r.session = "launch_1";
    r.keyframes_total = keyframes;
    r.next_object_id = 7;
    ObjectEstimate o;
    o.id = 6;
    for (const auto& m : models.models())
      if (m->name == "003_cracker_box") o.model = m;
    o.T_map_obj.translation() = Eigen::Vector3d(0.1 * keyframes, 0.0, 0.8);
    r.final_map.objects.push_back(o);
    return r;
  }
  MapAutosaver::Save save() const {
    return [](const std::string& p, RunResults m, MapFiles* files, std::string* error) {
      return saveMap(p, std::move(m), nullptr, files, error);
    };
  }

  ModelSet models = ModelSet::builtinPrimitives();
  std::string dir, prefix;
};

TEST_F(MapAutosaverTest, DueEveryNKeyframesOrAfterTheTime) {
  MapAutosaver::Config c;
  c.prefix = prefix;
  c.every_keyframes = 3;
  c.every_s = 10.0;
  MapAutosaver saver(c, save());
  EXPECT_FALSE(saver.keyframeAdded(100.0));
  EXPECT_FALSE(saver.keyframeAdded(101.0));
  EXPECT_TRUE(saver.keyframeAdded(102.0));  // the third keyframe
  saver.offer(map(3), 102.0);
  EXPECT_FALSE(saver.keyframeAdded(103.0));  // the count starts again
  EXPECT_TRUE(saver.keyframeAdded(112.5));   // 10 s after the last save, one keyframe later
  saver.flush();
  const MapAutosaver::Status s = saver.status();
  EXPECT_EQ(s.saved, 1u);
  EXPECT_EQ(s.last_keyframes, 3);
  EXPECT_FALSE(s.pending);

  c.every_keyframes = 0;
  c.every_s = 0.0;
  MapAutosaver off(c, save());
  EXPECT_FALSE(off.enabled());
  for (int i = 0; i < 50; ++i) EXPECT_FALSE(off.keyframeAdded(100.0 + 100.0 * i));
}

// The saved map loads back with who saved it, its keyframe count and the next object id; a newer
// snapshot replaces the older one.
TEST_F(MapAutosaverTest, WritesALoadableMap) {
  MapAutosaver::Config c;
  c.prefix = prefix;
  MapAutosaver saver(c, save());
  saver.offer(map(10), 1.0);
  saver.offer(map(20), 2.0);
  saver.flush();
  RunResults loaded;
  std::string error;
  ASSERT_TRUE(loadMap(prefix, models, &loaded, nullptr, &error)) << error;
  EXPECT_EQ(loaded.keyframes_total, saver.status().last_keyframes);
  EXPECT_EQ(loaded.session, "launch_1");
  EXPECT_EQ(loaded.next_object_id, 7);
  ASSERT_EQ(loaded.final_map.objects.size(), 1u);
  EXPECT_EQ(loaded.final_map.objects[0].id, 6);
  std::string session;
  bool exists = false;
  ASSERT_TRUE(readSavedMapSession(prefix + ".yaml", &session, &exists, &error)) << error;
  EXPECT_TRUE(exists);
  EXPECT_EQ(session, "launch_1");
  EXPECT_FALSE(readSavedMapSession(dir + "/none", &session, &exists, &error));
  EXPECT_FALSE(exists);
}

// A save that cannot be written (here the temporary file's path is taken by a folder, as an
// unwritable folder would refuse it) is counted with its reason; the previous autosave stays
// whole and loads; the next save that can be written clears the error.
TEST_F(MapAutosaverTest, AFailedSaveIsReportedAndThePreviousOneStaysWhole) {
  MapAutosaver::Config c;
  c.prefix = prefix;
  MapAutosaver saver(c, save());
  saver.offer(map(10), 1.0);
  saver.flush();
  ASSERT_EQ(saver.status().saved, 1u);
  fs::create_directory(prefix + ".yaml.tmp");
  saver.offer(map(20), 2.0);
  saver.flush();
  MapAutosaver::Status s = saver.status();
  EXPECT_EQ(s.failed, 1u);
  EXPECT_NE(s.last_error.find("cannot write"), std::string::npos) << s.last_error;
  EXPECT_EQ(s.last_keyframes, 10);
  RunResults loaded;
  std::string error;
  ASSERT_TRUE(loadMap(prefix, models, &loaded, nullptr, &error)) << error;
  EXPECT_EQ(loaded.keyframes_total, 10);
  EXPECT_NEAR(loaded.final_map.objects.at(0).T_map_obj.translation().x(), 1.0, 1e-9);
  fs::remove_all(prefix + ".yaml.tmp");
  saver.offer(map(30), 3.0);
  saver.flush();
  s = saver.status();
  EXPECT_EQ(s.saved, 2u);
  EXPECT_TRUE(s.last_error.empty()) << s.last_error;
  EXPECT_EQ(s.last_keyframes, 30);
}

// Stopping writes the snapshot still waiting (a shutdown between two autosaves loses nothing).
TEST_F(MapAutosaverTest, StoppingWritesWhatWaits) {
  {
    MapAutosaver::Config c;
    c.prefix = prefix;
    MapAutosaver saver(c, save());
    saver.offer(map(5), 1.0);
  }
  RunResults loaded;
  std::string error;
  ASSERT_TRUE(loadMap(prefix, models, &loaded, nullptr, &error)) << error;
  EXPECT_EQ(loaded.keyframes_total, 5);
}

// Only the launch that wrote an autosave continues it: a respawn (same launch id) does, a new
// launch or a node without a launch id does not; a corrupt autosave is said to be unreadable.
TEST_F(MapAutosaverTest, OnlyTheLaunchThatWroteItResumes) {
  std::string session, error;
  EXPECT_EQ(autosaveResume(prefix, "launch_1", &session, &error), AutosaveResume::kNone);
  MapAutosaver::Config c;
  c.prefix = prefix;
  {
    MapAutosaver saver(c, save());
    saver.offer(map(4), 1.0);
  }
  EXPECT_EQ(autosaveResume(prefix, "launch_1", &session, &error), AutosaveResume::kResume);
  EXPECT_EQ(autosaveResume(prefix, "launch_2", &session, &error), AutosaveResume::kOtherLaunch);
  EXPECT_EQ(session, "launch_1");
  EXPECT_EQ(autosaveResume(prefix, "", &session, &error), AutosaveResume::kOtherLaunch);
  std::ofstream(prefix + ".yaml") << "map: [unclosed";
  EXPECT_EQ(autosaveResume(prefix, "launch_1", &session, &error), AutosaveResume::kUnreadable);
  EXPECT_FALSE(error.empty());
}

}  // namespace
}  // namespace geofusion
