#include "geofusion/ros/tf_lookup.h"

#include <ros/ros.h>
#include <tf2_eigen/tf2_eigen.h>

namespace geofusion {

bool lookupTransformWallTimeout(const tf2_ros::Buffer& buffer, const std::string& target_frame,
                                const std::string& source_frame, const ros::Time& stamp,
                                double timeout_s, Eigen::Isometry3d* T_target_source,
                                std::string* error) {
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(timeout_s);
  std::string why;
  while (!buffer.canTransform(target_frame, source_frame, stamp, &why)) {
    if (ros::WallTime::now() >= deadline || !ros::ok()) {
      if (error) *error = why;
      return false;
    }
    ros::WallDuration(0.002).sleep();
  }
  try {
    *T_target_source =
        tf2::transformToEigen(buffer.lookupTransform(target_frame, source_frame, stamp));
  } catch (const tf2::TransformException& e) {
    if (error) *error = e.what();
    return false;
  }
  return true;
}

}  // namespace geofusion
