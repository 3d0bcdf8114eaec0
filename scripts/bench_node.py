#!/usr/bin/python3
"""Measures a running hair_sim_node from outside (called by scripts/bench.sh):

  cpu      share of one core used by the node's process over the window (/proc/PID/stat utime+stime)
  rate     hair_markers messages per second received
  latency  receipt time of each hair_markers (and hair_state) message minus its header.stamp, which is the stamp of
           the newest head tf the markers reflect (head_driver stamps tf with the time it sends it):
           from a tf update to the markers that reflect it, transport both ways included
  bytes    serialized size of each hair_markers message
Then a second window with hair_state alone subscribed (as with the rviz display plugin): CPU, rate,
latency.

Prints one JSON object. Usage: bench_node.py PID SECONDS
"""
import json
import struct
import sys
import time

import rospy


def cpu_seconds(pid):
    with open('/proc/%d/stat' % pid) as f:
        fields = f.read().rsplit(')', 1)[1].split()
    # fields[0] is the state (field 3); utime and stime are fields 14 and 15.
    import os
    ticks = os.sysconf(os.sysconf_names['SC_CLK_TCK'])
    return (int(fields[11]) + int(fields[12])) / ticks


def percentile(values, p):
    values = sorted(values)
    k = min(len(values) - 1, max(0, int(round(p / 100.0 * (len(values) - 1)))))
    return values[k]


def main():
    pid, seconds = int(sys.argv[1]), float(sys.argv[2])
    rospy.init_node('bench_node', anonymous=True)
    latencies, sizes, state_latencies = [], [], []

    def on_state(msg):
        # HairState: Header first: uint32 seq, uint32 secs, uint32 nsecs.
        secs, nsecs = struct.unpack_from('<II', msg._buff, 4)
        state_latencies.append(rospy.get_rostime().to_sec() - (secs + 1e-9 * nsecs))

    def on_markers(msg):
        now = rospy.get_rostime().to_sec()
        raw = msg._buff
        # MarkerArray: uint32 count, then the first Marker's Header: uint32 seq, uint32 secs, uint32 nsecs.
        secs, nsecs = struct.unpack_from('<II', raw, 8)
        latencies.append(now - (secs + 1e-9 * nsecs))
        sizes.append(len(raw))

    markers_sub = rospy.Subscriber('hair_markers', rospy.AnyMsg, on_markers, queue_size=100, buff_size=1 << 26)
    rospy.Subscriber('hair_state', rospy.AnyMsg, on_state, queue_size=100, buff_size=1 << 22)
    deadline = time.time() + 30.0
    while not latencies and time.time() < deadline:
        time.sleep(0.05)
    if not latencies:
        print(json.dumps({'error': 'no hair_markers within 30 s'}))
        sys.exit(1)
    time.sleep(2.0)  # let the subscription settle
    del latencies[:]
    del sizes[:]
    del state_latencies[:]
    cpu0, wall0 = cpu_seconds(pid), time.time()
    time.sleep(seconds)
    cpu1, wall1 = cpu_seconds(pid), time.time()
    n = len(latencies)
    result = {
        'seconds': wall1 - wall0,
        'cpu_share': (cpu1 - cpu0) / (wall1 - wall0),
        'rate_hz': n / (wall1 - wall0),
        'latency_ms_p50': 1e3 * percentile(latencies, 50),
        'latency_ms_p99': 1e3 * percentile(latencies, 99),
        'latency_ms_max': 1e3 * max(latencies),
        'bytes_per_message': sum(sizes) / n,
        'state_latency_ms_p50': 1e3 * percentile(state_latencies, 50),
        'state_latency_ms_p99': 1e3 * percentile(state_latencies, 99),
        'messages': n,
    }
    # Second window: hair_state alone (what the rviz display hair_sim/HairDisplay subscribes to); the
    # node builds no markers without a subscriber.
    markers_sub.unregister()
    time.sleep(2.0)
    del state_latencies[:]
    cpu0, wall0 = cpu_seconds(pid), time.time()
    time.sleep(seconds)
    cpu1, wall1 = cpu_seconds(pid), time.time()
    result.update({
        'state_only_cpu_share': (cpu1 - cpu0) / (wall1 - wall0),
        'state_only_rate_hz': len(state_latencies) / (wall1 - wall0),
        'state_only_latency_ms_p50': 1e3 * percentile(state_latencies, 50),
        'state_only_latency_ms_p99': 1e3 * percentile(state_latencies, 99),
    })
    print(json.dumps(result))


if __name__ == '__main__':
    main()
