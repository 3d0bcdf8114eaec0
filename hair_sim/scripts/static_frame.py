#!/usr/bin/env python3
"""Broadcasts one static tf (latched on /tf_static), like tf2_ros' static_transform_publisher, which
Debian's ROS does not ship. Private parameters: parent, child (frames), x, y, z (m), yaw (rad). A missing
or bad parameter stops the node with a message naming it and its value (exit status 1)."""
import math
import sys

import rospy
import tf2_ros
from geometry_msgs.msg import TransformStamped


def frame(name, default=None):
    """A tf frame name: a non-empty string without spaces or a leading '/'."""
    if default is None and not rospy.has_param(name):
        raise ValueError("parameter %s is required (a tf frame name)" % name)
    value = rospy.get_param(name, default)
    if not isinstance(value, str) or not value or value.startswith("/") or any(c.isspace() for c in value):
        raise ValueError("parameter %s: %r is not a valid tf frame name (non-empty, no spaces, no leading '/')"
                         % (name, value))
    return value


def number(name):
    """A finite number (default 0)."""
    value = rospy.get_param(name, 0.0)
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError("parameter %s: %r must be a finite number" % (name, value))
    return float(value)


def main():
    rospy.init_node("static_frame")
    try:
        t = TransformStamped()
        t.header.stamp = rospy.Time.now()
        t.header.frame_id = frame("~parent", "world")
        t.child_frame_id = frame("~child")
        if t.child_frame_id == t.header.frame_id:
            raise ValueError("parameters ~parent and ~child are both %r: a frame cannot be its own parent"
                             % t.child_frame_id)
        t.transform.translation.x = number("~x")
        t.transform.translation.y = number("~y")
        t.transform.translation.z = number("~z")
        yaw = number("~yaw")
    except ValueError as e:
        rospy.logfatal("static_frame: %s", e)
        sys.exit(1)
    t.transform.rotation.z = math.sin(yaw / 2.0)
    t.transform.rotation.w = math.cos(yaw / 2.0)
    broadcaster = tf2_ros.StaticTransformBroadcaster()
    broadcaster.sendTransform(t)
    rospy.loginfo("static_frame: %s -> %s at (%.3f, %.3f, %.3f), yaw %.3f", t.header.frame_id, t.child_frame_id,
                  t.transform.translation.x, t.transform.translation.y, t.transform.translation.z, yaw)
    rospy.spin()


if __name__ == "__main__":
    main()
