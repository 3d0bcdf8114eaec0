#!/usr/bin/python3
"""rostest node for wind_checks.test: hair_sim_node with the head still (head_driver, mode still) in a
steady wind, compared with the offline runner.

  test_a_wind_equilibrium_matches_offline
      Publishes hair_sim_msgs/Wind (3 m/s along +x of the world frame, steady, no ramp) at 10 Hz, waits
      (at most 20 s) until the mean tip x in head coordinates stops changing: the means over consecutive
      1 s windows of hair_state differ by less than 0.5 mm. (A few strips pressed against the head keep
      fluttering in this wind, in the offline runner too, so single tips never come to rest: the mean over
      all tips does.) Asserts the tips moved +x (mean displacement > 5 mm), then runs hair_sim_offline on a
      scenario with the same head pose and the same wind from t = 0 for 15 s, and asserts that the node's
      mean tip x displacement (mean of the last two 1 s windows) is within 5 % of the offline one (mean of
      the frames of the last 3 s of the 15 s run, which includes the last frame; also logged alone).
  test_b_no_point_inside_a_body
      No control point of any HairState received (at rest and in the wind; at the default head height the
      hair reaches the neck, torso and shoulder bodies) lies inside a body of the config:
      |S^-1 (p - c)| >= 1 - 1e-5 against every body inflated by the strip's thickness margin (the core's
      hard guarantee), bodies placed by tf at the state's stamp; the roots (row 0), on the scalp by
      construction, against the bodies' own radii with 1e-4 (see ROOT_TOLERANCE in hair_test_geometry.py).

Private parameters: config_file (required), offline_bin (path of hair_sim_offline; if it does not exist,
it is looked up with roslib as hair_sim's executable hair_sim_offline), world_frame / head_frame (default:
the config's), driver (the head_driver node whose base_x/y/z are read, default /head_driver),
wind_speed (m/s, 3.0), tolerance (relative, 0.05).
"""
import csv
import os
import shutil
import subprocess
import sys
import tempfile
import threading
import time
import unittest

import rospy
import rostest
import tf2_ros
from hair_sim_msgs.msg import HairState, Wind

PKG = 'hair_sim'
NAME = 'wind_checks'

EQUILIBRIUM_TIMEOUT = 20.0  # s after the wind starts
WINDOW = 1.0  # s
EQUILIBRIUM_CHANGE = 0.0005  # m between consecutive window means
MIN_DISPLACEMENT = 0.005  # m
OFFLINE_DURATION = 15.0  # s
OFFLINE_AVERAGE = 3.0  # s at the end of the offline run


# ---------------------------------------------------------------------------------------------- geometry
# Shared geometry (this folder is not on sys.path when catkin's relay runs the script).
sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
from hair_test_geometry import Body, Pose, assert_no_point_inside, load_config, strip_points, wait_until  # noqa: E402

def mean(values):
    values = list(values)
    return sum(values) / len(values)


# ---------------------------------------------------------------------------------------------- offline
def find_offline_bin(path):
    if path and os.path.isfile(path) and os.access(path, os.X_OK):
        return path
    try:
        import roslib.packages
        found = roslib.packages.find_node(PKG, 'hair_sim_offline')
        if found:
            return found[0]
    except Exception as e:  # noqa: BLE001 - any failure of the fallback is reported below
        rospy.logwarn('%s: roslib could not find hair_sim_offline: %s', NAME, e)
    return None


def offline_displacement(offline_bin, config_file, head_position, wind, workdir):
    """Runs hair_sim_offline with the head still at head_position and the wind from t = 0; returns
    (mean over the last OFFLINE_AVERAGE s of the mean tip x displacement, the same at the last frame)."""
    scenario = os.path.join(workdir, 'wind_still.yaml')
    out = os.path.join(workdir, 'control_points.csv')
    with open(scenario, 'w') as f:
        f.write('# wind_checks.py: head still, steady wind from t = 0\n')
        f.write('duration: %.17g\noutput_rate: 30\n' % OFFLINE_DURATION)
        f.write('head:\n  - {t: 0.0, position: [%.17g, %.17g, %.17g], rpy: [0.0, 0.0, 0.0]}\n' % head_position)
        f.write('wind:\n  - {t: 0.0, velocity: [%.17g, %.17g, %.17g]}\n' % wind)
    command = [offline_bin, '--config', config_file, '--scenario', scenario, '--out', out]
    rospy.loginfo('%s: %s', NAME, ' '.join(command))
    result = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=300,
                            universal_newlines=True)
    if result.returncode != 0:
        raise AssertionError('hair_sim_offline failed (%d):\n%s' % (result.returncode, result.stdout[-3000:]))
    frames = {}  # t -> {(strip, column): (row, x)} keeping the last row
    with open(out) as f:
        for row in csv.DictReader(f):
            t = round(float(row['t']), 6)
            key = (int(row['strip']), int(row['column']))
            r = int(row['row'])
            tips = frames.setdefault(t, {})
            if key not in tips or tips[key][0] < r:
                tips[key] = (r, float(row['x']))
    times = sorted(frames)
    rest = frames[times[0]]

    def mean_dx(t):
        return mean(frames[t][k][1] - rest[k][1] for k in rest)

    last = [t for t in times if t >= times[-1] - OFFLINE_AVERAGE + 1e-9]
    return mean(mean_dx(t) for t in last), mean_dx(times[-1])


# ---------------------------------------------------------------------------------------------- the test
class WindChecks(unittest.TestCase):
    lock = threading.Lock()
    states = []
    next_index = 0
    processed = []  # (stamp seconds, head Pose, state)

    @classmethod
    def setUpClass(cls):
        rospy.init_node(NAME)
        cls.config_file = rospy.get_param('~config_file')
        cls.config, cls.hairstyle = load_config(cls.config_file)
        cls.world_frame = rospy.get_param('~world_frame', cls.config.get('world_frame', 'world'))
        cls.head_frame = rospy.get_param('~head_frame', cls.config.get('head_frame', 'head'))
        cls.offline_bin = rospy.get_param('~offline_bin', '')
        cls.speed = float(rospy.get_param('~wind_speed', 3.0))
        cls.tolerance = float(rospy.get_param('~tolerance', 0.05))
        driver = rospy.get_param('~driver', '/head_driver')
        cls.head_base = tuple(float(rospy.get_param(driver + '/base_' + a, d))
                              for a, d in (('x', 0.0), ('y', 0.0), ('z', 1.6)))
        cls.bodies = [Body(b) for b in cls.config.get('bodies', [])]
        cls.tf_buffer = tf2_ros.Buffer(rospy.Duration(300.0))
        cls.tf_listener = tf2_ros.TransformListener(cls.tf_buffer)
        cls.wind_pub = rospy.Publisher('wind', Wind, queue_size=10)
        cls.state_sub = rospy.Subscriber('hair_state', HairState, cls.on_state, queue_size=200)
        cls.wind_on = threading.Event()
        cls.wind_thread = threading.Thread(target=cls.publish_wind)
        cls.wind_thread.daemon = True
        cls.wind_thread.start()

    @classmethod
    def on_state(cls, msg):
        with cls.lock:
            cls.states.append(msg)

    @classmethod
    def publish_wind(cls):
        rate = rospy.Rate(10.0)
        while not rospy.is_shutdown():
            if cls.wind_on.is_set():
                msg = Wind()
                msg.header.frame_id = cls.world_frame
                msg.velocity.x = cls.speed
                cls.wind_pub.publish(msg)
            try:
                rate.sleep()
            except rospy.ROSInterruptException:
                return

    def lookup(self, frame, stamp, timeout=1.0):
        if frame == self.world_frame:
            return Pose.identity()
        return Pose.from_msg(self.tf_buffer.lookup_transform(self.world_frame, frame, stamp,
                                                             rospy.Duration(timeout)))

    def process_new_states(self):
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

    @staticmethod
    def tips_x(head, msg):
        """x of every tip (last row of each strip) in head coordinates."""
        out = []
        for strip in msg.strips:
            columns, rows = int(strip.columns), int(strip.rows)
            for c in range(columns):
                p = strip_points(strip)[(rows - 1) * columns + c]
                out.append(head.to_local((p.x, p.y, p.z))[0])
        return out

    def wait_for(self, predicate, timeout, what):
        return wait_until(predicate, timeout, what, self.fail, lambda: not rospy.is_shutdown())

    def test_a_wind_equilibrium_matches_offline(self):
        # The hair at rest first: two states in a row with the same tips.
        rest_states = []

        def at_rest():
            for stamp, head, msg in self.process_new_states():
                rest_states.append(self.tips_x(head, msg))
            return len(rest_states) >= 2 and max(abs(a - b) for a, b in zip(rest_states[-1], rest_states[-2])) < 1e-6

        self.wait_for(at_rest, 30.0, 'hair_state at rest (is hair_sim_node running, head_driver still?)')
        rest = rest_states[-1]
        head_position = self.processed[-1][1].t
        for a, b in zip(head_position, self.head_base):
            self.assertAlmostEqual(a, b, delta=1e-6, msg='head not at the base pose of head_driver')

        wind_start = rospy.Time.now().to_sec()
        self.wind_on.set()
        windows = []  # (window start, mean displacement)
        current = []
        window_start = None
        deadline = time.time() + EQUILIBRIUM_TIMEOUT + 10.0
        equilibrium = None
        while equilibrium is None:
            self.assertLess(time.time(), deadline, 'no equilibrium within %.0f s of the wind: window means %s'
                            % (EQUILIBRIUM_TIMEOUT, ['%.2f mm' % (1e3 * w[1]) for w in windows]))
            self.assertFalse(rospy.is_shutdown())
            new = self.process_new_states()
            if not new:
                time.sleep(0.02)
                continue
            for stamp, head, msg in new:
                if stamp <= wind_start:
                    continue
                self.assertLess(stamp - wind_start, EQUILIBRIUM_TIMEOUT,
                                'no equilibrium within %.0f s of the wind: window means %s'
                                % (EQUILIBRIUM_TIMEOUT, ['%.2f mm' % (1e3 * w[1]) for w in windows]))
                if window_start is None:
                    window_start = stamp
                if stamp >= window_start + WINDOW:
                    windows.append((window_start, mean(current)))
                    current, window_start = [], stamp
                    if len(windows) >= 3 and abs(windows[-1][1] - windows[-2][1]) < EQUILIBRIUM_CHANGE:
                        equilibrium = windows[-1][0] + WINDOW
                        break
                current.append(mean(x - r for x, r in zip(self.tips_x(head, msg), rest)))
        node_dx = (windows[-1][1] + windows[-2][1]) / 2.0
        rospy.loginfo('%s: equilibrium %.2f s after the wind; mean tip x displacement %.2f mm (windows %s)', NAME,
                      equilibrium - wind_start, 1e3 * node_dx, ['%.2f' % (1e3 * w[1]) for w in windows])
        self.assertGreater(node_dx, MIN_DISPLACEMENT, 'tips did not move downwind (+x): mean %.2f mm'
                           % (1e3 * node_dx))

        offline_bin = find_offline_bin(self.offline_bin)
        self.assertIsNotNone(offline_bin, "hair_sim_offline not found at ~offline_bin '%s' nor by roslib"
                             % self.offline_bin)
        workdir = tempfile.mkdtemp(prefix='hair_sim_wind_checks_')
        try:
            offline_dx, offline_last = offline_displacement(offline_bin, self.config_file, tuple(head_position),
                                                            (self.speed, 0.0, 0.0), workdir)
        finally:
            shutil.rmtree(workdir, ignore_errors=True)
        rospy.loginfo('%s: offline mean tip x displacement %.2f mm over the last %.0f s (last frame %.2f mm); '
                      'node %.2f mm', NAME, 1e3 * offline_dx, OFFLINE_AVERAGE, 1e3 * offline_last, 1e3 * node_dx)
        self.assertGreater(offline_dx, MIN_DISPLACEMENT)
        self.assertLessEqual(abs(node_dx - offline_dx), self.tolerance * abs(offline_dx),
                             'node %.2f mm vs offline %.2f mm: more than %.0f %% apart'
                             % (1e3 * node_dx, 1e3 * offline_dx, 100 * self.tolerance))

    def test_b_no_point_inside_a_body(self):
        assert_no_point_inside(self, NAME, rospy.loginfo)


if __name__ == '__main__':
    rostest.rosrun(PKG, NAME, WindChecks, sys.argv)
