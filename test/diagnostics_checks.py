#!/usr/bin/python3
"""rostest node for diagnostics.test: hair_sim_node's statuses on /diagnostics.

  test_levels_follow_the_situation
      1. Nobody broadcasts world -> head: 'hair_sim: head tf' is ERROR ("no head pose").
      2. The test broadcasts the head (100 Hz): within 10 s all five statuses (simulated rate, step time,
         head tf, penetration, inputs) are OK, with the rate within 10 % of 240 substeps/s and a tf age
         below 0.25 s.
      3. Three Wind messages with a NaN velocity: 'inputs' becomes WARN (3 dropped, below the ERROR
         threshold 10) within 3 s, then OK again in a later window.
      4. The broadcast stops: 'head tf' turns WARN or ERROR within 4 s; the hair goes on with the head held
         where it was last seen (~max_tf_age 0.5 s), so 'simulated rate' is OK again within 4 s.
"""
import sys
import threading
import time
import unittest

import rospy
import rostest
import tf2_ros
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import TransformStamped
from hair_sim_msgs.msg import Wind

PKG = 'hair_sim'
NAME = 'diagnostics_checks'
PREFIX = 'hair_sim: '
TASKS = ('simulated rate', 'step time', 'head tf', 'penetration', 'inputs')


class DiagnosticsChecks(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node(NAME)

    def setUp(self):
        self.lock = threading.Lock()
        self.latest = {}  # task -> (receive time, DiagnosticStatus)
        rospy.Subscriber('/diagnostics', DiagnosticArray, self.on_diagnostics, queue_size=10)
        self.wind_pub = rospy.Publisher('wind', Wind, queue_size=10)
        self.broadcasting = threading.Event()
        self.stop = threading.Event()

    def tearDown(self):
        self.stop.set()

    def on_diagnostics(self, msg):
        with self.lock:
            for s in msg.status:
                if s.name.startswith(PREFIX):
                    self.latest[s.name[len(PREFIX):]] = (time.time(), s)

    def status(self, task, since=0.0):
        with self.lock:
            entry = self.latest.get(task)
        return entry[1] if entry and entry[0] > since else None

    def values(self, status):
        return {kv.key: kv.value for kv in status.values}

    def wait_level(self, task, levels, timeout, since=None):
        since = time.time() if since is None else since
        deadline = time.time() + timeout
        while True:
            s = self.status(task, since)
            if s is not None and s.level in levels:
                return s
            self.assertLess(time.time(), deadline, "'%s' not in levels %s within %.0f s; last: %s" %
                            (task, levels, timeout, None if s is None else (s.level, s.message)))
            time.sleep(0.05)

    def broadcast_head(self):
        broadcaster = tf2_ros.TransformBroadcaster()
        rate = rospy.Rate(100.0)
        while not self.stop.is_set() and not rospy.is_shutdown():
            if self.broadcasting.is_set():
                t = TransformStamped()
                t.header.stamp = rospy.Time.now()
                t.header.frame_id = 'world'
                t.child_frame_id = 'head'
                t.transform.translation.z = 1.6
                t.transform.rotation.w = 1.0
                broadcaster.sendTransform(t)
            try:
                rate.sleep()
            except rospy.ROSInterruptException:
                return

    def test_levels_follow_the_situation(self):
        thread = threading.Thread(target=self.broadcast_head)
        thread.daemon = True
        thread.start()
        # 1. No tf.
        s = self.wait_level('head tf', [DiagnosticStatus.ERROR], 30.0, since=0.0)
        rospy.loginfo('%s: without tf: %s', NAME, s.message)
        self.assertIn('no head pose', s.message)

        # 2. Running.
        self.broadcasting.set()
        start = time.time() + 1.5  # a window that begins after the first poses
        for task in TASKS:
            s = self.wait_level(task, [DiagnosticStatus.OK], 10.0, since=start)
            rospy.loginfo('%s: running: %s: %s', NAME, task, s.message)
        rate = float(self.values(self.status('simulated rate'))['simulated substeps per second'])
        self.assertLess(abs(rate - 240.0), 24.0)
        age = float(self.values(self.status('head tf'))['tf age s'])
        self.assertLess(age, 0.25)
        self.assertEqual(int(self.values(self.status('penetration'))['control points inside a body']), 0)

        # 3. Dropped inputs.
        bad = Wind()
        bad.velocity.x = float('nan')
        time.sleep(0.5)  # the publisher connects
        sent = time.time()
        for _ in range(3):
            self.wind_pub.publish(bad)
            time.sleep(0.05)
        s = self.wait_level('inputs', [DiagnosticStatus.WARN], 3.0, since=sent)
        rospy.loginfo('%s: NaN wind: %s', NAME, s.message)
        self.assertGreaterEqual(int(self.values(s)['dropped since start']), 3)
        self.assertIn('velocity.x is nan', s.message)
        self.wait_level('inputs', [DiagnosticStatus.OK], 4.0)

        # 4. tf stops.
        self.broadcasting.clear()
        stopped = time.time()
        s = self.wait_level('head tf', [DiagnosticStatus.WARN, DiagnosticStatus.ERROR], 4.0, since=stopped)
        rospy.loginfo('%s: tf stopped: %s', NAME, s.message)
        s = self.wait_level('simulated rate', [DiagnosticStatus.OK], 4.0, since=stopped + 1.5)
        rospy.loginfo('%s: tf stopped, head held: %s', NAME, s.message)


if __name__ == '__main__':
    rostest.rosrun(PKG, NAME, DiagnosticsChecks, sys.argv)
