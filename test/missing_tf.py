#!/usr/bin/python3
"""rostest node for missing_tf.test: hair_sim_node started with nobody broadcasting world -> head.

  test_node_waits_for_tf_then_starts
      1. The node registers with the master (within 20 s) and, for the next 3 s without the head's tf,
         stays registered and answers pings (rosnode ping, i.e. its XML-RPC getPid), and publishes no
         HairState: without the head pose there is no hair state to give (asserted; whether it publishes
         markers meanwhile is not asserted).
      2. The test then broadcasts world -> head (tf2_ros.TransformBroadcaster, head at [0, 0, 1.6], 50 Hz,
         in a thread) and asserts that hair_state and hair_markers both arrive within 5 s, and that the node
         is still alive.

Private parameters: node (the hair_sim node's name, default /hair_sim), world_frame (world),
head_frame (head).
"""
import sys
import threading
import time
import unittest

import rosgraph
import rosnode
import rospy
import rostest
import tf2_ros
from geometry_msgs.msg import TransformStamped
from hair_sim_msgs.msg import HairState

PKG = 'hair_sim'
NAME = 'missing_tf'

REGISTER_TIMEOUT = 20.0  # s
NO_TF_PERIOD = 3.0  # s
ARRIVAL_TIMEOUT = 5.0  # s
TF_RATE = 50.0  # Hz


class MissingTf(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node(NAME)

    def setUp(self):
        self.node = rospy.get_param('~node', '/hair_sim')
        self.world_frame = rospy.get_param('~world_frame', 'world')
        self.head_frame = rospy.get_param('~head_frame', 'head')
        self.lock = threading.Lock()
        self.counts = {'hair_state': 0, 'hair_markers': 0}
        self.state_sub = rospy.Subscriber('hair_state', HairState, self.count, 'hair_state', queue_size=10)
        # Markers are counted without deserializing them (about 1.5 MB each).
        self.marker_sub = rospy.Subscriber('hair_markers', rospy.AnyMsg, self.count, 'hair_markers', queue_size=2,
                                           buff_size=1 << 24)
        self.stop = threading.Event()

    def tearDown(self):
        self.stop.set()

    def count(self, _msg, topic):
        with self.lock:
            self.counts[topic] += 1

    def get_counts(self):
        with self.lock:
            return dict(self.counts)

    def registered(self):
        try:
            return rosgraph.Master('/' + NAME).lookupNode(self.node) is not None
        except (rosgraph.MasterError, IOError):
            return False

    def alive(self):
        return self.registered() and rosnode.rosnode_ping(self.node, max_count=1, verbose=False)

    def broadcast_head(self):
        broadcaster = tf2_ros.TransformBroadcaster()
        rate = rospy.Rate(TF_RATE)
        last = rospy.Time()
        while not self.stop.is_set() and not rospy.is_shutdown():
            now = rospy.Time.now()
            if now > last:
                t = TransformStamped()
                t.header.stamp = now
                t.header.frame_id = self.world_frame
                t.child_frame_id = self.head_frame
                t.transform.translation.z = 1.6
                t.transform.rotation.w = 1.0
                broadcaster.sendTransform(t)
                last = now
            try:
                rate.sleep()
            except rospy.ROSInterruptException:
                return

    def test_node_waits_for_tf_then_starts(self):
        deadline = time.time() + REGISTER_TIMEOUT
        while not self.registered():
            self.assertLess(time.time(), deadline, '%s did not register with the master' % self.node)
            time.sleep(0.05)
        # Give our subscriptions time to connect to the node's publishers, so a HairState would be seen.
        deadline = time.time() + REGISTER_TIMEOUT
        publishers = {}
        while not all(self.node in publishers.get(t, []) for t in ('/hair_state', '/hair_markers')):
            self.assertLess(time.time(), deadline, '%s does not advertise hair_state and hair_markers' % self.node)
            time.sleep(0.05)
            try:
                state = rosgraph.Master('/' + NAME).getSystemState()
                publishers = {topic: nodes for topic, nodes in state[0]}
            except (rosgraph.MasterError, IOError):
                publishers = {}

        # 1. No tf: alive, no HairState.
        end = time.time() + NO_TF_PERIOD
        pings = 0
        while time.time() < end:
            self.assertTrue(self.alive(), '%s died or stopped answering without the head tf' % self.node)
            pings += 1
            time.sleep(0.1)
        counts = self.get_counts()
        rospy.loginfo('%s: %d pings answered in %.0f s without tf; received %s', NAME, pings, NO_TF_PERIOD, counts)
        self.assertEqual(counts['hair_state'], 0, 'hair_state published without a head pose in tf')

        # 2. tf appears: both outputs start.
        thread = threading.Thread(target=self.broadcast_head)
        thread.daemon = True
        thread.start()
        deadline = time.time() + ARRIVAL_TIMEOUT
        while True:
            counts = self.get_counts()
            if counts['hair_state'] > 0 and counts['hair_markers'] > 0:
                break
            self.assertLess(time.time(), deadline, 'within %.0f s of the head tf, received only %s'
                            % (ARRIVAL_TIMEOUT, counts))
            time.sleep(0.02)
        self.assertTrue(self.alive(), '%s died after the head tf appeared' % self.node)
        rospy.loginfo('%s: outputs arriving after the tf appeared: %s', NAME, counts)


if __name__ == '__main__':
    rostest.rosrun(PKG, NAME, MissingTf, sys.argv)
