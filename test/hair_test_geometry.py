"""Geometry shared by the hair_sim rostest scripts: rotations, rigid poses from tf, and the body
ellipsoids of config/hair_sim.yaml (plain Python, no numpy on Debian's ROS install)."""

import collections
import math
import os
import time

import yaml

Point = collections.namedtuple('Point', 'x y z')


def strip_points(strip):
    """A hair_sim_msgs/StripState's control points (its xyz: float32 x, y, z per point, row-major) as
    Point(x, y, z) tuples."""
    v = strip.xyz
    return [Point(v[i], v[i + 1], v[i + 2]) for i in range(0, len(v) - 2, 3)]


def quat_to_matrix(x, y, z, w):
    n = math.sqrt(x * x + y * y + z * z + w * w)
    x, y, z, w = x / n, y / n, z / n, w / n
    return ((1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)),
            (2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)),
            (2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)))


def rpy_to_matrix(roll, pitch, yaw):
    """R = Rz(yaw) Ry(pitch) Rx(roll), as tf2's setRPY and the config's bodies."""
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    return ((cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr),
            (sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr),
            (-sp, cp * sr, cp * cr))


def mat_vec(m, v):
    return (m[0][0] * v[0] + m[0][1] * v[1] + m[0][2] * v[2],
            m[1][0] * v[0] + m[1][1] * v[1] + m[1][2] * v[2],
            m[2][0] * v[0] + m[2][1] * v[1] + m[2][2] * v[2])


def mat_t_vec(m, v):
    return (m[0][0] * v[0] + m[1][0] * v[1] + m[2][0] * v[2],
            m[0][1] * v[0] + m[1][1] * v[1] + m[2][1] * v[2],
            m[0][2] * v[0] + m[1][2] * v[1] + m[2][2] * v[2])


def mat_mul(a, b):
    return tuple(tuple(sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)) for i in range(3))


def transpose(m):
    return tuple(tuple(m[j][i] for j in range(3)) for i in range(3))


class Pose(object):
    """A rigid transform p_world = R p + t."""

    def __init__(self, rotation, translation):
        self.r = rotation
        self.t = translation

    @staticmethod
    def identity():
        return Pose(((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)), (0.0, 0.0, 0.0))

    @staticmethod
    def from_msg(transform_stamped):
        tr = transform_stamped.transform
        q = tr.rotation
        return Pose(quat_to_matrix(q.x, q.y, q.z, q.w), (tr.translation.x, tr.translation.y, tr.translation.z))

    def to_local(self, p):
        """World point -> coordinates in this frame."""
        return mat_t_vec(self.r, (p[0] - self.t[0], p[1] - self.t[1], p[2] - self.t[2]))


class Body(object):
    """An ellipsoid of the config: centre, rpy and radii in a tf frame."""

    def __init__(self, entry):
        self.name = entry['name']
        self.frame = entry['frame']
        self.center = tuple(float(v) for v in entry['center'])
        self.rotation = rpy_to_matrix(*[float(v) for v in entry.get('rpy', [0.0, 0.0, 0.0])])
        self.radii = tuple(float(v) for v in entry['radii'])

    def sphere_map(self, frame_pose, margin=0.0):
        """(M, o) with S^-1 (p - c) = M p - o for world points p, the body's frame at frame_pose; with margin
        (m), of the body inflated by it (every radius + margin, as the core's Ellipsoid::inflated)."""
        r = [radius + margin for radius in self.radii]
        scale = ((1.0 / r[0], 0.0, 0.0), (0.0, 1.0 / r[1], 0.0), (0.0, 0.0, 1.0 / r[2]))
        m = mat_mul(scale, mat_mul(transpose(self.rotation), transpose(frame_pose.r)))
        center_world = tuple(a + b for a, b in zip(mat_vec(frame_pose.r, self.center), frame_pose.t))
        return m, mat_vec(m, center_world)


def load_config(path):
    """The config file and the hairstyle file it names (relative to it), parsed."""
    with open(path) as f:
        config = yaml.safe_load(f)
    hairstyle_path = os.path.join(os.path.dirname(os.path.abspath(path)),
                                  config.get('hairstyle', 'hairstyles/default.yaml'))
    with open(hairstyle_path) as f:
        hairstyle = yaml.safe_load(f)
    return config, hairstyle


def closest_to_bodies(processed, bodies, margins, body_pose):
    """Over the (stamp, head pose, HairState) entries of processed: the smallest |S^-1 (p - c)| of a control
    point below the roots, against every body inflated by its strip's thickness margin (margins[strip], the
    hard guarantee of the core), and of a root, against the bodies' own radii (the roots sit on the scalp);
    each as (value, (t, strip, row, column, body)). body_pose(body, head, stamp) places a body's frame."""
    worst = (float('inf'), None)
    worst_root = (float('inf'), None)
    for stamp, head, msg in processed:
        poses = [body_pose(body, head, msg.header.stamp) for body in bodies]
        maps = {}  # margin -> the bodies' sphere maps inflated by it (one margin for most hairstyles)

        def inflated_by(margin):
            if margin not in maps:
                maps[margin] = [(body.name, body.sphere_map(pose, margin)) for body, pose in zip(bodies, poses)]
            return maps[margin]

        for s, strip in enumerate(msg.strips):
            for k, p in enumerate(strip_points(strip)):
                root = k < strip.columns
                for name, (m, o) in inflated_by(0.0 if root else margins[s]):
                    qx = m[0][0] * p.x + m[0][1] * p.y + m[0][2] * p.z - o[0]
                    qy = m[1][0] * p.x + m[1][1] * p.y + m[1][2] * p.z - o[1]
                    qz = m[2][0] * p.x + m[2][1] * p.y + m[2][2] * p.z - o[2]
                    q = math.sqrt(qx * qx + qy * qy + qz * qz)
                    if root:
                        if q < worst_root[0]:
                            worst_root = (q, (stamp, s, 0, k, name))
                    elif q < worst[0]:
                        worst = (q, (stamp, s, k // strip.columns, k % strip.columns, name))
    return worst, worst_root


# On |S^-1 (p - c)| of the control points below the roots (float32 in hair_state: ~1e-7 m).
INSIDE_TOLERANCE = 1e-5
# Roots (row 0) lie on the scalp ellipsoid by construction (|S^-1 (p - c)| = 1). The test knows the head pose
# at a state's stamp only to about 0.3 us of time (a double of seconds since 1970 resolves 0.24 us), which
# while the head moves at 1 m/s is a few 1e-6 of |S^-1 (p - c)|: roots get a looser tolerance.
ROOT_TOLERANCE = 1e-4


def assert_no_point_inside(test, name, log):
    """The check of a rostest's test_b_no_point_inside_a_body: over every state `test` has processed
    (test.processed, after test.process_new_states()), no control point below the roots inside a body of
    test.config inflated by its strip's thickness margin (test.hairstyle), and no root inside a body itself;
    the bodies in the head frame follow the state's head pose, the others are placed by test.lookup. Logs the
    closest approach with log (e.g. rospy.loginfo)."""
    test.process_new_states()
    test.assertTrue(test.processed, 'no hair_state received')
    head_frame_in_config = test.config.get('head_frame', 'head')

    def body_pose(body, head, stamp):
        return head if body.frame in (head_frame_in_config, test.head_frame) else test.lookup(body.frame, stamp)

    margins = [float(strip['thickness_margin']) for strip in test.hairstyle['strips']]
    worst, worst_root = closest_to_bodies(test.processed, test.bodies, margins, body_pose)
    log('%s: %d states checked; smallest |S^-1 (p - c)| = %.9f below the roots against the bodies inflated by '
        'the thickness margin (t, strip, row, column, body = %s), %.9f at the roots against the bodies (%s)'
        % (name, len(test.processed), worst[0], worst[1], worst_root[0], worst_root[1]))
    test.assertGreaterEqual(worst[0], 1.0 - INSIDE_TOLERANCE,
                            'control point inside an inflated body: |S^-1 (p - c)| = %.9f at (t, strip, row, '
                            'column, body) = %s' % (worst[0], worst[1]))
    test.assertGreaterEqual(worst_root[0], 1.0 - ROOT_TOLERANCE,
                            'root inside a body: |S^-1 (p - c)| = %.9f at (t, strip, row, column, body) = %s'
                            % (worst_root[0], worst_root[1]))


def wait_until(predicate, timeout, what, fail, alive=lambda: True, period=0.02):
    """Polls predicate() until it returns something true, which is returned; after timeout s (or when
    alive() turns false) calls fail('timed out ... waiting for <what>') (a TestCase's fail)."""
    deadline = time.time() + timeout
    while time.time() < deadline and alive():
        result = predicate()
        if result:
            return result
        time.sleep(period)
    fail('timed out after %.0f s waiting for %s' % (timeout, what))
