#!/usr/bin/python3
"""rostest node for hair_display.test (first test): what the rviz display needs, and what it saves.

  test_a_state_carries_the_strips    hair_state carries, per strip of the hairstyle file (in its order), the
                                     grid size (columns, rows), the hair length and the colour, and
                                     columns x rows finite control points: all HairDisplay needs to
                                     tessellate and colour the strips.
  test_b_state_much_smaller          Serialized size (the bytes on the wire, rospy.AnyMsg) of hair_state and
                                     of hair_markers at the node's default level of detail, mean over
                                     SAMPLES messages of each: hair_state must be at least MIN_RATIO times
                                     smaller. Prints both sizes, the ratio and the bandwidth at the
                                     messages' rate (the README's numbers come from here).

Private parameters: config_file (required: the hairstyle is read from it).
"""
import math
import os
import sys
import threading
import time
import unittest

import rospy
import rostest
from hair_sim_msgs.msg import HairState

sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
from hair_test_geometry import load_config  # noqa: E402

PKG = 'hair_sim'
NAME = 'hair_state_size'

MIN_RATIO = 30.0
SAMPLES = 30
TIMEOUT = 40.0  # s, for the first messages (the node waits for the head's tf)
COLOUR_TOLERANCE = 1e-6  # float32 in the message


class HairStateSize(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node(NAME)

    def setUp(self):
        self.hairstyle = load_config(rospy.get_param('~config_file'))[1]
        self.lock = threading.Lock()

    def wait_for(self, condition, timeout, what):
        end = time.time() + timeout
        while time.time() < end and not rospy.is_shutdown():
            with self.lock:
                if condition():
                    return
            time.sleep(0.05)
        self.fail('timed out after %.0f s waiting for %s' % (timeout, what))

    def test_a_state_carries_the_strips(self):
        states = []
        sub = rospy.Subscriber('hair_state', HairState, lambda m: states.append(m) if not states else None,
                               queue_size=1)
        self.wait_for(lambda: states, TIMEOUT, 'a hair_state message')
        sub.unregister()
        msg = states[0]
        strips = self.hairstyle['strips']
        self.assertEqual(len(msg.strips), len(strips))
        for i, (got, want) in enumerate(zip(msg.strips, strips)):
            self.assertEqual((got.columns, got.rows), (int(want['columns']), int(want['rows'])), 'strip %d' % i)
            self.assertAlmostEqual(got.hair_length, float(want['hair_length']), places=9, msg='strip %d' % i)
            colour = (got.color.r, got.color.g, got.color.b, got.color.a)
            for c, w in zip(colour, want['color']):
                self.assertAlmostEqual(c, float(w), delta=COLOUR_TOLERANCE, msg='strip %d colour' % i)
            self.assertEqual(len(got.xyz), 3 * got.columns * got.rows, 'strip %d' % i)
            self.assertTrue(all(math.isfinite(v) for v in got.xyz), 'strip %d' % i)

    def test_b_state_much_smaller(self):
        sizes = {'hair_state': [], 'hair_markers': []}
        stamps = {'hair_state': [], 'hair_markers': []}

        def record(msg, topic):
            with self.lock:
                sizes[topic].append(len(msg._buff))
                stamps[topic].append(time.time())

        subs = [rospy.Subscriber(t, rospy.AnyMsg, record, t, queue_size=SAMPLES, buff_size=1 << 24)
                for t in sizes]
        # The first messages after subscribing may be partial transients (a marker tessellated before the
        # subscription was seen): skip 3, then take SAMPLES of each.
        self.wait_for(lambda: all(len(s) >= SAMPLES + 3 for s in sizes.values()), TIMEOUT,
                      '%d messages on hair_state and hair_markers' % (SAMPLES + 3))
        for s in subs:
            s.unregister()
        mean = {t: sum(s[3:SAMPLES + 3]) / float(SAMPLES) for t, s in sizes.items()}
        rate = {t: (len(s) - 4) / (s[-1] - s[3]) if s[-1] > s[3] else float('nan') for t, s in stamps.items()}
        ratio = mean['hair_markers'] / mean['hair_state']
        print('hair_state_size: hair_state %.0f bytes/msg (%.1f kB/s at %.1f Hz), hair_markers %.0f bytes/msg '
              '(%.1f MB/s at %.1f Hz), ratio %.1f' %
              (mean['hair_state'], mean['hair_state'] * rate['hair_state'] / 1e3, rate['hair_state'],
               mean['hair_markers'], mean['hair_markers'] * rate['hair_markers'] / 1e6, rate['hair_markers'],
               ratio))
        sys.stdout.flush()
        self.assertGreater(mean['hair_state'], 0)
        self.assertGreaterEqual(ratio, MIN_RATIO, 'hair_markers %.0f B vs hair_state %.0f B per message' %
                                (mean['hair_markers'], mean['hair_state']))


if __name__ == '__main__':
    rostest.rosrun(PKG, NAME, HairStateSize, sys.argv)
