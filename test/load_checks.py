#!/usr/bin/python3
"""rostest node for load.test: hair_sim_node under a teleoperation load (issue 8).

head_driver broadcasts the head at 1 kHz (its ~rate); latency_probe, run for ~seconds s by
scripts/bench_node.py's window(), publishes Wind at WIND_RATE (1 kHz, a slowly turning 3 m/s wind in the
world frame, every message different, on an absolute schedule from its own thread), counts /tf, and
measures the outputs as a C++ viewer receives them; the node's CPU share is taken over the same window. (The
load comes from C++: a Python publisher and counter at 1 kHz each took much of one of the host's two cores
from the node they were loading.)

  rate       hair_markers and hair_state messages per second received
  latency    receipt time minus header.stamp (the stamp of the newest head tf the output reflects; head_driver
             stamps tf when it sends it): tf sent -> output received, p50 / p99 / max
  node       the node's own status line ("tf arrival -> output sent X ms mean Y ms max", every 5 s) on
             /rosout: the worst mean and the largest max over the window
  input      /tf messages per second received and Wind messages sent over the window (the load's premise)

test_load asserts that both outputs keep publish_rate within RATE_TOLERANCE (10 %), that the input rates
reached INPUT_FRACTION of 1 kHz (else the test did not load the node as asked), and that the node logged no
ERROR. With ~max_p99_ms > 0 it also asserts both outputs' p99 latency at or below it (`./run.sh load`: 5 ms,
issue 8's target); at 0 (CTest's 12 s run, which shares the machine with the other tests) the latency is
measured and reported only. The figures go to the log and, as one JSON object, to ~out when it is set.

Private parameters: seconds (measuring window, 12), publish_rate (30), node (/hair_sim), out (''),
max_p99_ms (0: not asserted).
"""
import json
import os
import re
import sys
import threading
import time
import unittest

try:
    from xmlrpc.client import ServerProxy
except ImportError:  # pragma: no cover
    from xmlrpclib import ServerProxy

import rosgraph
import roslib.packages
import rospy
import rostest
from rosgraph_msgs.msg import Log

# scripts/bench_node.py: the measuring window (latency_probe + CPU) shared with ./run.sh bench.
sys.path.insert(0, os.path.join(os.path.dirname(os.path.realpath(__file__)), '..', 'scripts'))
import bench_node  # noqa: E402

PKG = 'hair_sim'
NAME = 'load_checks'

WIND_RATE = 1000.0  # Hz
INPUT_FRACTION = 0.9  # of 1 kHz, tf and Wind
RATE_TOLERANCE = 0.10  # of publish_rate
STATUS = re.compile(r'tf arrival -> output sent ([0-9.]+) ms mean ([0-9.]+) ms max')


class LoadChecks(unittest.TestCase):
    lock = threading.Lock()
    status = []  # (mean ms, max ms) from the node's status lines
    errors = []

    @classmethod
    def setUpClass(cls):
        rospy.init_node(NAME)
        cls.seconds = float(rospy.get_param('~seconds', 12.0))
        cls.publish_rate = float(rospy.get_param('~publish_rate', 30.0))
        cls.node = rospy.get_param('~node', '/hair_sim')
        cls.out = rospy.get_param('~out', '')
        cls.max_p99_ms = float(rospy.get_param('~max_p99_ms', 0.0))
        cls.recording = False
        rospy.Subscriber('/rosout', Log, cls.on_log, queue_size=1000)

    @classmethod
    def on_log(cls, msg):
        if msg.name != cls.node:
            return
        with cls.lock:
            if msg.level >= Log.ERROR:
                cls.errors.append(msg.msg)
            m = STATUS.search(msg.msg)
            if m and cls.recording:
                cls.status.append((float(m.group(1)), float(m.group(2))))

    def node_pid(self):
        deadline = time.time() + 30.0
        while time.time() < deadline:
            try:
                uri = rosgraph.Master('/' + NAME).lookupNode(self.node)
                if uri:
                    code, _, pid = ServerProxy(uri).getPid('/' + NAME)
                    if code == 1:
                        return int(pid)
            except (rosgraph.MasterError, IOError):  # not up yet
                pass
            time.sleep(0.2)
        self.fail('%s did not register within 30 s' % self.node)

    def test_load(self):
        pid = self.node_pid()
        probes = roslib.packages.find_node(PKG, 'latency_probe')
        self.assertTrue(probes, 'latency_probe not found (build the hair_sim package)')
        time.sleep(2.0)  # the node starts following the head
        type(self).recording = True
        result = bench_node.window(pid, self.seconds, probes[0], True,
                                   ['_wind_rate:=%g' % WIND_RATE, '_count_tf:=true'])
        type(self).recording = False
        self.assertNotIn('error', result, 'latency_probe: %s' % result.get('error'))
        with self.lock:
            status, errors = list(self.status), list(self.errors)
        tf_rate, wind_rate = result['input']['tf_hz'], result['input']['wind_hz']
        m, s = result['markers'], result['state']
        figures = {
            'seconds': result['seconds'],
            'tf_rate_hz': tf_rate,
            'wind_rate_hz': wind_rate,
            'publish_rate_hz': self.publish_rate,
            'markers_rate_hz': m['rate_hz'],
            'state_rate_hz': s['rate_hz'],
            'markers_latency_ms_p50': m['latency_ms_p50'],
            'markers_latency_ms_p99': m['latency_ms_p99'],
            'markers_latency_ms_max': m['latency_ms_max'],
            'state_latency_ms_p50': s['latency_ms_p50'],
            'state_latency_ms_p99': s['latency_ms_p99'],
            'state_latency_ms_max': s['latency_ms_max'],
            'node_tf_to_output_ms_mean': max([x[0] for x in status]) if status else None,
            'node_tf_to_output_ms_max': max([x[1] for x in status]) if status else None,
            'node_cpu_share': result['cpu_share'],
        }
        rospy.loginfo('%s: %s', NAME, json.dumps(figures))
        if self.out:
            with open(self.out, 'w') as f:
                json.dump(figures, f, indent=1)
                f.write('\n')
        self.assertGreaterEqual(tf_rate, INPUT_FRACTION * 1000.0, 'tf came at %.0f Hz, not 1 kHz' % tf_rate)
        self.assertGreaterEqual(wind_rate, INPUT_FRACTION * WIND_RATE, 'Wind went out at %.0f Hz' % wind_rate)
        for name, rate in (('hair_markers', m['rate_hz']), ('hair_state', s['rate_hz'])):
            self.assertLessEqual(abs(rate - self.publish_rate), RATE_TOLERANCE * self.publish_rate,
                                 '%s at %.2f Hz under load, publish_rate %.0f Hz +- %.0f %%' %
                                 (name, rate, self.publish_rate, 100 * RATE_TOLERANCE))
        self.assertEqual(errors, [], 'the node logged errors: %s' % errors[:3])
        if self.max_p99_ms > 0.0:
            for name, series in (('hair_markers', m), ('hair_state', s)):
                self.assertLessEqual(series['latency_ms_p99'], self.max_p99_ms,
                                     'tf -> %s p99 %.2f ms under load (max %.2f ms), target %.1f ms' %
                                     (name, series['latency_ms_p99'], series['latency_ms_max'], self.max_p99_ms))


if __name__ == '__main__':
    rostest.rosrun(PKG, NAME, LoadChecks, sys.argv)
