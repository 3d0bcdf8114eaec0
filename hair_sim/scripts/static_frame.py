#!/usr/bin/env python3
"""Broadcasts one static tf (latched on /tf_static), like tf2_ros' static_transform_publisher, which
Debian's ROS does not ship. Private parameters: parent, child (frames), x, y, z (m), yaw (rad)."""
import math

import rospy
import tf2_ros
from geometry_msgs.msg import TransformStamped


def main():
    rospy.init_node("static_frame")
    t = TransformStamped()
    t.header.stamp = rospy.Time.now()
    t.header.frame_id = rospy.get_param("~parent", "world")
    t.child_frame_id = rospy.get_param("~child")
    t.transform.translation.x = float(rospy.get_param("~x", 0.0))
    t.transform.translation.y = float(rospy.get_param("~y", 0.0))
    t.transform.translation.z = float(rospy.get_param("~z", 0.0))
    yaw = float(rospy.get_param("~yaw", 0.0))
    t.transform.rotation.z = math.sin(yaw / 2.0)
    t.transform.rotation.w = math.cos(yaw / 2.0)
    broadcaster = tf2_ros.StaticTransformBroadcaster()
    broadcaster.sendTransform(t)
    rospy.loginfo("static_frame: %s -> %s at (%.3f, %.3f, %.3f), yaw %.3f", t.header.frame_id, t.child_frame_id,
                  t.transform.translation.x, t.transform.translation.y, t.transform.translation.z, yaw)
    rospy.spin()


if __name__ == "__main__":
    main()
