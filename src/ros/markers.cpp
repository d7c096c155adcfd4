#include "geofusion/ros/markers.h"

#include "geofusion/core/class_palette.h"
#include "geofusion/ros/conversions.h"

#include <cstdio>

namespace geofusion {

namespace {
std_msgs::ColorRGBA color(float r, float g, float b, float a = 1.f) {
  std_msgs::ColorRGBA c;
  c.r = r;
  c.g = g;
  c.b = b;
  c.a = a;
  return c;
}

visualization_msgs::Marker makeMarker(const std_msgs::Header& header, const char* ns, int id,
                                      int type) {
  visualization_msgs::Marker m;
  m.header = header;
  m.ns = ns;
  m.id = id;
  m.type = type;
  m.action = visualization_msgs::Marker::ADD;
  m.pose.orientation.w = 1.0;
  return m;
}

geometry_msgs::Point point(const Eigen::Vector3d& p) {
  geometry_msgs::Point q;
  q.x = p.x();
  q.y = p.y();
  q.z = p.z();
  return q;
}
}  // namespace

visualization_msgs::MarkerArray detectionMarkers(const std::vector<WorldDetection>& detections,
                                                 const std_msgs::Header& header,
                                                 double axis_length_m) {
  visualization_msgs::MarkerArray out;
  visualization_msgs::Marker clear;
  clear.header = header;
  clear.action = visualization_msgs::Marker::DELETEALL;
  out.markers.push_back(clear);

  for (std::size_t i = 0; i < detections.size(); ++i) {
    const WorldDetection& d = detections[i];
    const Rgb rgb = classColor(d.measurement.class_name);

    const int id = static_cast<int>(i);
    visualization_msgs::Marker sphere =
        makeMarker(header, kDetectionNs, id, visualization_msgs::Marker::SPHERE);
    sphere.pose = toPoseMsg(d.T_world_obj);
    sphere.scale.x = sphere.scale.y = sphere.scale.z = 0.4 * axis_length_m;
    sphere.color = color(rgb.r, rgb.g, rgb.b, 0.9f);
    out.markers.push_back(sphere);

    visualization_msgs::Marker axes =
        makeMarker(header, kDetectionAxesNs, id, visualization_msgs::Marker::LINE_LIST);
    axes.pose = toPoseMsg(d.T_world_obj);
    axes.scale.x = 0.08 * axis_length_m;  // line width
    const std_msgs::ColorRGBA axis_colors[3] = {color(1, 0, 0), color(0, 1, 0), color(0, 0, 1)};
    for (int a = 0; a < 3; ++a) {
      axes.points.push_back(point(Eigen::Vector3d::Zero()));
      axes.points.push_back(point(axis_length_m * Eigen::Vector3d::Unit(a)));
      axes.colors.push_back(axis_colors[a]);
      axes.colors.push_back(axis_colors[a]);
    }
    out.markers.push_back(axes);

    visualization_msgs::Marker label =
        makeMarker(header, kDetectionLabelNs, id, visualization_msgs::Marker::TEXT_VIEW_FACING);
    label.pose.position =
        point(d.T_world_obj.translation() + Eigen::Vector3d(0, 0, 1.5 * axis_length_m));
    label.scale.z = 0.5 * axis_length_m;
    label.color = color(1, 1, 1);
    char text[128];
    std::snprintf(text, sizeof(text), "%s %.2f", d.measurement.class_name.c_str(),
                  d.measurement.score);
    label.text = text;
    out.markers.push_back(label);
  }
  return out;
}

}  // namespace geofusion
