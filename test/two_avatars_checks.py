#!/usr/bin/python3
"""rostest node for two_avatars.test: two hair_sim nodes side by side (avatar1 at y = +0.4 m, avatar2 at
y = -0.4 m in world).

  test_each_avatar_has_its_own_hair
      For avatar1 and avatar2: /<avatar>/hair_state arrives within 30 s, in frame <avatar>/base; its
      control points, taken to world through tf, have their centroid within 0.25 m of the avatar's head
      (world -> <avatar>/head) and on the avatar's side (y of the right sign, |y| > 0.2 m); diagnostics
      come from /<avatar>/hair_sim.
"""
import os
import sys
import threading
import time
import unittest

import rospy
import rostest
import tf2_ros
from diagnostic_msgs.msg import DiagnosticArray
from hair_sim_msgs.msg import HairState

# Shared geometry (this folder is not on sys.path when catkin's relay runs the script).
sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
from hair_test_geometry import Pose, mat_vec, strip_points  # noqa: E402

PKG = 'hair_sim'
NAME = 'two_avatars_checks'
AVATARS = {'avatar1': 0.4, 'avatar2': -0.4}


class TwoAvatars(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node(NAME)

    def test_each_avatar_has_its_own_hair(self):
        lock = threading.Lock()
        states = {}
        names = set()

        def on_state(msg, avatar):
            with lock:
                states[avatar] = msg

        for avatar in AVATARS:
            rospy.Subscriber('/%s/hair_state' % avatar, HairState, on_state, avatar, queue_size=1)
        rospy.Subscriber('/diagnostics', DiagnosticArray, lambda m: names.update(s.name for s in m.status),
                         queue_size=10)
        buffer = tf2_ros.Buffer()
        tf2_ros.TransformListener(buffer)
        deadline = time.time() + 30.0
        while True:
            with lock:
                if len(states) == len(AVATARS):
                    break
            self.assertLess(time.time(), deadline, 'hair_state only from %s' % sorted(states))
            time.sleep(0.1)
        time.sleep(1.0)
        for avatar, y in AVATARS.items():
            with lock:
                state = states[avatar]
            self.assertEqual(state.header.frame_id, '%s/base' % avatar)
            base = Pose.from_msg(buffer.lookup_transform('world', state.header.frame_id, rospy.Time(0),
                                                         rospy.Duration(5.0)))
            head = buffer.lookup_transform('world', '%s/head' % avatar, rospy.Time(0), rospy.Duration(5.0))
            points = [[a + b for a, b in zip(mat_vec(base.r, (p.x, p.y, p.z)), base.t)]
                      for s in state.strips for p in strip_points(s)]
            centroid = [sum(p[i] for p in points) / len(points) for i in range(3)]
            h = head.transform.translation
            distance = sum((c - v) ** 2 for c, v in zip(centroid, (h.x, h.y, h.z))) ** 0.5
            rospy.loginfo('%s: %s: hair centroid %s, head %.3f %.3f %.3f, distance %.3f m', NAME, avatar,
                          ['%.3f' % c for c in centroid], h.x, h.y, h.z, distance)
            self.assertLess(distance, 0.25)
            self.assertGreater(centroid[1] * y, 0.0)
            self.assertGreater(abs(centroid[1]), 0.2)
        deadline = time.time() + 5.0
        while not all('%s/hair_sim: simulated rate' % a in names for a in AVATARS):
            self.assertLess(time.time(), deadline, 'diagnostics names: %s' % sorted(names))
            time.sleep(0.1)


if __name__ == '__main__':
    rostest.rosrun(PKG, NAME, TwoAvatars, sys.argv)
