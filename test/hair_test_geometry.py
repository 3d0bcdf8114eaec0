"""Geometry shared by the hair_sim rostest scripts: rotations, rigid poses from tf, and the body
ellipsoids of config/hair_sim.yaml (plain Python, no numpy on Debian's ROS install)."""

import collections
import math
import time

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

    def sphere_map(self, frame_pose):
        """(M, o) with S^-1 (p - c) = M p - o for world points p, the body's frame at frame_pose."""
        scale = ((1.0 / self.radii[0], 0.0, 0.0), (0.0, 1.0 / self.radii[1], 0.0), (0.0, 0.0, 1.0 / self.radii[2]))
        m = mat_mul(scale, mat_mul(transpose(self.rotation), transpose(frame_pose.r)))
        center_world = tuple(a + b for a, b in zip(mat_vec(frame_pose.r, self.center), frame_pose.t))
        return m, mat_vec(m, center_world)


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
