#!/usr/bin/python3
"""Compares hair_state of a live run (live.bag) with that of a replay of its tf and wind (replay.bag),
for rosbag_roundtrip.sh.

hair_sim_node steps on a grid of substeps fixed in ROS time (multiples of the substep), samples the head tf
at those instants, starts a wind ramp at the Wind message's header.stamp and publishes on the first head
pose stamped at or after each multiple of 1/publish_rate, the output stamped with that pose's stamp. A
replay of the same tf and wind with use_sim_time therefore publishes states with the same stamps, computed
from the same inputs: each replayed state is compared with the live state of the same stamp (to the
nanosecond). Both runs start from the rest shape with the head still, which is where the live hair is when
the recording starts.

Asserted: at least MIN_PAIRS pairs (of about 290 states in the 10 s), at least 95 % of the replayed states
have a live state of the same stamp, the largest control-point distance over every pair < MAX_TOL, and the
live hair moved by > 10 mm over them (the wind and the head's move, so the comparison is not between two
still heads). Measured on the development VM: every pair bit-identical (distance 0). MAX_TOL leaves room for
one race the grid does not remove: a Wind message that reaches the live node after it stepped past the
message's stamp (the replay may see it before) changes the first substep or two of the ramp, a wind of
under 0.02 m/s for 4 ms.
"""
import sys

import rosbag

MIN_PAIRS = 250
MATCHED_FRACTION = 0.95
MAX_TOL = 0.001  # m


def states(path):
    with rosbag.Bag(path) as bag:
        return {(m.header.stamp.secs, m.header.stamp.nsecs):
                [tuple(s.xyz[i:i + 3]) for s in m.strips for i in range(0, len(s.xyz), 3)]
                for _, m, _ in bag.read_messages(topics=['/hair_state'])}


def distance(p, q):
    return sum((x - y) ** 2 for x, y in zip(p, q)) ** 0.5


def main(live_path, replay_path):
    live = states(live_path)
    replay = states(replay_path)
    stamps = sorted(set(live) & set(replay))
    worst, total, count, identical = 0.0, 0.0, 0, 0
    for k in stamps:
        a, b = live[k], replay[k]
        if len(a) != len(b):
            print('rosbag_compare: FAIL: %d live and %d replayed control points at %d.%09d' % (len(a), len(b), *k))
            return 1
        d = [distance(p, q) for p, q in zip(a, b)]
        worst = max(worst, max(d))
        total += sum(d)
        count += len(d)
        identical += a == b
    moved = max(distance(p, q) for p, q in zip(live[stamps[0]], live[stamps[-1]])) if stamps else 0.0
    matched = len(stamps) / len(replay) if replay else 0.0
    span = (stamps[-1][0] - stamps[0][0]) + 1e-9 * (stamps[-1][1] - stamps[0][1]) if stamps else 0.0
    print('rosbag_compare: %d live, %d replayed states; %d of the same stamp (%.1f %% of the replayed) over %.1f s, '
          '%d bit-identical; control-point distance max %.3g mm, mean %.3g mm; live hair moved up to %.1f mm'
          % (len(live), len(replay), len(stamps), 100 * matched, span, identical, 1e3 * worst,
             1e3 * total / count if count else 0.0, 1e3 * moved))
    ok = len(stamps) >= MIN_PAIRS and matched >= MATCHED_FRACTION and worst < MAX_TOL and moved > 0.01
    print('rosbag_compare: %s (need >= %d pairs of the same stamp, >= %.0f %% of the replayed states paired, '
          'all < %.0f mm, moved > 10 mm)' % ('OK' if ok else 'FAIL', MIN_PAIRS, 100 * MATCHED_FRACTION, 1e3 * MAX_TOL))
    return 0 if ok else 1


if __name__ == '__main__':
    sys.exit(main(sys.argv[1], sys.argv[2]))
