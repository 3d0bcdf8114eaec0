#!/usr/bin/python3
"""hair_sim_node with use_sim_time and a looping rosbag of tf: its outputs carry the bag's time, and
when the bag loops (time goes backwards) the node starts again instead of stalling or exploding."""
import math
import time
import unittest

import rosbag
import rospy
import rostest
from hair_sim_msgs.msg import HairState
from visualization_msgs.msg import MarkerArray


class SimTimeBag(unittest.TestCase):
    def setUp(self):
        with rosbag.Bag(rospy.get_param('~bag')) as bag:
            self.bag_start = bag.get_start_time()
            self.bag_end = bag.get_end_time()
        self.states = []
        self.markers = []
        rospy.Subscriber('hair_state', HairState, lambda m: self.states.append(m))
        rospy.Subscriber('hair_markers', MarkerArray, lambda m: self.markers.append(m))

    def wait_for(self, condition, timeout):
        deadline = time.time() + timeout
        while time.time() < deadline and not rospy.is_shutdown():
            if condition():
                return True
            time.sleep(0.05)
        return condition()

    def test_outputs_follow_the_bag_clock_across_a_loop(self):
        span = self.bag_end - self.bag_start
        self.assertTrue(self.wait_for(lambda: len(self.states) > 0, 20.0), 'no hair_state on simulated time')

        def backwards():
            stamps = [m.header.stamp.to_sec() for m in list(self.states)]
            return sum(1 for a, b in zip(stamps, stamps[1:]) if b < a - 1.0)

        # Until the bag has looped and the state followed it back, and a second of states after that:
        # at most three loops of the bag in wall time (a loaded machine plays it late).
        self.wait_for(lambda: backwards() >= 1, 3.0 * span + 5.0)
        self.wait_for(lambda: False, 1.0)
        stamps = [m.header.stamp.to_sec() for m in self.states]
        self.assertGreater(len(stamps), 30)
        for t in stamps:  # stamped with the bag's (simulated) time, never wall time
            self.assertGreaterEqual(t, self.bag_start - 1e-3)
            self.assertLessEqual(t, self.bag_end + 1e-3)
        backwards = backwards()
        self.assertGreaterEqual(backwards, 1, 'the bag looped, the state must have followed it back')
        # After each restart the hair is sane: every point finite and near the head (within 1 m).
        for m in self.states[-10:]:
            for strip in m.strips:
                v = strip.xyz  # x, y, z per point
                for x, y, z in zip(v[0::3], v[1::3], v[2::3]):
                    self.assertTrue(all(math.isfinite(c) for c in (x, y, z)))
                    self.assertLess(math.sqrt(x ** 2 + y ** 2 + (z - 1.6) ** 2), 1.0)
        self.assertGreater(len(self.markers), 0)
        marker_stamp = self.markers[-1].markers[0].header.stamp.to_sec()
        self.assertTrue(self.bag_start - 1e-3 <= marker_stamp <= self.bag_end + 1e-3)


if __name__ == '__main__':
    rospy.init_node('sim_time_bag')
    rostest.rosrun('hair_sim', 'sim_time_bag', SimTimeBag)
