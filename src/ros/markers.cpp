#include "geofusion/ros/markers.h"

#include "geofusion/common/class_palette.h"
#include "geofusion/ros/conversions.h"

#include <cstdio>

namespace geofusion {

std_msgs::ColorRGBA colorMsg(float r, float g, float b, float a) {
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

visualization_msgs::Marker deleteAllMarker(const std_msgs::Header& header) {
  visualization_msgs::Marker clear;
  clear.header = header;
  clear.action = visualization_msgs::Marker::DELETEALL;
  return clear;
}

visualization_msgs::MarkerArray detectionMarkers(const std::vector<WorldDetection>& detections,
                                                 const std_msgs::Header& header,
                                                 double axis_length_m) {
  visualization_msgs::MarkerArray out;
  out.markers.push_back(deleteAllMarker(header));

  for (std::size_t i = 0; i < detections.size(); ++i) {
    const WorldDetection& d = detections[i];
    const Rgb rgb = classColor(d.measurement.class_name);

    const int id = static_cast<int>(i);
    visualization_msgs::Marker sphere =
        makeMarker(header, kDetectionNs, id, visualization_msgs::Marker::SPHERE);
    sphere.pose = toPoseMsg(d.T_world_obj);
    sphere.scale.x = sphere.scale.y = sphere.scale.z = 0.4 * axis_length_m;
    sphere.color = colorMsg(rgb.r, rgb.g, rgb.b, 0.9f);
    out.markers.push_back(sphere);

    visualization_msgs::Marker axes =
        makeMarker(header, kDetectionAxesNs, id, visualization_msgs::Marker::LINE_LIST);
    axes.pose = toPoseMsg(d.T_world_obj);
    axes.scale.x = 0.08 * axis_length_m;  // line width
    const std_msgs::ColorRGBA axis_colors[3] = {colorMsg(1, 0, 0), colorMsg(0, 1, 0),
                                                colorMsg(0, 0, 1)};
    for (int a = 0; a < 3; ++a) {
      axes.points.push_back(toPointMsg(Eigen::Vector3d::Zero()));
      axes.points.push_back(toPointMsg(axis_length_m * Eigen::Vector3d::Unit(a)));
      axes.colors.push_back(axis_colors[a]);
      axes.colors.push_back(axis_colors[a]);
    }
    out.markers.push_back(axes);

    visualization_msgs::Marker label =
        makeMarker(header, kDetectionLabelNs, id, visualization_msgs::Marker::TEXT_VIEW_FACING);
    label.pose.position =
        toPointMsg(d.T_world_obj.translation() + Eigen::Vector3d(0, 0, 1.5 * axis_length_m));
    label.scale.z = 0.5 * axis_length_m;
    label.color = colorMsg(1, 1, 1);
    char text[128];
    std::snprintf(text, sizeof(text), "%s %.2f", d.measurement.class_name.c_str(),
                  d.measurement.score);
    label.text = text;
    out.markers.push_back(label);
  }
  return out;
}

}  // namespace geofusion
