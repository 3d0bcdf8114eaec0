#!/usr/bin/python3
"""Bakes a short run with hair_sim_offline --bag and reads the bag back with the rosbag API: the
expected topics, types and message counts, stamps at 1 s + t, finite control points that match the
--out CSV of the same run, and the latched collision_bodies connection. Also checks the progress
bar: drawn on a terminal (run under `script`), absent when stderr is a pipe.

Usage: bake_check.py OFFLINE_BIN REPO_ROOT
"""
import atexit
import csv
import math
import os
import shutil
import subprocess
import sys
import tempfile

import rosbag

SCENARIO = """duration: 1.0
output_rate: 10
head:
  - {t: 0.0, position: [0.0, 0.0, 1.6], rpy: [0.0, 0.0, 0.0]}
events:
  - {type: shake, start: 0.2, duration: 0.8, ease: 0.2, amplitude: 0.5, frequency: 2.0}
  - {type: wind, start: 0.0, ease: 0.3, velocity: [0.0, 3.0, 0.0]}
"""
FRAMES = 11  # t = 0, 0.1, ..., 1.0


def check(condition, message):
    if not condition:
        print('bake_check: FAILED: ' + message)
        sys.exit(1)


def main():
    offline, repo = sys.argv[1], sys.argv[2]
    work = tempfile.mkdtemp(prefix='hair_sim_bake_')
    atexit.register(shutil.rmtree, work, True)  # (also after a failed check's sys.exit)
    scenario = os.path.join(work, 'short.yaml')
    with open(scenario, 'w') as f:
        f.write(SCENARIO)
    bag_path = os.path.join(work, 'run.bag')
    csv_path = os.path.join(work, 'points.csv')
    config = os.path.join(repo, 'config', 'hair_sim.yaml')
    run = subprocess.run([offline, '--config', config, '--scenario', scenario, '--bag', bag_path, '--out', csv_path],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True, timeout=300)
    check(run.returncode == 0, 'hair_sim_offline failed:\n' + run.stderr)
    check('[' not in run.stderr, 'a progress bar was drawn although stderr is a pipe:\n' + run.stderr)

    counts, types, stamps = {}, {}, {}
    last_state = None
    with rosbag.Bag(bag_path) as bag:
        info = bag.get_type_and_topic_info()
        for topic, topic_info in info.topics.items():
            types[topic] = topic_info.msg_type
        for topic, msg, t in bag.read_messages():
            counts[topic] = counts.get(topic, 0) + 1
            stamps.setdefault(topic, []).append(t.to_sec())
            if topic == '/hair_state':
                last_state = msg
        latched = [c for c in bag._connections.values() if c.topic == '/collision_bodies']
    expected_types = {'/tf': 'tf2_msgs/TFMessage', '/hair_markers': 'visualization_msgs/MarkerArray',
                      '/collision_bodies': 'visualization_msgs/MarkerArray', '/hair_state': 'hair_sim_msgs/HairState'}
    check(types == expected_types, 'topics and types: %s' % types)
    for topic in ('/tf', '/hair_markers', '/hair_state'):
        check(counts[topic] == FRAMES, '%s: %d messages, expected %d' % (topic, counts[topic], FRAMES))
        check(all(abs(s - (1.0 + 0.1 * k)) < 1e-6 for k, s in enumerate(stamps[topic])), '%s stamps %s' % (topic, stamps[topic]))
    # The head body moves with the shake: bodies are written again whenever the head turned.
    check(2 <= counts['/collision_bodies'] <= FRAMES, '/collision_bodies: %d messages' % counts['/collision_bodies'])
    check(latched and all(c.header.get('latching') in ('1', b'1') for c in latched), '/collision_bodies is not latched')

    # The last hair_state equals the last frame of the CSV (same run, same order).
    with open(csv_path) as f:
        rows = [r for r in csv.DictReader(f) if abs(float(r['t']) - 1.0) < 1e-9]
    points = [tuple(s.xyz[i:i + 3]) for s in last_state.strips for i in range(0, len(s.xyz), 3)]
    check(len(points) == len(rows) == 1000, '%d points in hair_state, %d in the CSV' % (len(points), len(rows)))
    # CSV rows go strip by strip, row by row, column by column: the order of StripState.xyz (float32).
    worst = max(math.dist(p, (float(r['x']), float(r['y']), float(r['z']))) for p, r in zip(points, rows))
    check(worst < 1e-6, 'hair_state and CSV differ by %.3g m' % worst)
    check(all(math.isfinite(v) for p in points for v in p), 'non-finite control point')

    # Progress bar on a terminal: a run that takes well over a second, under script(1). The bar starts after one
    # second of wall time: 40 simulated seconds once took 0.7 s here (73 ns per update), so 400 (about 7 s).
    long_scenario = os.path.join(work, 'long.yaml')
    with open(long_scenario, 'w') as f:
        f.write(SCENARIO.replace('duration: 1.0', 'duration: 400.0').replace('output_rate: 10', 'output_rate: 2'))
    command = '%s --config %s --scenario %s --out /dev/null' % (offline, config, long_scenario)
    tty = subprocess.run(['script', '-qefc', command, '/dev/null'], stdout=subprocess.PIPE,
                         stderr=subprocess.STDOUT, universal_newlines=True, timeout=300)
    check(tty.returncode == 0, 'the run under script failed:\n' + tty.stdout[-2000:])
    check('hair_sim_offline: [' in tty.stdout and '%  t = ' in tty.stdout, 'no progress bar on a terminal:\n' + tty.stdout[-2000:])
    print('bake_check: OK: %s, %d messages; progress bar on a terminal only' % (counts, sum(counts.values())))


if __name__ == '__main__':
    main()
