// Dense-clutter tabletop scenes: objects dropped onto a table and settled with a physics engine
// (Bullet), checked for interpenetration with FCL, with their ground-truth contact graph.
#pragma once

#include "geofusion/estimation/contacts.h"
#include "geofusion/model/collision.h"
#include "geofusion/model/object_model.h"

#include <Eigen/Geometry>

#include <memory>
#include <string>
#include <vector>

namespace geofusion {

struct TableSpec {
  double height_m = 0.75;  ///< top surface, world z (world: z up, origin on the floor)
  double size_x_m = 1.2;
  double size_y_m = 0.8;
  double thickness_m = 0.04;
  /// The table as an object model (a box; its top plane supports the bottom layer). Model frame
  /// at the box centre.
  ObjectModel model() const;
  Eigen::Isometry3d pose() const;  ///< T_world_table (box centre)
};

struct SceneObject {
  std::shared_ptr<const ObjectModel> model;
  Eigen::Isometry3d T_world_obj = Eigen::Isometry3d::Identity();
  /// A changed scene (SceneSpec::removed, ::moved): the camera frames the object is there,
  /// [present_from_frame, present_until_frame); -1: to the end. A moved object is two objects,
  /// one until the change and one from it.
  int present_from_frame = 0;
  int present_until_frame = -1;
  bool presentAt(int frame) const {
    return frame >= present_from_frame && (present_until_frame < 0 || frame < present_until_frame);
  }
  bool presentAtTheEnd() const { return present_until_frame < 0; }
};

struct ClutterConfig {
  int num_objects = 12;    ///< objects to place (duplicates allowed)
  double area_x_m = 0.40;  ///< drop area on the table, centred
  double area_y_m = 0.30;
  double stack_fraction = 0.3;   ///< share of objects dropped onto another object
  double lying_fraction = 0.35;  ///< share dropped lying on a side rather than upright
  /// Share set down beside an object, standing and tipped towards it, to come to rest leaning
  /// on it (or fall flat, as physics decides).
  double lean_fraction = 0.0;
  /// Classes to draw from (empty: the whole model set).
  std::vector<std::string> classes;
  double max_penetration_m = 0.001;  ///< FCL check; larger fails the scene
  /// Pairs closer than this count as touching in the contact graph (physics leaves a sub-mm gap).
  double touch_distance_m = 0.004;
};

struct ClutterScene {
  TableSpec table;
  std::vector<SceneObject> objects;
  /// Feature contacts; object index -1 is the table. Support contacts (plane normal within the
  /// support cone) and side contacts (support == false) of touching pairs.
  std::vector<FeatureContact> contacts;
  double max_penetration_m = 0.0;  ///< deepest pair interpenetration found by FCL
  int dropped_off_table = 0;       ///< objects that fell off while settling and were re-dropped
};

/// Builds a settled scene, deterministic for a seed. False (with `report` saying why) when the
/// model set is empty or the scene could not be settled within the penetration bound.
bool makeClutterScene(const ModelSet& models, const ClutterConfig& config, unsigned seed,
                      ClutterScene* scene, std::string* report);

/// FCL: deepest interpenetration between any two objects, or an object and the table (convex
/// hulls of the models), metres; 0 when nothing overlaps. `pair` receives the pair (-1 = table).
double maxPenetration(const ClutterScene& scene, std::pair<int, int>* pair = nullptr);

/// FCL: distance between two objects' convex hulls (-1 = the table); 0 when they overlap.
double hullDistance(const ClutterScene& scene, int a, int b);

/// The ground-truth contact graph of the scene's current poses (FCL gate + feature contacts).
std::vector<FeatureContact> groundTruthContacts(const ClutterScene& scene,
                                                const ClutterConfig& config);

}  // namespace geofusion
