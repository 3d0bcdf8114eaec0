/// hair_sim_node: animates hair strips on a head that moves in tf; see README.md.
#include <ros/ros.h>

#include <exception>

#include "hair_sim/ros/HairSimNode.hpp"

int main(int argc, char** argv) {
  ros::init(argc, argv, "hair_sim");
  // The handles outlive a failing constructor, so that roscpp is still up to print ROS_FATAL.
  ros::NodeHandle nh;
  ros::NodeHandle private_nh("~");
  try {
    hair_sim::HairSimNode node(nh, private_nh);
    ros::spin();
  } catch (const std::exception& e) {
    ROS_FATAL("hair_sim: %s", e.what());
    return 1;
  }
  return 0;
}
