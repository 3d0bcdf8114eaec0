#!/usr/bin/python3
"""rostest node for hair_node_checks.test: hair_sim_node following head_driver in translate mode.

The head (head_driver, mode translate) rests at its base pose, then moves sideways (+y in world) by
translate_distance m over translate_duration s, and stops. The checks, run in this order on the same run:

  test_a_tips_lag_then_settle   During the move the strip tips, in head coordinates, move the other way
                                (mean y displacement < -2 mm: they lag behind the head); after the move
                                every tip is back within 5 mm of its position before the move (3 states in
                                a row) within a settle time derived from the config (see settle_time()).
  test_b_no_point_inside_a_body No control point of any HairState received so far lies inside a body of the
                                config inflated by the strip's thickness margin (the core's hard
                                guarantee): |S^-1 (p - c)| >= 1 - 1e-5, bodies in a tf frame placed by tf at
                                the state's stamp (the node samples tf at the same stamps). The roots (row
                                0), on the scalp by construction, against the bodies' own radii with 1e-4
                                (see ROOT_TOLERANCE in hair_test_geometry.py).
  test_c_reset_rest_pose        The reset service (REST_POSE) succeeds, the substep count (HairState.step)
                                starts again, and the states published after it have every tip within 1 mm
                                of its rest position in head coordinates (the styled shape of the hairstyle
                                file, which is the rest shape).
  test_d_markers_well_formed    Every hair_markers message received during the whole run: at least one
                                TRIANGLE_LIST marker, frame_id == world frame, every point (and pose, scale,
                                colour) finite, and len(colors) == len(points) > 0 for list markers.
  test_f_subscribers_get_tcp_nodelay  ~tcp_nodelay (default true): a new subscription to collision_bodies
                                (rospy does not ask for TCP_NODELAY) gets TCP_NODELAY on the node's side
                                of its connection, read from the node's sockets themselves
                                (pidfd_getfd: needs the right to trace the node, e.g. root; skipped without).

Markers are large (about 1.5 MB at 30 Hz), far too slow for genpy in Python: they are read from the wire
format with array/struct (checked against genpy on the first message).

Private parameters: config_file (required), world_frame (default: the config's), head_frame (default:
the config's), driver (name of the head_driver node whose translate_* parameters are read, default
/head_driver). Everything is waited for with polling loops and timeouts.
"""
import array
import ctypes
import errno
import math
import os
import socket
import struct
import sys
import threading
import time
import unittest

import rosgraph
import rospy
import rostest
import tf2_ros
from hair_sim_msgs.msg import HairState
from hair_sim_msgs.srv import Reset, ResetRequest
from rosgraph_msgs.msg import Log
from visualization_msgs.msg import Marker, MarkerArray

try:
    from xmlrpc.client import ServerProxy
except ImportError:  # pragma: no cover
    from xmlrpclib import ServerProxy

PKG = 'hair_sim'
NAME = 'hair_node_checks'

LAG_MIN = 0.002  # m: the mean tip displacement against the motion during the move must exceed this
SETTLE_TOLERANCE = 0.005  # m
SETTLE_CONSECUTIVE = 3  # states in a row within the tolerance
SETTLE_CAP = 8.0  # s
RESET_TOLERANCE = 0.001  # m


# ---------------------------------------------------------------------------------------------- geometry
# Shared geometry (this folder is not on sys.path when catkin's relay runs the script).
sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
from hair_test_geometry import Body, Pose, assert_no_point_inside, load_config, strip_points, wait_until  # noqa: E402

# ---------------------------------------------------------------------------------------------- config
def segment_lengths(hairstyle):
    lengths = []
    for strip in hairstyle['strips']:
        columns, pts = int(strip['columns']), strip['points']
        for r in range(1, int(strip['rows'])):
            for c in range(columns):
                a, b = pts[r * columns + c], pts[(r - 1) * columns + c]
                lengths.append(math.sqrt(sum((float(x) - float(y)) ** 2 for x, y in zip(a, b))))
    return lengths


def decay_time(config, hairstyle):
    """Slowest decay time 2 I / gamma over the segments: I = rho d^3 / 3 (with the simulator's floor on I,
    gamma dt and 2 k dt^2, README "Equation (7)"), gamma = hinge_damping."""
    physics = config.get('physics', {}) or {}
    rho = float(physics.get('linear_density', 0.01))
    gamma = float(physics.get('hinge_damping', 1e-5))
    k = float(physics.get('hinge_stiffness', 4e-4))
    dt = float(physics.get('substep', 1.0 / 240.0))
    inertia = max(max(rho * d ** 3 / 3.0, gamma * dt, 2.0 * k * dt * dt) for d in segment_lengths(hairstyle))
    return 2.0 * inertia / gamma


def settle_time(config, hairstyle):
    """Time allowed after the head stops for the tips to come back within 5 mm, capped at 8 s.

    Five decay times take one segment's deflection down by e^-5; the segments of a column are excited one by
    the next, so the tips of the chain take longer: the offline runner needs 4.8 decay times with the default
    config for a 0.3 m move in 0.5 s. Allowed: 8 decay times (2.8 s with the default config)."""
    return min(SETTLE_CAP, 8.0 * decay_time(config, hairstyle))


def tip_indices(strip_msg):
    """Indices of the last row (tips) of a StripState's row-major points."""
    columns, rows = int(strip_msg.columns), int(strip_msg.rows)
    return [(rows - 1) * columns + c for c in range(columns)]


# ---------------------------------------------------------------------------------------------- markers
_U32 = struct.Struct('<I')
_ID_TYPE_ACTION = struct.Struct('<iii')
_POSE_SCALE = struct.Struct('<10d')
_COLOR = struct.Struct('<4f')
_LIST_TYPES = (Marker.LINE_STRIP, Marker.LINE_LIST, Marker.CUBE_LIST, Marker.SPHERE_LIST, Marker.POINTS,
               Marker.TRIANGLE_LIST)


def _typed(code, data):
    a = array.array(code)
    a.frombytes(data)
    if sys.byteorder != 'little':
        a.byteswap()
    return a


def parse_marker_array(buf):
    """Reads a serialized visualization_msgs/MarkerArray into a list of dicts (frame_id, ns, type, action,
    pose_scale (10 doubles), color, points (flat doubles), colors (flat floats)). Raises ValueError."""
    mv = memoryview(buf)
    off = 0

    def u32():
        nonlocal off
        (v,) = _U32.unpack_from(buf, off)
        off += 4
        return v

    def string():
        nonlocal off
        n = u32()
        s = bytes(mv[off:off + n]).decode('utf-8', 'replace')
        off += n
        return s

    markers = []
    for _ in range(u32()):
        off += 12  # header.seq, header.stamp
        frame_id = string()
        ns = string()
        _mid, mtype, action = _ID_TYPE_ACTION.unpack_from(buf, off)
        off += 12
        pose_scale = _POSE_SCALE.unpack_from(buf, off)
        off += 80
        color = _COLOR.unpack_from(buf, off)
        off += 16 + 8 + 1  # color, lifetime, frame_locked
        n = u32()
        points = _typed('d', mv[off:off + 24 * n])
        off += 24 * n
        n = u32()
        colors = _typed('f', mv[off:off + 16 * n])
        off += 16 * n
        string()  # text
        string()  # mesh_resource
        off += 1  # mesh_use_embedded_materials
        if off > len(buf):
            raise ValueError('truncated MarkerArray')
        markers.append(dict(frame_id=frame_id, ns=ns, type=mtype, action=action, pose_scale=pose_scale,
                            color=color, points=points, colors=colors))
    if off != len(buf):
        raise ValueError('MarkerArray: %d bytes left over' % (len(buf) - off))
    return markers


def marker_problems(markers, world_frame):
    """Problems of one hair_markers message (empty list when well formed)."""
    problems = []
    triangle_lists = 0
    for i, m in enumerate(markers):
        if m['action'] != Marker.ADD:
            continue
        where = 'marker %d (ns %s, type %d)' % (i, m['ns'], m['type'])
        if m['frame_id'] != world_frame:
            problems.append("%s: frame_id '%s' != '%s'" % (where, m['frame_id'], world_frame))
        if not all(map(math.isfinite, m['pose_scale'])) or not all(map(math.isfinite, m['color'])):
            problems.append('%s: non-finite pose, scale or colour' % where)
        if not all(map(math.isfinite, m['points'])):
            problems.append('%s: non-finite point' % where)
        if not all(map(math.isfinite, m['colors'])):
            problems.append('%s: non-finite vertex colour' % where)
        if m['type'] in _LIST_TYPES:
            n_points, n_colors = len(m['points']) // 3, len(m['colors']) // 4
            if n_points == 0:
                problems.append('%s: no points' % where)
            if n_colors != n_points:
                problems.append('%s: %d colors for %d points' % (where, n_colors, n_points))
        if m['type'] == Marker.TRIANGLE_LIST:
            triangle_lists += 1
            if (len(m['points']) // 3) % 3 != 0:
                problems.append('%s: %d points is not a multiple of 3' % (where, len(m['points']) // 3))
    if triangle_lists == 0:
        problems.append('no TRIANGLE_LIST marker among %d markers' % len(markers))
    return problems


def crosscheck_parser(buf, parsed):
    """The wire reader against genpy on one message: the same markers, counts and sample points."""
    full = MarkerArray()
    full.deserialize(buf)
    assert len(full.markers) == len(parsed), 'parser: %d markers, genpy %d' % (len(parsed), len(full.markers))
    for m, p in zip(full.markers, parsed):
        assert m.header.frame_id == p['frame_id'] and m.ns == p['ns'] and m.type == p['type'], 'parser: header'
        assert len(m.points) * 3 == len(p['points']) and len(m.colors) * 4 == len(p['colors']), 'parser: sizes'
        for k in (0, len(m.points) // 2, len(m.points) - 1):
            if m.points:
                q = m.points[k]
                assert (q.x, q.y, q.z) == tuple(p['points'][3 * k:3 * k + 3]), 'parser: point %d' % k


# ---------------------------------------------------------------------------------------------- the test
class HairNodeChecks(unittest.TestCase):
    lock = threading.Lock()
    states = []  # HairState, in arrival order
    marker_count = 0
    marker_problems = []
    marker_parser_checked = False
    processed = []  # (stamp seconds, head Pose, state) for states whose head pose was found
    node_errors = []  # ERROR/FATAL lines of the hair node on /rosout

    @classmethod
    def setUpClass(cls):
        rospy.init_node(NAME)
        cls.config_file = rospy.get_param('~config_file')
        cls.config, cls.hairstyle = load_config(cls.config_file)
        cls.world_frame = rospy.get_param('~world_frame', cls.config.get('world_frame', 'world'))
        cls.head_frame = rospy.get_param('~head_frame', cls.config.get('head_frame', 'head'))
        driver = rospy.get_param('~driver', '/head_driver')
        cls.distance = float(rospy.get_param(driver + '/translate_distance', 0.3))
        cls.duration = float(rospy.get_param(driver + '/translate_duration', 0.5))
        cls.bodies = [Body(b) for b in cls.config.get('bodies', [])]
        cls.tf_buffer = tf2_ros.Buffer(rospy.Duration(300.0))
        cls.tf_listener = tf2_ros.TransformListener(cls.tf_buffer)
        cls.state_sub = rospy.Subscriber('hair_state', HairState, cls.on_state, queue_size=200)
        cls.marker_sub = rospy.Subscriber('hair_markers', rospy.AnyMsg, cls.on_markers, queue_size=5,
                                          buff_size=1 << 24)
        cls.node_name = rospy.get_param('~node', '/hair_sim')
        cls.rosout_sub = rospy.Subscriber('/rosout', Log, cls.on_log, queue_size=1000)
        cls.next_index = 0

    # -- callbacks (rospy threads): record only
    @classmethod
    def on_state(cls, msg):
        with cls.lock:
            cls.states.append(msg)

    @classmethod
    def on_log(cls, msg):
        if msg.name == cls.node_name and msg.level >= Log.ERROR:
            with cls.lock:
                cls.node_errors.append(msg.msg)

    @classmethod
    def on_markers(cls, raw):
        try:
            parsed = parse_marker_array(raw._buff)
            if not cls.marker_parser_checked:
                crosscheck_parser(raw._buff, parsed)
                cls.marker_parser_checked = True
            problems = marker_problems(parsed, cls.world_frame)
        except (ValueError, AssertionError, struct.error) as e:
            problems = ['unreadable message: %s' % e]
        with cls.lock:
            cls.marker_count += 1
            if problems and len(cls.marker_problems) < 20:
                cls.marker_problems.append('message %d: %s' % (cls.marker_count, '; '.join(problems[:5])))

    # -- helpers (test thread)
    def lookup(self, frame, stamp, timeout=1.0):
        if frame == self.world_frame:
            return Pose.identity()
        t = self.tf_buffer.lookup_transform(self.world_frame, frame, stamp, rospy.Duration(timeout))
        return Pose.from_msg(t)

    def process_new_states(self):
        """Pairs every newly received state with the head pose at its stamp; returns the new entries."""
        with self.lock:
            new = self.states[type(self).next_index:]
            type(self).next_index = len(self.states)
        out = []
        for msg in new:
            try:
                head = self.lookup(self.head_frame, msg.header.stamp)
            except (tf2_ros.LookupException, tf2_ros.ExtrapolationException, tf2_ros.ConnectivityException) as e:
                rospy.logwarn('%s: no head pose at %.3f: %s', NAME, msg.header.stamp.to_sec(), e)
                continue
            entry = (msg.header.stamp.to_sec(), head, msg)
            out.append(entry)
            self.processed.append(entry)
        return out

    def tips_local(self, head, msg):
        """Tips of every strip in head coordinates, in strip/column order."""
        out = []
        for strip in msg.strips:
            points = strip_points(strip)
            for i in tip_indices(strip):
                p = points[i]
                out.append(head.to_local((p.x, p.y, p.z)))
        return out

    def wait_for(self, predicate, timeout, what):
        return wait_until(predicate, timeout, what, self.fail, lambda: not rospy.is_shutdown())

    # -- (a) lag and settle
    def test_a_tips_lag_then_settle(self):
        self.assertEqual(self.config.get('world_frame', 'world'), self.world_frame)
        self.wait_for(lambda: self.process_new_states() or self.processed, 30.0,
                      'hair_state with a head pose in tf (is hair_sim_node running?)')
        start = self.processed[0][1].t
        moved = lambda head: (head.t[0] - start[0], head.t[1] - start[1], head.t[2] - start[2])
        self.assertLess(abs(moved(self.processed[0][1])[1]), 1e-9,
                        'the head was already moving when the first hair_state arrived: test started too late')
        settle = settle_time(self.config, self.hairstyle)
        rospy.loginfo('%s: decay time %.3f s, settle time %.3f s', NAME, decay_time(self.config, self.hairstyle),
                      settle)

        reference = None  # tips before the move (head coordinates)
        min_lag = 0.0  # most negative mean y displacement during the move
        moving_states = 0
        move_end = None
        in_row = 0
        deadline_wall = time.time() + 60.0
        i = 0
        while True:
            if i >= len(self.processed):
                self.assertLess(time.time(), deadline_wall, 'timed out: no settled state after the move')
                self.assertFalse(rospy.is_shutdown())
                time.sleep(0.02)
                self.process_new_states()
                continue
            stamp, head, msg = self.processed[i]
            i += 1
            dy = moved(head)[1]
            tips = self.tips_local(head, msg)
            if abs(dy) < 1e-9 and move_end is None:
                reference = tips
                continue
            self.assertIsNotNone(reference, 'no hair_state before the move')
            self.assertEqual(len(tips), len(reference))
            if move_end is None and abs(dy) < abs(self.distance) - 1e-6:
                moving_states += 1
                mean_dy = sum(t[1] - r[1] for t, r in zip(tips, reference)) / len(tips)
                min_lag = min(min_lag, math.copysign(1.0, self.distance) * mean_dy)
                continue
            if move_end is None:
                move_end = stamp
                self.assertAlmostEqual(dy, self.distance, delta=1e-4, msg='the head did not move as commanded')
                rospy.loginfo('%s: head moved %.3f m; %d states during the move; most lag %.1f mm', NAME, dy,
                              moving_states, -1e3 * min_lag)
                self.assertGreater(moving_states, 0, 'no hair_state during the move')
                self.assertLess(min_lag, -LAG_MIN,
                                'tips did not lag behind the head during the move (mean displacement %.2f mm '
                                'along the motion, expected < -%.1f mm)' % (1e3 * min_lag, 1e3 * LAG_MIN))
            worst = max(math.sqrt(sum((a - b) ** 2 for a, b in zip(t, r))) for t, r in zip(tips, reference))
            in_row = in_row + 1 if worst < SETTLE_TOLERANCE else 0
            if in_row >= SETTLE_CONSECUTIVE:
                rospy.loginfo('%s: settled %.2f s after the move (limit %.2f s), worst tip %.2f mm', NAME,
                              stamp - move_end, settle, 1e3 * worst)
                return
            if stamp - move_end > settle:
                self.fail('tips not back within %.0f mm of their pre-move positions %.2f s after the move '
                          '(settle time %.2f s from the config): worst tip %.1f mm (%d states in a row within)'
                          % (1e3 * SETTLE_TOLERANCE, stamp - move_end, settle, 1e3 * worst, in_row))

    # -- (b) no control point inside a body
    def test_b_no_point_inside_a_body(self):
        assert_no_point_inside(self, NAME, rospy.loginfo)

    # -- (c) reset
    def test_c_reset_rest_pose(self):
        rospy.wait_for_service('reset', timeout=10.0)
        reset = rospy.ServiceProxy('reset', Reset)
        # The hair has settled near its rest shape by now, so the shape alone would not show a reset that did
        # nothing: the substep count (HairState.step, since the last reset) must start again as well.
        self.wait_for(lambda: bool(self.states) and self.states[-1].step > 240, 10.0, 'a second of substeps')
        with self.lock:
            steps_before = self.states[-1].step
        response = reset(ResetRequest(mode=ResetRequest.REST_POSE))
        after = rospy.Time.now()
        self.assertTrue(response.success, 'reset REST_POSE failed: %s' % response.message)
        rest = []
        for strip in self.hairstyle['strips']:
            columns, rows = int(strip['columns']), int(strip['rows'])
            rest.extend(tuple(float(v) for v in strip['points'][(rows - 1) * columns + c]) for c in range(columns))
        checked = []

        def five_states_after():
            for stamp, head, msg in self.process_new_states():
                if msg.header.stamp > after:
                    checked.append((stamp, self.tips_local(head, msg), msg.step))
            return len(checked) >= 5

        self.wait_for(five_states_after, 10.0, 'hair_state after the reset')
        self.assertLess(checked[0][2], steps_before, 'the substep count did not start again at the reset '
                        '(%d before it, %d after)' % (steps_before, checked[0][2]))
        for stamp, tips, _ in checked:
            self.assertEqual(len(tips), len(rest))
            worst = max((math.sqrt(sum((a - b) ** 2 for a, b in zip(t, r))), k) for k, (t, r) in
                        enumerate(zip(tips, rest)))
            self.assertLess(worst[0], RESET_TOLERANCE, 'after the reset, tip %d is %.2f mm from its rest position '
                            '(head coordinates) at t = %.3f' % (worst[1], 1e3 * worst[0], stamp))

    # -- (d) markers
    def test_d_markers_well_formed(self):
        self.wait_for(lambda: self.marker_count >= 10, 10.0, '10 hair_markers messages')
        with self.lock:
            count, problems = self.marker_count, list(self.marker_problems)
        rospy.loginfo('%s: %d hair_markers messages checked', NAME, count)
        self.assertTrue(self.marker_parser_checked, 'the marker reader was never checked against genpy')
        self.assertEqual(problems, [], 'malformed hair_markers: %s' % '\n'.join(problems))

    # -- (e) a normal run logs no error (tf2_ros's Buffer once logged one on every lookup with a timeout)
    def test_e_no_errors_logged(self):
        self.wait_for(lambda: self.marker_count >= 30, 15.0, '30 hair_markers messages')
        with self.lock:
            errors = list(self.node_errors)
        self.assertEqual(errors[:3], [], '%d errors logged by %s, first ones above' % (len(errors), self.node_name))

    # -- (f) ~tcp_nodelay: the node turns Nagle's algorithm off on its subscribers' connections
    @staticmethod
    def tcp_ends(s):
        """(local, peer) addresses of a connected IPv4 / IPv6 TCP socket, else None (a listening socket has no
        peer)."""
        if s.family not in (socket.AF_INET, socket.AF_INET6) or s.type != socket.SOCK_STREAM:
            return None
        try:
            return s.getsockname(), s.getpeername()
        except OSError:
            return None

    @classmethod
    def connections_to(cls, port):
        """Local (host, port) of this process's TCP connections to `port`."""
        mine = set()
        for name in os.listdir('/proc/self/fd'):
            try:
                s = socket.socket(fileno=os.dup(int(name)))
            except OSError:  # not a socket (or closed meanwhile)
                continue
            try:
                ends = cls.tcp_ends(s)
                if ends and ends[1][1] == port:
                    mine.add(ends[0])
            finally:
                s.close()
        return mine

    def test_f_subscribers_get_tcp_nodelay(self):
        uri = rosgraph.Master('/' + NAME).lookupNode(self.node_name)
        node = ServerProxy(uri)
        code, _, pid = node.getPid('/' + NAME)
        self.assertEqual(code, 1, 'getPid of %s' % self.node_name)
        # The node's TCPROS port: where it tells a subscriber of hair_markers to connect.
        code, _, protocol = node.requestTopic('/' + NAME, '/hair_markers', [['TCPROS']])
        self.assertEqual(code, 1, 'requestTopic(/hair_markers) of %s: %s' % (self.node_name, protocol))
        port = int(protocol[2])
        if not hasattr(os, 'pidfd_open'):
            self.skipTest('os.pidfd_open needs Python 3.9 and Linux 5.3')
        # A new subscription (rospy does not ask for TCP_NODELAY) to an output this process has not
        # subscribed to (rospy shares one connection among a process's subscribers of a topic): its
        # connection is the one this process has now and did not have before. (This process's /rosout
        # subscription also connects to the node's port, to roscpp's own /rosout publisher, which has no
        # connect callback: the node sets it only if a subscriber of its own outputs connects later.)
        before = self.connections_to(port)
        got = {'collision_bodies': 0}

        def counter(topic):
            def count(_):
                got[topic] += 1
            return count
        subs = [rospy.Subscriber(topic, rospy.AnyMsg, counter(topic), queue_size=1) for topic in got]
        try:
            self.wait_for(lambda: min(got.values()) >= 1, 10.0, 'collision_bodies (latched) on a new subscription')
            new = self.connections_to(port) - before
            self.assertEqual(len(new), 1, 'new connections to the node\'s port %d: %s' % (port, sorted(new)))
            # The node sets the option when its connect callback runs, right after the link is made: wait a
            # little for it.
            deadline = time.time() + 2.0
            while True:
                accepted = self.node_tcp_nodelay(int(pid), port)
                missing = [peer for peer in new if peer not in accepted]
                self.assertEqual(missing, [], 'the node has no socket accepted from %s (it has %s)' %
                                 (missing, sorted(accepted)))
                off = [peer for peer in new if not accepted[peer]]
                if not off or time.time() > deadline:
                    break
                time.sleep(0.1)
            rospy.loginfo('%s: connections accepted on port %d (TCP_NODELAY): %s; the new subscriptions: %s', NAME,
                          port, accepted, sorted(new))
            self.assertEqual(off, [], 'new subscriptions\' connections without TCP_NODELAY on the node\'s side: %s' %
                             off)
        finally:
            for sub in subs:
                sub.unregister()

    def node_tcp_nodelay(self, pid, port):
        """{peer: TCP_NODELAY} of the node's connections accepted on `port`, from copies of its descriptors
        (pidfd_getfd); skips the test without the right to take them."""
        libc = ctypes.CDLL(None, use_errno=True)
        pidfd = os.pidfd_open(pid)
        accepted = {}
        try:
            for name in os.listdir('/proc/%d/fd' % pid):
                try:
                    if not os.readlink('/proc/%d/fd/%s' % (pid, name)).startswith('socket:'):
                        continue
                except OSError:  # closed meanwhile
                    continue
                fd = libc.syscall(438, pidfd, int(name), 0)  # pidfd_getfd: a copy of the node's descriptor
                if fd < 0:
                    err = ctypes.get_errno()
                    if err in (errno.EPERM, errno.EACCES, errno.ENOSYS):
                        self.skipTest('cannot read the node\'s sockets (pidfd_getfd: %s)' % os.strerror(err))
                    continue
                s = socket.socket(fileno=fd)
                try:
                    ends = self.tcp_ends(s)
                    if ends and ends[0][1] == port:
                        accepted[ends[1]] = s.getsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY)
                finally:
                    s.close()  # the copy only
        finally:
            os.close(pidfd)
        return accepted

if __name__ == '__main__':
    rostest.rosrun(PKG, NAME, HairNodeChecks, sys.argv)
