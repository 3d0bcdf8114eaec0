#!/usr/bin/python3
"""Measures a running hair_sim_node from outside (called by scripts/bench.sh):

  cpu      share of one core used by the node's process over the window (/proc/PID/stat utime+stime)
  rate     hair_markers messages per second received
  latency  receipt time of each hair_markers (and hair_state) message in a C++ subscriber (latency_probe,
           after deserialisation, as rviz receives it) minus its header.stamp, which is the stamp of the
           newest head tf the output reflects (head_driver stamps tf with the time it sends it): from a tf
           update to the markers that reflect it, transport both ways included
  bytes    serialized size of each hair_markers message
Then a second window with hair_state alone subscribed (as with the rviz display plugin): CPU, rate,
latency.

Prints one JSON object. Usage: bench_node.py PID SECONDS PROBE (PROBE: the latency_probe executable)
"""
import json
import os
import subprocess
import sys
import time


def cpu_seconds(pid):
    with open('/proc/%d/stat' % pid) as f:
        fields = f.read().rsplit(')', 1)[1].split()
    # fields[0] is the state (field 3); utime and stime are fields 14 and 15.
    ticks = os.sysconf(os.sysconf_names['SC_CLK_TCK'])
    return (int(fields[11]) + int(fields[12])) / ticks


def window(pid, seconds, probe, markers, extra=()):
    """One measuring window: the probe's latencies and the node's CPU share over the same time; `extra`:
    more private parameters of the probe ('_name:=value')."""
    proc = subprocess.Popen([probe, '_seconds:=%g' % seconds, '_markers:=%s' % ('true' if markers else 'false')]
                            + list(extra), stdout=subprocess.PIPE, universal_newlines=True)
    line = proc.stdout.readline().strip()
    if line != 'recording':
        proc.wait()
        return json.loads(line) if line.startswith('{') else {'error': 'latency_probe: %r' % line}
    cpu0, wall0 = cpu_seconds(pid), time.time()
    result = json.loads(proc.stdout.readline())
    cpu1, wall1 = cpu_seconds(pid), time.time()
    proc.wait()
    result['cpu_share'] = (cpu1 - cpu0) / (wall1 - wall0)
    return result


def main():
    pid, seconds, probe = int(sys.argv[1]), float(sys.argv[2]), sys.argv[3]
    both = window(pid, seconds, probe, True)
    if 'error' in both:
        print(json.dumps(both))
        sys.exit(1)
    m, s = both['markers'], both['state']
    result = {
        'seconds': both['seconds'],
        'cpu_share': both['cpu_share'],
        'rate_hz': m['rate_hz'],
        'latency_ms_p50': m['latency_ms_p50'],
        'latency_ms_p99': m['latency_ms_p99'],
        'latency_ms_max': m['latency_ms_max'],
        'bytes_per_message': m['bytes'],
        'state_latency_ms_p50': s['latency_ms_p50'],
        'state_latency_ms_p99': s['latency_ms_p99'],
        'messages': m['messages'],
    }
    # Second window: hair_state alone (what the rviz display hair_sim/HairDisplay subscribes to); the
    # node builds no markers without a subscriber.
    alone = window(pid, seconds, probe, False)
    if 'error' not in alone:
        result.update({
            'state_only_cpu_share': alone['cpu_share'],
            'state_only_rate_hz': alone['state']['rate_hz'],
            'state_only_latency_ms_p50': alone['state']['latency_ms_p50'],
            'state_only_latency_ms_p99': alone['state']['latency_ms_p99'],
        })
    print(json.dumps(result))


if __name__ == '__main__':
    main()
