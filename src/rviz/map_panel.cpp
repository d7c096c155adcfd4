#include "map_panel.h"

#include "geofusion/ros/map_inspection.h"

#include <geofusion/SaveMap.h>
#include <visualization_msgs/MarkerArray.h>
#include <pluginlib/class_list_macros.hpp>

#include <QHBoxLayout>
#include <QHeaderView>
#include <QLabel>
#include <QLineEdit>
#include <QPushButton>
#include <QScrollBar>
#include <QTableWidget>
#include <QVBoxLayout>

#include <algorithm>
#include <cmath>

namespace geofusion {
namespace {

constexpr const char* kDefaultTopic = "/scene_estimator/object_map";
// Rows the tables show without scrolling: at least the first, at most the second.
constexpr int kObjectRows[] = {6, 12};
constexpr int kContactRows[] = {4, 8};

QTableWidget* makeTable(const QStringList& headers, QWidget* parent) {
  auto* table = new QTableWidget(0, headers.size(), parent);
  table->setHorizontalHeaderLabels(headers);
  table->setSelectionBehavior(QAbstractItemView::SelectRows);
  table->setSelectionMode(QAbstractItemView::SingleSelection);
  table->setEditTriggers(QAbstractItemView::NoEditTriggers);
  table->verticalHeader()->setVisible(false);
  table->horizontalHeader()->setSectionResizeMode(QHeaderView::ResizeToContents);
  table->horizontalHeader()->setStretchLastSection(true);
  return table;
}

// A table as tall as its rows, between min_rows and max_rows of them (a scroll bar beyond): the
// panel shows what there is at a glance and gives the rest of its height to the other table.
void fitRows(QTableWidget* table, int min_rows, int max_rows) {
  const int rows = std::clamp(table->rowCount(), min_rows, max_rows);
  const int chrome = table->horizontalHeader()->sizeHint().height() + 2 * table->frameWidth() +
                     table->horizontalScrollBar()->sizeHint().height();
  table->setMinimumHeight(chrome + rows * table->verticalHeader()->defaultSectionSize());
}

void setRow(QTableWidget* table, int row, const QStringList& cells) {
  for (int c = 0; c < cells.size(); ++c) table->setItem(row, c, new QTableWidgetItem(cells[c]));
}

// The estimator's save_map next to its object_map topic.
std::string saveService(const std::string& map_topic) {
  const auto slash = map_topic.find_last_of('/');
  return (slash == std::string::npos ? std::string() : map_topic.substr(0, slash + 1)) + "save_map";
}

}  // namespace

MapPanel::MapPanel(QWidget* parent) : rviz::Panel(parent) {
  topic_ = new QLineEdit(kDefaultTopic);
  objects_ =
      makeTable({"id", "class", "state", "seen", "σ pos mm", "σ rot deg", "take", "free"}, this);
  contacts_ = makeTable({"a", "b", "kind", "type", "gap mm"}, this);
  save_path_ = new QLineEdit(QString::fromStdString(
      std::string(std::getenv("HOME") ? std::getenv("HOME") : "/tmp") + "/geofusion_map"));
  save_button_ = new QPushButton("Save map");
  status_ = new QLabel("no map yet");
  status_->setWordWrap(true);

  auto* topic_row = new QHBoxLayout;
  topic_row->addWidget(new QLabel("ObjectMap topic:"));
  topic_row->addWidget(topic_);
  auto* save_row = new QHBoxLayout;
  save_row->addWidget(save_path_);
  save_row->addWidget(save_button_);
  auto* layout = new QVBoxLayout;
  layout->addLayout(topic_row);
  layout->addWidget(new QLabel("Objects (select one to highlight it and its contacts)"));
  layout->addWidget(objects_, 3);
  layout->addWidget(new QLabel("Contacts"));
  layout->addWidget(contacts_, 2);
  fitRows(objects_, kObjectRows[0], kObjectRows[1]);
  fitRows(contacts_, kContactRows[0], kContactRows[1]);
  layout->addLayout(save_row);
  layout->addWidget(status_);
  setLayout(layout);
  setMinimumWidth(480);  // the tables' columns readable in rviz's dock

  connect(topic_, &QLineEdit::editingFinished, this, &MapPanel::subscribe);
  connect(objects_, &QTableWidget::itemSelectionChanged, this, &MapPanel::onObjectRowChanged);
  connect(save_button_, &QPushButton::clicked, this, &MapPanel::onSaveClicked);
  connect(this, &MapPanel::saveFinished, this, &MapPanel::showSaveResult, Qt::QueuedConnection);

  selection_pub_ =
      nh_.advertise<visualization_msgs::MarkerArray>("geofusion_panel/selection", 1, true);
  select_sub_ = nh_.subscribe("geofusion_panel/select", 5, &MapPanel::onSelect, this);
  subscribe();
}

MapPanel::~MapPanel() {
  if (save_thread_.joinable()) save_thread_.join();
}

void MapPanel::load(const rviz::Config& config) {
  rviz::Panel::load(config);
  QString topic, path;
  if (config.mapGetString("Topic", &topic)) topic_->setText(topic);
  if (config.mapGetString("Save path", &path)) save_path_->setText(path);
  subscribe();
}

void MapPanel::save(rviz::Config config) const {
  rviz::Panel::save(config);
  config.mapSetValue("Topic", topic_->text());
  config.mapSetValue("Save path", save_path_->text());
}

void MapPanel::subscribe() {
  const std::string topic = topic_->text().trimmed().toStdString();
  if (!map_sub_ || map_sub_.getTopic() != ros::names::resolve(topic)) {
    map_sub_ = topic.empty() ? ros::Subscriber() : nh_.subscribe(topic, 1, &MapPanel::onMap, this);
    // The plan beside the map (~scene_graph): the removal order and the free objects.
    graph_.reset();
    graph_sub_ = topic.empty() ? ros::Subscriber()
                               : nh_.subscribe(sceneGraphTopicFor(ros::names::resolve(topic)), 1,
                                               &MapPanel::onGraph, this);
    status_->setText(QString("waiting for %1").arg(QString::fromStdString(topic)));
  }
}

void MapPanel::onMap(const geofusion::ObjectMap::ConstPtr& map) {
  map_ = map;
  fillObjects();
  fillContacts();
  selection_pub_.publish(selectionMarkers(*map_, selected_));  // the selection follows the map
  status_->setText(QString("%1 objects (%2 tentative), %3 contacts")
                       .arg(map_->objects.size())
                       .arg(map_->tentative.size())
                       .arg(map_->contacts.size()));
}

void MapPanel::onGraph(const geofusion::SceneGraph::ConstPtr& graph) {
  graph_ = graph;
  if (map_) fillObjects();
}

void MapPanel::fillObjects() {
  filling_ = true;
  objects_->setRowCount(static_cast<int>(map_->objects.size() + map_->tentative.size()));
  int row = 0;
  for (const auto* list : {&map_->objects, &map_->tentative}) {
    for (const auto& o : *list) {
      const PoseSpread spread = poseSpread(o);
      const PlanCells plan = graph_ ? planCells(*graph_, o.id) : PlanCells();
      setRow(
          objects_, row,
          {QString::number(o.id), QString::fromStdString(o.class_name),
           o.state == geofusion::MapObject::STATE_CONFIRMED ? "confirmed" : "tentative",
           QString::number(o.num_measurements), QString::number(1000.0 * spread.position_m, 'f', 1),
           QString::number(spread.rotation_rad * 180.0 / M_PI, 'f', 1),
           QString::fromStdString(plan.take), QString::fromStdString(plan.free)});
      if (o.id == selected_) objects_->selectRow(row);
      ++row;
    }
  }
  if (!findObject(*map_, selected_)) objects_->clearSelection();
  fitRows(objects_, kObjectRows[0], kObjectRows[1]);
  filling_ = false;
}

void MapPanel::fillContacts() {
  contacts_->setRowCount(static_cast<int>(map_->contacts.size()));
  int row = 0;
  for (const auto& c : map_->contacts) {
    setRow(contacts_, row,
           {c.object_a == 0 ? "table" : QString::number(c.object_a), QString::number(c.object_b),
            QString::fromStdString(contactKindName(c.kind)),
            QString::fromStdString(contactTypeName(c.type)),
            QString::number(std::round(1e4 * c.distance_residual_m) / 10.0 + 0.0, 'f', 1)});
    const bool involved = selected_ != 0 && (c.object_a == selected_ || c.object_b == selected_);
    for (int col = 0; col < contacts_->columnCount(); ++col)
      contacts_->item(row, col)->setBackground(involved ? QBrush(QColor(255, 230, 80, 120))
                                                        : QBrush());
    ++row;
  }
  fitRows(contacts_, kContactRows[0], kContactRows[1]);
}

void MapPanel::onObjectRowChanged() {
  if (filling_ || !map_) return;
  const auto rows = objects_->selectionModel()->selectedRows();
  select(rows.empty() ? 0 : objects_->item(rows.front().row(), 0)->text().toUInt());
}

void MapPanel::onSelect(const std_msgs::UInt32::ConstPtr& id) {
  select(id->data);
  if (map_) fillObjects();
}

void MapPanel::select(uint32_t id) {
  selected_ = id;
  if (!map_) return;
  fillContacts();
  selection_pub_.publish(selectionMarkers(*map_, selected_));
}

void MapPanel::onSaveClicked() {
  if (save_thread_.joinable()) save_thread_.join();
  const std::string service =
      saveService(ros::names::resolve(topic_->text().trimmed().toStdString()));
  geofusion::SaveMap srv;
  srv.request.path = save_path_->text().trimmed().toStdString();
  save_button_->setEnabled(false);
  status_->setText(QString("saving through %1 ...").arg(QString::fromStdString(service)));
  save_thread_ = std::thread([this, service, srv]() mutable {
    const bool called = ros::service::call(service, srv);
    Q_EMIT saveFinished(
        called && srv.response.success,
        QString::fromStdString(called ? srv.response.message : "cannot call " + service));
  });
}

void MapPanel::showSaveResult(bool ok, const QString& message) {
  save_button_->setEnabled(true);
  status_->setText((ok ? "saved: " : "not saved: ") + message);
}

}  // namespace geofusion

PLUGINLIB_EXPORT_CLASS(geofusion::MapPanel, rviz::Panel)
