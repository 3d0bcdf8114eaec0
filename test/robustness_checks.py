#!/usr/bin/python3
"""rostest node for robustness.test: bad input and faults sent to the real hair_sim_node (issue 8).

The test broadcasts world -> odom -> head itself (odom at the world's origin, an upright head, TF_RATE Hz, both
in one message stamped now) and, in this order on the same node, sends:

  test_a_nan_tf            a head tf with translation.x = NaN, then one with rotation.w = inf
  test_b_zero_quaternion   a head tf with the rotation quaternion (0, 0, 0, 0)
  test_c_nonunit_quat      1 s of head tf with a quaternion of norm 2 turning the head 0.5 rad (yaw)
  test_d_bad_wind          Wind with velocity.x = NaN, then a Wind in frame 'nowhere' (no tf)
  test_e_tf_order          a head tf 0.2 s older than the newest (out of order), one 30 s older (beyond
                           the tf cache), one repeating the newest stamp
  test_f_stale_head        no head tf for STALE_PERIOD s (~max_tf_age is 0.5 s)
  test_g_teleport          the head jumps 1.0 m sideways and turns 2 rad between two tf messages
  test_h_stall             the node's process stopped (SIGSTOP) for STALL s while tf goes on, then continued
  test_i_far_future        a head tf and a Wind stamped 2^32 - 1 s (68 years past the clock's range of
                           ros::Duration): the tf refused as ahead of the clock, the Wind taken on arrival
  test_j_turbulence        a Wind with turbulence 1e306 (the wind would be infinite)
  test_k_gap               no head tf for GAP s, longer than the 10 s tf cache: the hair steps on afterwards
  test_l_body_lost         the neck body's frame (world -> neck, broadcast with the head) stops: the node holds
                           the neck where it was last seen and the hair steps on; it says so, and when it is back
  test_m_event_flood       wind events for an hour from now through `trigger`: the first 256 scheduled, the next
                           refused (too many events scheduled); the hair steps on
  test_n_odom_teleport     world -> odom, the frame above the head, jumps 1.0 m sideways between two messages
                           (a localisation's correction): the hair goes with the head rigidly, as in test_g
  test_o_odom_turn         odom turns ODOM_YAW about its z axis, 1 m from the head: under teleport_angle, but
                           the head moves 0.59 m (over teleport_distance): the hair goes rigidly, as in test_g
  test_q_body_jump         world -> neck jumps 1.0 m down between two messages: held until the new one (the
                           neck jumps within one substep, not swept through the hair over 10 ms), said
  test_r_head_motion_without_head_driver
                           a shake through `trigger` with no head_driver running: refused (no head driver
                           subscribes to /events), not reported as passed on; a nod on `events`: warned
  test_s_body_turn         world -> neck turns NECK_ROLL about x: under teleport_angle and no move of the frame's
                           origin, but the neck body, 1.45 m up in its frame, swings 0.86 m: held, said at the body

and checks after each: the node's /rosout has a WARN naming the field or the fault (the text expected is
given with each case), hair_state keeps coming at publish_rate (at least 80 % of it, stale period included),
hair_state.step never goes back (the simulation is not restarted), every point of every hair_state is
finite and within NEAR m of the head position (the hair is at most
0.32 m long on a scalp of 0.115 m: 0.5 m is "near"), and the roots (row 0) stay on the head the test
broadcast last as good, turned as it was (within ROOT_TOLERANCE: a bad pose must not have moved the head,
a normalised one must have turned it). For the teleport:
the tips, in head coordinates, move less than TELEPORT_TIP_MOVE m from just before the jump to 0.2 s after
it (the hair is carried rigidly; interpolated over one tf period instead, the head moves at 100 m/s and the
tips swing by tens of cm), and the node logs the jump; for odom's jump, it names odom's as well. For the stall: the node says it skipped ahead
(max_substeps_per_update), that it buffered the queued tf without stepping for each (no burst of outputs),
and from 0.5 s after it publishes at its rate again (no spiral of death): at least 80 % of publish_rate and
at most STALL_RATE_MAX x publish_rate.
At the end: no ERROR from the node on /rosout.

Private parameters: node (/hair_sim), world_frame (world), head_frame (head), publish_rate (30).
"""
import math
import os
import signal
import sys
import threading
import time
import unittest

import rosgraph
import rospy
import rostest
from geometry_msgs.msg import TransformStamped
from hair_sim_msgs.msg import HairEvent, HairState, Wind
from hair_sim_msgs.srv import Trigger
from rosgraph_msgs.msg import Log
from tf2_msgs.msg import TFMessage

try:
    from xmlrpc.client import ServerProxy
except ImportError:  # pragma: no cover
    from xmlrpclib import ServerProxy

# Shared helpers (this folder is not on sys.path when catkin's relay runs the script).
sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
from hair_test_geometry import strip_points, wait_until  # noqa: E402

PKG = 'hair_sim'
NAME = 'robustness_checks'

TF_RATE = 100.0  # Hz
HOME = (0.0, 0.0, 1.6)  # m: the head's rest place (the world bodies are placed for it)
NONUNIT_YAW = 0.5  # rad: the turn given by the non-unit quaternion
TELEPORT_YAW = 2.0  # rad, with the teleport (the node's ~teleport_angle is 1.0 rad)
NEAR = 0.5  # m: every control point within this of the head's position
ROOT_TOLERANCE = 0.002  # m: roots from the head position the test broadcast (scalp offsets aside, see roots)
RATE_FRACTION = 0.8  # of publish_rate, over each case's watch window
WATCH = 1.0  # s after each fault
STALE_PERIOD = 2.0  # s without head tf
TELEPORT = 1.0  # m, sideways (+y); the node's ~teleport_distance is 0.5 m
TELEPORT_TIP_MOVE = 0.05  # m
STALL = 3.0  # s: the node's process stopped
STALL_RATE_MAX = 1.2  # x publish_rate after the stall (the tf backlog stepped one message at a time: 2.4 x)
GAP = 12.0  # s without head tf: beyond the tf cache (10 s)
STEP_FRACTION = 0.5  # of 240 substeps per second: the hair steps on (not frozen at the old pose)
ODOM_YAW = 0.6  # rad: odom's turn in test_o (the node's ~teleport_angle is 1.0 rad)
NECK_ROLL = 0.6  # rad: the neck frame's turn in test_r
NECK_CENTER = (-0.01, 0.0, 1.45)  # m: the neck body's center in its frame (test/data/robustness_config.yaml)
NECK_RADIUS = 0.09  # m: its largest radius


def quat_yaw(yaw):
    return (0.0, 0.0, math.sin(0.5 * yaw), math.cos(0.5 * yaw))


def rotate_yaw(p, yaw):
    c, s = math.cos(yaw), math.sin(yaw)
    return (c * p[0] - s * p[1], s * p[0] + c * p[1], p[2])


class RobustnessChecks(unittest.TestCase):
    lock = threading.Lock()
    states = []  # (receipt wall time, HairState)
    logs = []  # (level, text) from the node
    head = list(HOME)  # where the broadcaster puts the head in odom
    odom = (0.0, 0.0, 0.0)  # where the broadcaster puts odom in the world
    odom_yaw = 0.0  # and how it turns odom (rad, about z)
    quaternion = (0.0, 0.0, 0.0, 1.0)
    broadcasting = True
    neck_broadcasting = True  # world -> neck, the frame of the neck body in the test's config
    neck = (0.0, 0.0, 0.0)  # where the broadcaster puts neck in the world
    neck_q = (0.0, 0.0, 0.0, 1.0)  # and how it turns it
    last_stamp = None  # newest head tf stamp sent
    root_offsets = None  # roots in head coordinates, from the first states
    last_step = None  # hair_state.step of the last state watched

    @classmethod
    def setUpClass(cls):
        rospy.init_node(NAME)
        cls.node = rospy.get_param('~node', '/hair_sim')
        cls.world_frame = rospy.get_param('~world_frame', 'world')
        cls.head_frame = rospy.get_param('~head_frame', 'head')
        cls.publish_rate = float(rospy.get_param('~publish_rate', 30.0))
        cls.tf_pub = rospy.Publisher('/tf', TFMessage, queue_size=100)
        cls.wind_pub = rospy.Publisher('wind', Wind, queue_size=10)
        rospy.Subscriber('hair_state', HairState, cls.on_state, queue_size=100)
        rospy.Subscriber('/rosout', Log, cls.on_log, queue_size=1000)
        cls.stop = threading.Event()
        cls.thread = threading.Thread(target=cls.broadcast)
        cls.thread.daemon = True
        cls.thread.start()

    @classmethod
    def tearDownClass(cls):
        cls.stop.set()

    # -- rospy threads
    @classmethod
    def on_state(cls, msg):
        with cls.lock:
            cls.states.append((time.time(), msg))

    @classmethod
    def on_log(cls, msg):
        if msg.name == cls.node:
            with cls.lock:
                cls.logs.append((msg.level, msg.msg))

    @classmethod
    def transform(cls, stamp, position, q, parent='odom'):
        t = TransformStamped()
        t.header.stamp = stamp
        t.header.frame_id = parent
        t.child_frame_id = cls.head_frame
        t.transform.translation.x, t.transform.translation.y, t.transform.translation.z = position
        r = t.transform.rotation
        r.x, r.y, r.z, r.w = q
        return t

    @classmethod
    def broadcast(cls):
        period = 1.0 / TF_RATE
        while not cls.stop.is_set() and not rospy.is_shutdown():
            with cls.lock:
                go, position, q, odom, neck_at = cls.broadcasting, tuple(cls.head), cls.quaternion, cls.odom, cls.neck
                neck_q = cls.neck_q
                odom_q = quat_yaw(cls.odom_yaw)
                neck = go and cls.neck_broadcasting
            if go:
                stamp = rospy.Time.now()
                above = cls.transform(stamp, odom, odom_q, parent=cls.world_frame)
                above.child_frame_id = 'odom'
                cls.send(cls.transform(stamp, position, q), above)
            if neck:
                t = cls.transform(stamp, neck_at, neck_q, parent=cls.world_frame)
                t.child_frame_id = 'neck'
                cls.tf_pub.publish(TFMessage(transforms=[t]))
            time.sleep(period)

    @classmethod
    def send(cls, t, above=None):
        """A head transform (with `above`, world -> odom, in the same message first)."""
        with cls.lock:
            if cls.last_stamp is None or t.header.stamp > cls.last_stamp:
                cls.last_stamp = t.header.stamp
        cls.tf_pub.publish(TFMessage(transforms=[above, t] if above is not None else [t]))

    @classmethod
    def send_raw(cls, t):
        """A transform not counted as the newest sent (one the node must refuse)."""
        cls.tf_pub.publish(TFMessage(transforms=[t]))

    # -- helpers (test thread)
    def wait_for(self, predicate, timeout, what):
        return wait_until(predicate, timeout, what, self.fail, lambda: not rospy.is_shutdown())

    def log_index(self):
        with self.lock:
            return len(self.logs)

    def expect_log(self, since, text, level=Log.WARN, timeout=3.0):
        """A node message at `level` containing `text` after log index `since`; returns it."""
        def found():
            with self.lock:
                for lv, msg in self.logs[since:]:
                    if lv == level and text in msg:
                        return msg
            return None
        msg = self.wait_for(found, timeout, "a /rosout message of %s containing '%s'" % (self.node, text))
        rospy.loginfo('%s: node said: %s', NAME, msg)
        return msg

    def watch(self, seconds, head, yaw=0.0):
        """States received over the next `seconds`: count >= RATE_FRACTION of the rate, all sane."""
        t0 = time.time()
        time.sleep(seconds)
        with self.lock:
            window = [m for (w, m) in self.states if w > t0]
        self.assertGreaterEqual(len(window), int(RATE_FRACTION * self.publish_rate * seconds),
                                '%d hair_state in %.1f s (publish_rate %.0f Hz)' % (len(window), seconds,
                                                                                    self.publish_rate))
        for msg in window:
            self.check_sane(msg, head, yaw)
            # The simulation goes on: its substep count never goes back (a reset would start it again).
            if self.last_step is not None:
                self.assertGreaterEqual(msg.step, self.last_step, 'hair_state.step went back from %d to %d: the '
                                        'simulation was restarted' % (self.last_step, msg.step))
            type(self).last_step = msg.step
        return window

    def check_sane(self, msg, head, yaw=0.0):
        """Finite, near the head, roots where the head at `head` turned by `yaw` puts them."""
        roots = []
        for s, strip in enumerate(msg.strips):
            for k, p in enumerate(strip_points(strip)):
                v = (p.x, p.y, p.z)
                self.assertTrue(all(map(math.isfinite, v)), 'strip %d point %d is %s' % (s, k, v))
                d = math.sqrt(sum((a - b) ** 2 for a, b in zip(v, head)))
                self.assertLess(d, NEAR, 'strip %d point %d is %.3f m from the head at %s' % (s, k, d, head))
                if k < strip.columns:
                    roots.append(tuple(a - b for a, b in zip(v, head)))
        if self.root_offsets is None:
            type(self).root_offsets = roots
        worst = max(math.sqrt(sum((a - b) ** 2 for a, b in zip(r, rotate_yaw(o, yaw))))
                    for r, o in zip(roots, self.root_offsets))
        self.assertLess(worst, ROOT_TOLERANCE, 'roots moved %.4f m from the head at %s: the head was moved' %
                        (worst, head))

    def tips(self, msg, head, yaw=0.0):
        """Tips in the coordinates of the head at `head` turned by `yaw`."""
        out = []
        for strip in msg.strips:
            for c in range(strip.columns):
                p = strip_points(strip)[(strip.rows - 1) * strip.columns + c]
                out.append(rotate_yaw((p.x - head[0], p.y - head[1], p.z - head[2]), -yaw))
        return out

    def now_stamp(self):
        with self.lock:
            last = self.last_stamp
        now = rospy.Time.now()
        return now if last is None or now > last else last + rospy.Duration(1e-4)

    # -- the cases, in order
    def test_0_starts(self):
        self.wait_for(lambda: len(self.states) > 10, 30.0, 'hair_state (is hair_sim_node running?)')
        time.sleep(1.0)  # the hair settles a little
        self.watch(WATCH, HOME)

    def test_a_nan_tf(self):
        since = self.log_index()
        self.send(self.transform(self.now_stamp(), (float('nan'), 0.0, 1.6), (0.0, 0.0, 0.0, 1.0)))
        self.expect_log(since, 'transform.translation.x is nan')
        self.watch(WATCH, HOME)
        time.sleep(2.1)  # the warning is throttled to one per 2 s
        since = self.log_index()
        self.send(self.transform(self.now_stamp(), HOME, (0.0, 0.0, 0.0, float('inf'))))
        self.expect_log(since, 'transform.rotation.w is inf')
        self.watch(WATCH, HOME)

    def test_b_zero_quaternion(self):
        time.sleep(2.1)
        since = self.log_index()
        self.send(self.transform(self.now_stamp(), (0.3, 0.0, 1.6), (0.0, 0.0, 0.0, 0.0)))
        self.expect_log(since, 'rotation is a zero quaternion')
        self.watch(WATCH, HOME)

    def test_c_nonunit_quaternion(self):
        since = self.log_index()
        # Norm 2 and a turn: taken normalised, the hair turns with the head (the roots show it).
        with self.lock:
            type(self).quaternion = tuple(2.0 * v for v in quat_yaw(NONUNIT_YAW))
        self.expect_log(since, 'rotation quaternion of norm 2 normalised')
        time.sleep(0.1)
        self.watch(WATCH, HOME, NONUNIT_YAW)
        with self.lock:
            type(self).quaternion = (0.0, 0.0, 0.0, 1.0)
        time.sleep(1.0)

    def test_d_bad_wind(self):
        since = self.log_index()
        w = Wind()
        w.header.frame_id = self.world_frame
        w.velocity.x = float('nan')
        self.wind_pub.publish(w)
        self.expect_log(since, 'Wind message: velocity.x is nan')
        self.watch(WATCH, HOME)
        time.sleep(2.1)
        since = self.log_index()
        w = Wind()
        w.header.frame_id = 'nowhere'
        w.velocity.x = 2.0
        self.wind_pub.publish(w)
        self.expect_log(since, "header.frame_id 'nowhere' is unknown")
        self.watch(WATCH, HOME)

    def test_e_tf_order(self):
        since = self.log_index()
        newest = self.now_stamp()
        self.send(self.transform(newest - rospy.Duration(0.2), HOME, (0.0, 0.0, 0.0, 1.0)))
        self.expect_log(since, 'arrived out of order')
        since = self.log_index()
        self.send(self.transform(newest - rospy.Duration(30.0), (1.0, 0.0, 1.6), (0.0, 0.0, 0.0, 1.0)))
        self.expect_log(since, 'beyond the 10.0 s tf cache')
        since = self.log_index()
        with self.lock:
            repeat = self.last_stamp
        self.send(self.transform(repeat, HOME, (0.0, 0.0, 0.0, 1.0)))
        self.expect_log(since, 'repeats the previous one')
        self.watch(WATCH, HOME)

    def test_f_stale_head(self):
        since = self.log_index()
        with self.lock:
            type(self).broadcasting = False
        t0 = time.time()
        self.expect_log(since, '(max_tf_age 0.50 s): holding the head')
        stale = self.watch(STALE_PERIOD - (time.time() - t0), HOME)
        rospy.loginfo('%s: %d hair_state while the head was stale', NAME, len(stale))
        since = self.log_index()
        with self.lock:
            type(self).broadcasting = True
        self.expect_log(since, 'fresh again', level=Log.INFO)
        self.watch(WATCH, HOME)

    def rigid_over_jump(self, head, yaw, new_head, new_yaw, move):
        """The worst move of the tips in head coordinates from just before `move()` jumps the head from `head`
        turned by `yaw` (in the world) to `new_head` turned by `new_yaw`, to 0.2 s after it."""
        time.sleep(1.0)
        with self.lock:
            before = self.states[-1][1]
        with self.lock:
            move()
        t0 = time.time()
        time.sleep(0.2)
        with self.lock:
            after = [m for (w, m) in self.states if w > t0 - 0.2]
        tips_before = self.tips(before, head, yaw)
        old_root = [h + o for h, o in zip(head, rotate_yaw(self.root_offsets[0], yaw))]
        new_root = [h + o for h, o in zip(new_head, rotate_yaw(self.root_offsets[0], new_yaw))]
        worst = 0.0
        for msg in after:
            # States stamped before the jump still show the head where it was: compare each with its own head.
            root = strip_points(msg.strips[0])[0]
            jumped = math.dist((root.x, root.y, root.z), new_root) < math.dist((root.x, root.y, root.z), old_root)
            tips = self.tips(msg, new_head, new_yaw) if jumped else self.tips(msg, head, yaw)
            worst = max(worst, max(math.sqrt(sum((a - b) ** 2 for a, b in zip(t, r)))
                                   for t, r in zip(tips, tips_before)))
        return worst

    def test_g_teleport(self):
        since = self.log_index()
        far = (HOME[0], HOME[1] + TELEPORT, HOME[2])

        def move():
            type(self).head = list(far)
            type(self).quaternion = quat_yaw(TELEPORT_YAW)
        worst = self.rigid_over_jump(HOME, 0.0, far, TELEPORT_YAW, move)
        rospy.loginfo('%s: teleport of %.1f m: tips moved at most %.1f mm in head coordinates', NAME, TELEPORT,
                      1e3 * worst)
        self.assertLess(worst, TELEPORT_TIP_MOVE, 'tips moved %.3f m relative to the head over the teleport' % worst)
        self.expect_log(since, 'the head jumped 1.000 m and 2.000 rad')
        self.watch(WATCH, far, TELEPORT_YAW)

    def test_h_stall(self):
        """The node's process stopped for STALL s (SIGSTOP) while tf goes on: on SIGCONT it catches up within
        max_substeps_per_update substeps, says it skipped ahead, and publishes at its rate again."""
        pid = self.node_pid()
        head = tuple(self.head)  # where test_g left it, turned by TELEPORT_YAW
        time.sleep(0.5)
        since = self.log_index()
        os.kill(pid, signal.SIGSTOP)
        try:
            time.sleep(STALL)
        finally:
            os.kill(pid, signal.SIGCONT)
        resumed = time.time()
        self.expect_log(since, 'skipping ahead (max_substeps_per_update 60)')
        self.expect_log(since, 's old on arrival (max_tf_age 0.50 s): buffered without stepping')
        time.sleep(max(0.0, resumed + 0.5 - time.time()))
        window = self.watch(WATCH, head, TELEPORT_YAW)
        self.assertLessEqual(len(window), STALL_RATE_MAX * self.publish_rate * WATCH,
                             '%d hair_state in the %.1f s from 0.5 s after the stall: a burst' % (len(window), WATCH))
        rospy.loginfo('%s: after a %.1f s stall, %d hair_state in the %.1f s from 0.5 s after it', NAME, STALL,
                      len(window), WATCH)

    def steps_on(self, window):
        """The simulation advanced through the window: at least STEP_FRACTION of 240 substeps per second."""
        span = window[-1].header.stamp.to_sec() - window[0].header.stamp.to_sec()
        steps = window[-1].step - window[0].step
        self.assertGreater(span, 0.5 * WATCH, 'hair_state stamps advanced %.3f s in %.1f s' % (span, WATCH))
        self.assertGreaterEqual(steps, STEP_FRACTION * 240.0 * span,
                                '%d substeps over %.3f s of hair_state stamps: the simulation stopped' % (steps, span))

    def test_i_far_future(self):
        head = tuple(self.head)
        since = self.log_index()
        self.send_raw(self.transform(rospy.Time(4294967295, 0), head, quat_yaw(TELEPORT_YAW)))
        self.expect_log(since, 'ahead of the clock')
        self.steps_on(self.watch(WATCH, head, TELEPORT_YAW))
        w = Wind()
        w.header.stamp = rospy.Time(4294967295, 0)
        w.header.frame_id = self.world_frame
        w.velocity.x = 0.5
        self.wind_pub.publish(w)
        time.sleep(0.2)
        self.steps_on(self.watch(WATCH, head, TELEPORT_YAW))

    def test_j_turbulence(self):
        head = tuple(self.head)
        since = self.log_index()
        w = Wind()
        w.header.frame_id = self.world_frame
        w.velocity.x = 1.0
        w.turbulence = 1e306
        self.wind_pub.publish(w)
        self.expect_log(since, 'turbulence is 1e+306, must be <= 10')
        self.steps_on(self.watch(WATCH, head, TELEPORT_YAW))

    def test_k_gap(self):
        head = tuple(self.head)
        with self.lock:
            type(self).broadcasting = False
        time.sleep(GAP)
        since = self.log_index()
        with self.lock:
            type(self).broadcasting = True
        time.sleep(0.5)
        # The hair steps on (waiting for poses tf no longer has, it would stop for good), and says why.
        self.steps_on(self.watch(WATCH, head, TELEPORT_YAW))
        self.expect_log(since, 'skipping ahead to it, the hair carried rigidly')

    def test_l_body_lost(self):
        head = tuple(self.head)
        since = self.log_index()
        with self.lock:
            type(self).neck_broadcasting = False
        time.sleep(1.0)
        # The hair steps on (waiting for the neck instead, it would stop at its last pose for good), and says why.
        self.steps_on(self.watch(WATCH, head, TELEPORT_YAW))
        self.expect_log(since, "body 'neck': no tf world -> neck newer than max_tf_age (0.50 s): held where it was "
                        "last seen")
        since = self.log_index()
        with self.lock:
            type(self).neck_broadcasting = True
        self.expect_log(since, "body 'neck': tf world -> neck fresh again", level=Log.INFO)
        self.steps_on(self.watch(WATCH, head, TELEPORT_YAW))

    def test_m_event_flood(self):
        head = tuple(self.head)
        rospy.wait_for_service('trigger', timeout=10.0)
        trigger = rospy.ServiceProxy('trigger', Trigger)
        start = rospy.Time.now() + rospy.Duration(3600.0)  # pending for the rest of the test: harmless
        for k in range(257):
            event = HairEvent(type='wind', duration=1.0)
            event.header.stamp = start + rospy.Duration(2.0 * k)
            event.vector.x = 0.1
            reply = trigger(event)
            if k < 256:
                self.assertTrue(reply.accepted, 'event %d refused: %s' % (k, reply.message))
            else:
                self.assertFalse(reply.accepted, 'event 257 scheduled: %s' % reply.message)
                self.assertIn('too many events scheduled (256, at most 256)', reply.message)
        self.steps_on(self.watch(WATCH, head, TELEPORT_YAW))

    def test_n_odom_teleport(self):
        head = tuple(self.head)  # odom is at the world's origin until now
        new_head = (head[0], head[1] + TELEPORT, head[2])
        since = self.log_index()

        def move():
            type(self).odom = (0.0, TELEPORT, 0.0)
        worst = self.rigid_over_jump(head, TELEPORT_YAW, new_head, TELEPORT_YAW, move)
        rospy.loginfo('%s: odom jumped %.1f m: tips moved at most %.1f mm in head coordinates', NAME, TELEPORT,
                      1e3 * worst)
        self.assertLess(worst, TELEPORT_TIP_MOVE, 'tips moved %.3f m relative to the head over the jump of odom' %
                        worst)
        said = self.expect_log(since, 'jumped 1.000 m at the head and 0.000 rad between two messages')
        self.assertIn('tf %s -> odom from ' % self.world_frame, said)
        self.expect_log(since, 'the head jumped 1.000 m and 0.000 rad')
        self.steps_on(self.watch(WATCH, new_head, TELEPORT_YAW))

    def test_q_body_jump(self):
        yaw = TELEPORT_YAW + self.odom_yaw  # the head's, turned with odom by test_o
        head = tuple(a + b for a, b in zip(self.odom, rotate_yaw(self.head, self.odom_yaw)))
        since = self.log_index()
        with self.lock:
            type(self).neck = (0.0, 0.0, -TELEPORT)
        said = self.expect_log(since, "jumped 1.000 m at body 'neck' and 0.000 rad between two messages")
        self.assertIn('tf %s -> neck from ' % self.world_frame, said)
        self.steps_on(self.watch(WATCH, head, yaw))

    def test_s_body_turn(self):
        yaw = TELEPORT_YAW + self.odom_yaw
        head = tuple(a + b for a, b in zip(self.odom, rotate_yaw(self.head, self.odom_yaw)))
        # A turn by NECK_ROLL about x moves the body's center by the chord 2 sin(roll / 2) times its distance
        # from the x axis, and its surface by up to the same chord of its largest radius more.
        chord = 2.0 * math.sin(0.5 * NECK_ROLL)
        reach = chord * (math.hypot(NECK_CENTER[1], NECK_CENTER[2]) + NECK_RADIUS)
        self.assertGreater(reach, 0.5, 'the test needs the body to move more than teleport_distance')
        since = self.log_index()
        with self.lock:
            type(self).neck_q = (math.sin(0.5 * NECK_ROLL), 0.0, 0.0, math.cos(0.5 * NECK_ROLL))
        said = self.expect_log(since, "jumped %.3f m at body 'neck' and %.3f rad between two messages" %
                               (reach, NECK_ROLL))
        self.assertIn('tf %s -> neck from ' % self.world_frame, said)
        self.steps_on(self.watch(WATCH, head, yaw))

    def test_o_odom_turn(self):
        odom, in_odom = self.odom, tuple(self.head)  # odom is not turned until now
        head = tuple(a + b for a, b in zip(odom, in_odom))
        new_head = tuple(a + b for a, b in zip(odom, rotate_yaw(in_odom, ODOM_YAW)))
        moved = math.dist(head, new_head)
        self.assertGreater(moved, 0.5, 'the test needs the head more than teleport_distance from odom\'s axis')
        since = self.log_index()

        def move():
            type(self).odom_yaw = ODOM_YAW
        # The 0.5 m/s wind test_i left blowing along x turns with the head relative to the hair: the tips start
        # to follow it (about 20 mm in the 0.2 s; 611 mm when tf interpolated the turn over 10 ms).
        worst = self.rigid_over_jump(head, TELEPORT_YAW, new_head, TELEPORT_YAW + ODOM_YAW, move)
        rospy.loginfo('%s: odom turned %.1f rad, the head moved %.3f m: tips moved at most %.1f mm in head '
                      'coordinates', NAME, ODOM_YAW, moved, 1e3 * worst)
        self.assertLess(worst, TELEPORT_TIP_MOVE, 'tips moved %.3f m relative to the head over the turn of odom' %
                        worst)
        said = self.expect_log(since, 'jumped %.3f m at the head and 0.600 rad between two messages' % moved)
        self.assertIn('tf %s -> odom from ' % self.world_frame, said)
        self.expect_log(since, 'the head jumped %.3f m and 0.600 rad' % moved)
        self.steps_on(self.watch(WATCH, new_head, TELEPORT_YAW + ODOM_YAW))

    def node_pid(self):
        uri = rosgraph.Master('/' + NAME).lookupNode(self.node)
        code, _, pid = ServerProxy(uri).getPid('/' + NAME)
        self.assertEqual(code, 1, 'getPid of %s failed' % self.node)
        return int(pid)

    def test_r_head_motion_without_head_driver(self):
        # No head_driver in this launch: a shake through `trigger` would go out on `events` to no one.
        rospy.wait_for_service('trigger', timeout=10.0)
        since = self.log_index()
        reply = rospy.ServiceProxy('trigger', Trigger)(
            HairEvent(type='shake', duration=3.0, ease=0.3, amplitude=0.5, frequency=2.0))
        self.assertFalse(reply.accepted, reply.message)
        self.assertIn('no head driver subscribes to /events', reply.message)
        self.expect_log(since, 'no head driver subscribes to /events')
        # The same on the topic: nobody would take it, and the node says so.
        events = rospy.Publisher('events', HairEvent, queue_size=10)
        wait_until(lambda: events.get_num_connections() >= 1, 5.0, 'a connection to hair_sim on events',
                   self.fail, lambda: not rospy.is_shutdown())
        since = self.log_index()
        events.publish(HairEvent(type='nod', duration=2.0, amplitude=0.2, frequency=1.0))
        self.expect_log(since, 'a nod HairEvent on /events: no head driver subscribes to it')

    def test_z_no_errors(self):
        with self.lock:
            errors = [m for (lv, m) in self.logs if lv >= Log.ERROR]
        self.assertEqual(errors, [], 'the node logged errors: %s' % errors[:3])


if __name__ == '__main__':
    rostest.rosrun(PKG, NAME, RobustnessChecks, sys.argv)
