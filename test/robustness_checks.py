#!/usr/bin/python3
"""rostest node for robustness.test: bad input to a running hair_sim_node (issue 8).

The script broadcasts world -> head at 100 Hz itself (a thread; the head at [0, 0, 1.6]) and, one case at
a time, slips bad input in. After each case the node must still publish hair_state, every point finite
and every root within 0.15 m of the head's origin (the hair sits on the head it follows), and /rosout must
carry a warning of the node that names what was wrong:

  1 NaN translation         -> "transform.translation.x is nan"
  2 infinite rotation       -> "transform.rotation.z is inf"
  3 zero quaternion         -> "zero quaternion"
  4 non-unit quaternion     -> "normalised" (the pose is taken: the hair follows a turn given as norm 2)
  5 NaN Wind, unknown frame -> "velocity.x is nan", "header.frame_id 'nowhere' is unknown"
  6 stale head (tf stops 1.5 s, max_tf_age 0.5 s) -> "s old (max_tf_age", hair_state keeps coming
  7 teleport (2 m sideways, turned 2 rad, at once) -> "jumped", and the hair moves with the head: the
    tips in head coordinates move less than 5 cm, no point is left more than 0.6 m from the head.

Private parameters: node (default /hair_sim).
"""
import math
import sys
import threading
import time
import unittest

import rospy
import rostest
import tf2_ros
from geometry_msgs.msg import TransformStamped
from hair_sim_msgs.msg import HairState, Wind
from rosgraph_msgs.msg import Log

PKG = 'hair_sim'
NAME = 'robustness_checks'
HEAD = (0.0, 0.0, 1.6)


def quat_yaw(yaw):
    return (0.0, 0.0, math.sin(0.5 * yaw), math.cos(0.5 * yaw))


def rotate_yaw(p, yaw):
    c, s = math.cos(yaw), math.sin(yaw)
    return (c * p[0] - s * p[1], s * p[0] + c * p[1], p[2])


class Robustness(unittest.TestCase):
    lock = threading.Lock()
    states = []
    logs = []
    head = {'xyz': HEAD, 'q': (0.0, 0.0, 0.0, 1.0), 'paused': False, 'bad': None}

    @classmethod
    def setUpClass(cls):
        rospy.init_node(NAME)
        cls.node = rospy.get_param('~node', '/hair_sim')
        cls.broadcaster = tf2_ros.TransformBroadcaster()
        rospy.Subscriber('hair_state', HairState, cls.on_state, queue_size=50)
        rospy.Subscriber('/rosout', Log, cls.on_log, queue_size=1000)
        cls.wind_pub = rospy.Publisher('wind', Wind, queue_size=10)
        cls.stop = threading.Event()
        cls.thread = threading.Thread(target=cls.broadcast)
        cls.thread.daemon = True
        cls.thread.start()

    @classmethod
    def tearDownClass(cls):
        cls.stop.set()

    @classmethod
    def on_state(cls, msg):
        with cls.lock:
            cls.states.append(msg)

    @classmethod
    def on_log(cls, msg):
        if msg.name == cls.node and msg.level >= Log.WARN:
            with cls.lock:
                cls.logs.append(msg.msg)

    @classmethod
    def broadcast(cls):
        while not cls.stop.is_set() and not rospy.is_shutdown():
            with cls.lock:
                xyz, q, paused, bad = cls.head['xyz'], cls.head['q'], cls.head['paused'], cls.head['bad']
                cls.head['bad'] = None
            if not paused:
                t = TransformStamped()
                t.header.stamp = rospy.Time.now()
                t.header.frame_id = 'world'
                t.child_frame_id = 'head'
                t.transform.translation.x, t.transform.translation.y, t.transform.translation.z = xyz
                (t.transform.rotation.x, t.transform.rotation.y, t.transform.rotation.z,
                 t.transform.rotation.w) = q
                if bad is not None:
                    bad(t)
                cls.broadcaster.sendTransform(t)
            time.sleep(0.01)

    # -- helpers
    def send_bad(self, change, times=3):
        for _ in range(times):
            with self.lock:
                self.head['bad'] = change
            time.sleep(0.05)

    def wait_log(self, text, timeout=5.0):
        deadline = time.time() + timeout
        while time.time() < deadline:
            with self.lock:
                found = [m for m in self.logs if text in m]
            if found:
                return found[0]
            time.sleep(0.05)
        with self.lock:
            seen = list(self.logs)
        self.fail('no warning of %s containing %r within %.0f s; it said: %s' % (self.node, text, timeout, seen))

    def fresh_states(self, count=10, timeout=5.0):
        with self.lock:
            start = len(self.states)
        deadline = time.time() + timeout
        while time.time() < deadline:
            with self.lock:
                if len(self.states) >= start + count:
                    return self.states[start:start + count]
            time.sleep(0.02)
        self.fail('fewer than %d hair_state messages within %.0f s' % (count, timeout))

    def assert_sane(self, states, head=None):
        head = head or self.head['xyz']
        for msg in states:
            for strip in msg.strips:
                for p in strip.points:
                    self.assertTrue(all(math.isfinite(v) for v in (p.x, p.y, p.z)), 'a non-finite point')
                for p in strip.points[:strip.columns]:  # the roots, on the scalp
                    d = math.sqrt((p.x - head[0]) ** 2 + (p.y - head[1]) ** 2 + (p.z - head[2]) ** 2)
                    self.assertLess(d, 0.15, 'a root %.3f m from the head' % d)

    def tips_in_head(self, msg, head, yaw):
        out = []
        for strip in msg.strips:
            p = strip.points[-1]
            out.append(rotate_yaw((p.x - head[0], p.y - head[1], p.z - head[2]), -yaw))
        return out

    # -- cases, in order
    def test_0_starts(self):
        self.assert_sane(self.fresh_states(10, 30.0))

    def test_1_nan_translation(self):
        def nan(t):
            t.transform.translation.x = float('nan')
        self.send_bad(nan)
        self.wait_log('transform.translation.x is nan')
        self.assert_sane(self.fresh_states())

    def test_2_infinite_rotation(self):
        def inf(t):
            t.transform.rotation.z = float('inf')
        self.send_bad(inf)
        self.wait_log('transform.rotation.z is inf')
        self.assert_sane(self.fresh_states())

    def test_3_zero_quaternion(self):
        def zero(t):
            t.transform.rotation.x = t.transform.rotation.y = t.transform.rotation.z = t.transform.rotation.w = 0.0
        self.send_bad(zero)
        self.wait_log('zero quaternion')
        self.assert_sane(self.fresh_states())

    def test_4_non_unit_quaternion(self):
        # Norm 2, a 0.5 rad turn: taken, normalised; the hair turns with the head.
        q = quat_yaw(0.5)
        with self.lock:
            self.head['q'] = tuple(2.0 * v for v in q)
        self.wait_log('normalised')
        self.assert_sane(self.fresh_states())
        with self.lock:
            self.head['q'] = (0.0, 0.0, 0.0, 1.0)
        time.sleep(1.0)

    def test_5_bad_wind(self):
        w = Wind()
        w.velocity.x = float('nan')
        for _ in range(3):
            self.wind_pub.publish(w)
            time.sleep(0.05)
        self.wait_log('velocity.x is nan')
        w = Wind()
        w.header.frame_id = 'nowhere'
        w.velocity.x = 3.0
        for _ in range(3):
            self.wind_pub.publish(w)
            time.sleep(0.05)
        self.wait_log("header.frame_id 'nowhere' is unknown")
        self.assert_sane(self.fresh_states())

    def test_6_stale_head(self):
        with self.lock:
            self.head['paused'] = True
        time.sleep(0.3)
        states = self.fresh_states(30, 3.0)  # 30 Hz goes on without tf
        self.wait_log('s old (max_tf_age', 3.0)
        self.assert_sane(states)
        with self.lock:
            self.head['paused'] = False
        self.assert_sane(self.fresh_states())

    def test_7_teleport(self):
        time.sleep(2.5)  # the hair settles
        before = self.fresh_states(1)[0]
        old_head = self.head['xyz']
        new_head = (old_head[0], old_head[1] + 2.0, old_head[2])
        with self.lock:
            self.head['xyz'] = new_head
            self.head['q'] = quat_yaw(2.0)
        self.wait_log('jumped')
        time.sleep(0.2)
        after = self.fresh_states(1)[0]
        self.assert_sane([after], new_head)
        tips_before = self.tips_in_head(before, old_head, 0.0)
        tips_after = self.tips_in_head(after, new_head, 2.0)
        moved = max(math.sqrt(sum((a - b) ** 2 for a, b in zip(p, q))) for p, q in zip(tips_before, tips_after))
        rospy.loginfo('%s: teleport: tips moved %.4f m in head coordinates', NAME, moved)
        self.assertLess(moved, 0.05, 'tips moved %.3f m in head coordinates across the teleport' % moved)
        for strip in after.strips:
            for p in strip.points:
                d = math.sqrt((p.x - new_head[0]) ** 2 + (p.y - new_head[1]) ** 2 + (p.z - new_head[2]) ** 2)
                self.assertLess(d, 0.6, 'a point %.2f m from the teleported head' % d)


if __name__ == '__main__':
    rostest.rosrun(PKG, NAME, Robustness, sys.argv)
