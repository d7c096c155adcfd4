// TF look-ups that never block longer than a wall-clock timeout. (tf2_ros::Buffer's own timeout
// counts ROS time: under /use_sim_time with a paused or finished bag it would wait forever.)
#pragma once

#include <ros/time.h>
#include <tf2_ros/buffer.h>
#include <Eigen/Geometry>

#include <string>

namespace geofusion {

/// T_target_source at `stamp`, waiting up to `timeout_s` wall-clock seconds for it to arrive.
/// On failure returns false and says why in `error`.
bool lookupTransformWallTimeout(const tf2_ros::Buffer& buffer, const std::string& target_frame,
                                const std::string& source_frame, const ros::Time& stamp,
                                double timeout_s, Eigen::Isometry3d* T_target_source,
                                std::string* error);

}  // namespace geofusion
