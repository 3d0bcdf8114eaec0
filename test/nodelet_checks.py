#!/usr/bin/python3
"""rostest node for nodelet.test: hair_sim/HairSimNodelet in a nodelet manager.

  test_runs_inside_the_manager
      hair_state arrives (30 s), the master lists the manager (private parameter manager) as the
      publisher of /hair_state and /hair_markers (the nodelet's publishers are the manager's), the
      nodelet's dynamic_reconfigure service /hair_sim/set_parameters answers (hinge_stiffness set and read
      back), and /diagnostics carries 'hair_sim: simulated rate'.
"""
import sys
import threading
import time
import unittest

import dynamic_reconfigure.client
import rosgraph
import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray
from hair_sim_msgs.msg import HairState

PKG = 'hair_sim'
NAME = 'nodelet_checks'


class NodeletChecks(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node(NAME)

    def test_runs_inside_the_manager(self):
        manager = rospy.get_param('~manager', '/hair_sim_manager')
        got = threading.Event()
        names = set()
        rospy.Subscriber('hair_state', HairState, lambda _m: got.set(), queue_size=1)
        rospy.Subscriber('/diagnostics', DiagnosticArray, lambda m: names.update(s.name for s in m.status),
                         queue_size=5)
        self.assertTrue(got.wait(30.0), 'no hair_state from the nodelet within 30 s')
        publishers = {t: n for t, n in rosgraph.Master('/' + NAME).getSystemState()[0]}
        for topic in ('/hair_state', '/hair_markers'):
            self.assertIn(manager, publishers.get(topic, []), '%s is published by %s, not by the manager %s'
                          % (topic, publishers.get(topic), manager))
        client = dynamic_reconfigure.client.Client('/hair_sim', timeout=10.0)
        answer = client.update_configuration({'hinge_stiffness': 5e-4})
        self.assertAlmostEqual(answer['hinge_stiffness'], 5e-4)
        deadline = time.time() + 5.0
        while 'hair_sim: simulated rate' not in names:
            self.assertLess(time.time(), deadline, 'no hair_sim diagnostics from the nodelet: %s' % sorted(names))
            time.sleep(0.1)


if __name__ == '__main__':
    rostest.rosrun(PKG, NAME, NodeletChecks, sys.argv)
