#!/usr/bin/python3
"""rostest node for live_tuning.test: dynamic_reconfigure on a running hair_sim_node.

  test_live_parameters
      0. Waits for hair_state and sends a steady wind of 3 m/s along +x (Wind, ramp 0).
      1. render_mode strands: within 2 s hair_markers carries a LINE_LIST in ns 'strands' and no 'hair'
         mesh; render_mode mesh: the TRIANGLE_LIST is back. What rviz would show (every message's ADD and
         DELETE applied in order) follows: strands only, then the mesh only; both, then mesh: the strands
         are gone (a namespace a switch drops is deleted, not left behind).
      2. render_mode bogus: rejected, the server answers with the previous value (mesh) and the
         markers stay a mesh.
      3. samples_across 1, samples_along 2: the mesh has fewer points (both faces of
         2 (n_u - 1)(n_v - 1) triangles per strip); back to 2 x 4: the first count again.
         max_triangles 100, below the coarsest level's 800: refused (the reply and the configuration keep 0),
         the mesh unchanged; 3000: the ladder's 1 x 3 (2400 triangles, 7200 points); 0: 2 x 4 again.
      4. The wind bends the hair: mean tip x displacement from the windless start d_wind > 5 mm.
         wind_scale 0: the tips come back (|d| < d_wind / 4) within 6 s; wind_scale 1: bent again.
      5. hinge_stiffness x 10: the steady displacement drops below d_wind / 2 (a stiffer hinge bends less).
      6. spring_contact_fraction is 0.8 (the config file's and the default); 1.0 is taken and the hair keeps
         stepping.
      7. hinge_damping 5, beyond the cfg's [0, 0.1]: the server clamps it, the reply and the configuration
         say 0.1, and the hair keeps stepping.
      Throughout, HairState.step only grows: a change never resets the simulation.

A second node, /extreme/hair_sim, runs with settings at their extremes: publish_rate 200 (above head_driver's
100 Hz tf), render_mode strands and strands_per_strip 10000.

  test_p_publish_rate_above_the_tf_rate
      Its hair_state over 3 s: at most 5 % of the stamps not newer than the one before (the outputs follow the
      100 Hz tf; before, the timer sent the last output again between two tf messages: 141 Hz, a third of
      them repeats), and at least 50 Hz of them.
  test_s_markers_too_large_for_a_subscriber
      hair_markers would be 1.3 GB, beyond the 1 GB a roscpp subscriber accepts: subscribed to it, the node
      warns ('hair_markers not sent', naming ~strands_per_strip) and sends none, and its hair_state keeps
      coming (at least 50 Hz; before, it built the 1.3 GB at every output: 4.8 GB resident, the hair stalled
      for seconds at a time and no subscriber got anything).

Private parameters: node (default /hair_sim), extreme_node (default /extreme/hair_sim).
"""
import sys
import threading
import time
import unittest
from collections import namedtuple

import dynamic_reconfigure.client
import rospy
import rostest
from hair_sim_msgs.msg import HairState, Wind
from rosgraph_msgs.msg import Log
from visualization_msgs.msg import Marker, MarkerArray

PKG = 'hair_sim'
Point = namedtuple('Point', 'x y z')
NAME = 'live_tuning'
WIND = 3.0  # m/s along +x


class LiveTuning(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node(NAME)

    def setUp(self):
        self.lock = threading.Lock()
        self.state = None
        self.markers = None
        self.shown = {}  # (ns, id) -> marker type: what rviz shows after every message received
        self.steps = []
        rospy.Subscriber('hair_state', HairState, self.on_state, queue_size=2)
        rospy.Subscriber('hair_markers', MarkerArray, self.on_markers, queue_size=1, buff_size=1 << 24)
        self.wind_pub = rospy.Publisher('wind', Wind, queue_size=1, latch=True)

    def on_state(self, msg):
        with self.lock:
            self.state = msg
            self.steps.append(msg.step)

    def on_markers(self, msg):
        with self.lock:
            self.markers = (rospy.get_time(), msg)
            for m in msg.markers:
                if m.action == Marker.DELETEALL:
                    self.shown.clear()
                elif m.action == Marker.DELETE:
                    self.shown.pop((m.ns, m.id), None)
                else:
                    self.shown[(m.ns, m.id)] = m.type

    def wait_shown(self, expected, what, timeout=3.0):
        """rviz's markers from hair_markers (ns -> type) become `expected` within timeout."""
        deadline = time.time() + timeout
        while True:
            with self.lock:
                shown = {ns: t for (ns, _), t in self.shown.items()}
            if shown == expected:
                return
            self.assertLess(time.time(), deadline, 'within %.0f s rviz would not show %s (%s); it shows %s'
                            % (timeout, expected, what, shown))
            time.sleep(0.05)

    def tips(self):
        with self.lock:
            state = self.state
        tips = []
        for s in state.strips:
            for c in range(s.columns):
                k = 3 * ((s.rows - 1) * s.columns + c)  # xyz: x, y, z per point
                tips.append(Point(*s.xyz[k:k + 3]))
        return tips

    def mean_dx(self, rest):
        tips = self.tips()
        return sum(t.x - r.x for t, r in zip(tips, rest)) / len(rest)

    def wait_for(self, predicate, timeout, what):
        deadline = time.time() + timeout
        while not predicate():
            self.assertLess(time.time(), deadline, 'timed out after %.0f s waiting for %s' % (timeout, what))
            time.sleep(0.05)

    def wait_markers(self, predicate, what, timeout=3.0):
        """The first hair_markers (as {ns: marker}) that satisfies predicate within timeout."""
        deadline = time.time() + timeout
        while True:
            with self.lock:
                ns = {m.ns: m for m in self.markers[1].markers if m.action == Marker.ADD} if self.markers else {}
            if ns and predicate(ns):
                return ns
            self.assertLess(time.time(), deadline, 'within %.0f s no hair_markers with %s; last: %s'
                            % (timeout, what, {k: len(m.points) for k, m in ns.items()}))
            time.sleep(0.05)

    def settle(self, rest, seconds):
        """Mean tip displacement once it has stopped changing (max `seconds`)."""
        last = self.mean_dx(rest)
        end = time.time() + seconds
        while time.time() < end:
            time.sleep(0.5)
            now = self.mean_dx(rest)
            if abs(now - last) < 2e-4:
                return now
            last = now
        return last

    def reconfigure(self, **values):
        answer = self.client.update_configuration(values)
        time.sleep(0.3)  # the node takes them before its next substep (next timer tick)
        return answer

    def test_live_parameters(self):
        self.wait_for(lambda: self.state is not None, 30.0, 'hair_state')
        self.client = dynamic_reconfigure.client.Client(rospy.get_param('~node', '/hair_sim'), timeout=10.0)
        rest = self.tips()

        # 1. Render mode.
        self.reconfigure(render_mode='strands')
        ns = self.wait_markers(lambda ns: 'strands' in ns and 'hair' not in ns, 'strands only')
        self.assertEqual(ns['strands'].type, Marker.LINE_LIST)
        self.wait_shown({'strands': Marker.LINE_LIST}, 'mesh -> strands: the mesh deleted')
        self.reconfigure(render_mode='mesh')
        ns = self.wait_markers(lambda ns: 'hair' in ns and 'strands' not in ns, 'the mesh only')
        self.assertEqual(ns['hair'].type, Marker.TRIANGLE_LIST)
        mesh_points = len(ns['hair'].points)
        self.wait_shown({'hair': Marker.TRIANGLE_LIST}, 'strands -> mesh: the strands deleted')
        self.reconfigure(render_mode='both')
        self.wait_shown({'hair': Marker.TRIANGLE_LIST, 'strands': Marker.LINE_LIST}, 'both')
        self.reconfigure(render_mode='mesh')
        self.wait_shown({'hair': Marker.TRIANGLE_LIST}, 'both -> mesh: the strands deleted')

        # 2. A bad value is refused and the previous one kept.
        answer = self.reconfigure(render_mode='bogus')
        self.assertEqual(answer['render_mode'], 'mesh')
        self.assertEqual(self.client.get_configuration(timeout=5.0)['render_mode'], 'mesh')
        time.sleep(0.5)
        self.wait_markers(lambda ns: 'hair' in ns and 'strands' not in ns, 'the mesh only')

        # 3. Level of detail.
        self.reconfigure(samples_across=1, samples_along=2)
        ns = self.wait_markers(lambda ns: 0 < len(ns.get('hair', Marker()).points) < mesh_points / 2,
                               'fewer than half the %d mesh points' % mesh_points)
        rospy.loginfo('%s: level of detail 2 x 4: %d points, 1 x 2: %d points', NAME, mesh_points,
                      len(ns['hair'].points))
        self.reconfigure(samples_across=2, samples_along=4)
        self.wait_markers(lambda ns: len(ns.get('hair', Marker()).points) == mesh_points,
                          'the %d points of 2 x 4 again' % mesh_points)
        # A triangle budget below the coarsest level (1 x 1: 8 triangles for each of the 100 strips of 2 x 5)
        # cannot be met: refused, the previous value (0, off) kept.
        answer = self.reconfigure(max_triangles=100)
        self.assertEqual(answer['max_triangles'], 0, 'max_triangles 100 below the coarsest 800: the reply')
        self.assertEqual(self.client.get_configuration(timeout=5.0)['max_triangles'], 0)
        self.wait_markers(lambda ns: len(ns.get('hair', Marker()).points) == mesh_points,
                          'the %d points of 2 x 4 still' % mesh_points)
        answer = self.reconfigure(max_triangles=3000)
        self.assertEqual(answer['max_triangles'], 3000)
        self.wait_markers(lambda ns: len(ns.get('hair', Marker()).points) == 3 * 2400,
                          'the 3 x 2400 points of 1 x 3, the finest level within 3000 triangles')
        self.reconfigure(max_triangles=0)
        self.wait_markers(lambda ns: len(ns.get('hair', Marker()).points) == mesh_points,
                          'the %d points of 2 x 4 again' % mesh_points)

        # 4. Wind scale.
        wind = Wind()
        wind.header.stamp = rospy.Time.now()
        wind.velocity.x = WIND
        self.wind_pub.publish(wind)
        d_wind = self.settle(rest, 10.0)
        rospy.loginfo('%s: wind %.1f m/s: mean tip displacement %.4f m', NAME, WIND, d_wind)
        self.assertGreater(d_wind, 0.005)
        self.reconfigure(wind_scale=0.0)
        d_off = self.settle(rest, 8.0)
        rospy.loginfo('%s: wind_scale 0: %.4f m', NAME, d_off)
        self.assertLess(abs(d_off), d_wind / 4)
        self.reconfigure(wind_scale=1.0)
        d_on = self.settle(rest, 8.0)
        rospy.loginfo('%s: wind_scale 1: %.4f m', NAME, d_on)
        self.assertGreater(d_on, 0.75 * d_wind)

        # 5. Stiffness.
        k = self.client.get_configuration(timeout=5.0)['hinge_stiffness']
        self.reconfigure(hinge_stiffness=10 * k)
        d_stiff = self.settle(rest, 8.0)
        rospy.loginfo('%s: hinge_stiffness %.2g -> %.2g: %.4f m', NAME, k, 10 * k, d_stiff)
        self.assertLess(d_stiff, d_wind / 2)

        # 6. The spring band's contact edge: 0.8 at start, a new value taken while the hair runs.
        self.assertAlmostEqual(self.client.get_configuration(timeout=5.0)['spring_contact_fraction'], 0.8)
        answer = self.reconfigure(spring_contact_fraction=1.0)
        self.assertAlmostEqual(answer['spring_contact_fraction'], 1.0)
        with self.lock:
            before = self.steps[-1]
        self.wait_for(lambda: self.steps[-1] > before + 30, 5.0, 'substeps after spring_contact_fraction 1')

        # 7. A value beyond the cfg's range is clamped to its edge by the server (the reply says so); the hair
        # keeps stepping with it.
        answer = self.reconfigure(hinge_damping=5.0)
        self.assertEqual(answer['hinge_damping'], 0.1, 'hinge_damping 5 beyond [0, 0.1]: the reply')
        self.assertEqual(self.client.get_configuration(timeout=5.0)['hinge_damping'], 0.1)
        with self.lock:
            before = self.steps[-1]
        self.wait_for(lambda: self.steps[-1] > before + 30, 5.0, 'substeps after hinge_damping 0.1')

        with self.lock:
            steps = list(self.steps)
        self.assertTrue(all(b >= a for a, b in zip(steps, steps[1:])), 'the step count went back: a reset')

    def extreme_states(self):
        """/extreme's hair_state as (arrival, stamp) pairs, appended as they come."""
        node = rospy.get_param('~extreme_node', '/extreme/hair_sim')
        ns = node.rsplit('/', 1)[0]
        states = []
        sub = rospy.Subscriber(ns + '/hair_state', HairState,
                               lambda m: states.append((time.time(), m.header.stamp.to_sec())), queue_size=50)
        self.wait_for(lambda: len(states) > 0, 30.0, '%s/hair_state' % ns)
        return node, ns, states, sub

    def rate_since(self, states, start, seconds):
        return sum(1 for t, _ in states if t >= start) / seconds

    def test_p_publish_rate_above_the_tf_rate(self):
        node, ns, states, sub = self.extreme_states()
        start = time.time()
        time.sleep(3.0)
        window = [stamp for t, stamp in list(states) if t >= start]
        sub.unregister()
        repeats = sum(1 for a, b in zip(window, window[1:]) if b <= a)
        rospy.loginfo('%s: %s/hair_state (publish_rate 200, tf at 100 Hz): %.1f Hz, %d of %d stamps not newer '
                      'than the one before', NAME, ns, len(window) / 3.0, repeats, len(window))
        # (A tf message late by a whole interval lets the timer send the last output again: rare.)
        self.assertLessEqual(repeats, 0.05 * len(window),
                             '%d of %d hair_state not newer than the one before' % (repeats, len(window)))
        self.assertGreaterEqual(len(window) / 3.0, 50.0)

    def test_s_markers_too_large_for_a_subscriber(self):
        node, ns, states, sub = self.extreme_states()
        warnings = []
        markers = []
        log_sub = rospy.Subscriber('/rosout', Log, lambda m: warnings.append(m.msg)
                                   if m.name == node and 'hair_markers not sent' in m.msg else None, queue_size=100)
        self.wait_for(lambda: log_sub.get_num_connections() > 0, 10.0, 'a connection to /rosout')
        markers_sub = rospy.Subscriber(ns + '/hair_markers', rospy.AnyMsg, lambda m: markers.append(len(m._buff)),
                                       queue_size=1)
        self.wait_for(lambda: warnings, 8.0, "a warning 'hair_markers not sent' from %s" % node)
        rospy.loginfo('%s: %s', NAME, warnings[0])
        self.assertIn('strands_per_strip 10000', warnings[0])
        start = time.time()
        time.sleep(3.0)
        rate = self.rate_since(states, start, 3.0)
        markers_sub.unregister()
        sub.unregister()
        rospy.loginfo('%s: %s/hair_state at %.1f Hz with its hair_markers subscribed', NAME, ns, rate)
        self.assertGreaterEqual(rate, 50.0, '%s/hair_state with its hair_markers subscribed' % ns)
        self.assertEqual(markers, [], 'hair_markers of 1.3 GB sent')

if __name__ == '__main__':
    rostest.rosrun(PKG, NAME, LiveTuning, sys.argv)
