// rviz markers for the package's views.
#pragma once

#include "geofusion/estimation/frame_by_frame.h"

#include <std_msgs/Header.h>
#include <visualization_msgs/MarkerArray.h>

#include <vector>

namespace geofusion {

/// A marker to ADD: header, namespace, id, type, identity orientation.
visualization_msgs::Marker makeMarker(const std_msgs::Header& header, const char* ns, int id,
                                      int type);
std_msgs::ColorRGBA colorMsg(float r, float g, float b, float a = 1.f);
/// The DELETEALL that starts every marker array of a view (nothing from the last one lingers).
visualization_msgs::Marker deleteAllMarker(const std_msgs::Header& header);

/// Marker namespaces of the frame-by-frame view.
constexpr const char* kDetectionNs = "detections";             ///< SPHERE at each object origin
constexpr const char* kDetectionAxesNs = "detection_axes";     ///< LINE_LIST x/y/z axes (r/g/b)
constexpr const char* kDetectionLabelNs = "detection_labels";  ///< TEXT "class score"

/// One frame's detections: a DELETEALL first (so the previous frame's markers never linger), then
/// per detection i a class-coloured sphere, its axes and a label, all with id i, in header's frame.
visualization_msgs::MarkerArray detectionMarkers(const std::vector<WorldDetection>& detections,
                                                 const std_msgs::Header& header,
                                                 double axis_length_m);

}  // namespace geofusion
