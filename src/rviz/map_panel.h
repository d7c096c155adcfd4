// geofusion/MapPanel, an rviz panel (rviz's Panel API): the objects of the estimator's map
// (id, class, state, keyframes seen, pose spread, and from the scene graph beside the map topic
// their place in the removal order and whether they are free to pick) and their contacts in two
// tables; selecting an
// object highlights it and its contacts in the 3D view (MarkerArray geofusion_panel/selection,
// made by map_inspection.h); a button calls the estimator's save_map. An id on
// geofusion_panel/select (std_msgs/UInt32, 0 clears) selects from outside (tools, tests).
#pragma once

#include <geofusion/ObjectMap.h>
#include <geofusion/SceneGraph.h>
#include <ros/ros.h>
#include <rviz/panel.h>
#include <std_msgs/UInt32.h>

#include <QString>

#include <cstdint>
#include <thread>

class QLabel;
class QLineEdit;
class QPushButton;
class QTableWidget;

namespace geofusion {

class MapPanel : public rviz::Panel {
  Q_OBJECT

 public:
  explicit MapPanel(QWidget* parent = nullptr);
  ~MapPanel() override;

  void load(const rviz::Config& config) override;
  void save(rviz::Config config) const override;

 Q_SIGNALS:
  void saveFinished(bool ok, const QString& message);

 private Q_SLOTS:
  void subscribe();
  void onObjectRowChanged();
  void onSaveClicked();
  void showSaveResult(bool ok, const QString& message);

 private:
  // ROS callbacks: rviz spins the global queue in its GUI thread, so they may touch widgets.
  void onMap(const geofusion::ObjectMap::ConstPtr& map);
  void onSelect(const std_msgs::UInt32::ConstPtr& id);
  void onGraph(const geofusion::SceneGraph::ConstPtr& graph);
  void fillObjects();
  void fillContacts();
  void select(uint32_t id);

  ros::NodeHandle nh_;
  ros::Subscriber map_sub_, select_sub_, graph_sub_;
  ros::Publisher selection_pub_;
  geofusion::ObjectMap::ConstPtr map_;
  geofusion::SceneGraph::ConstPtr graph_;  ///< the plan, when the estimator publishes one
  uint32_t selected_ = 0;                  // 0: none
  bool filling_ = false;                   // the tables are being refilled: no selection events
  std::thread save_thread_;

  QLineEdit* topic_ = nullptr;
  QTableWidget* objects_ = nullptr;
  QTableWidget* contacts_ = nullptr;
  QLineEdit* save_path_ = nullptr;
  QPushButton* save_button_ = nullptr;
  QLabel* status_ = nullptr;
};

}  // namespace geofusion
