#!/usr/bin/env python3
"""Writes the seed inputs of the fuzz targets (hair_sim/fuzz/) into test/fuzz_corpus/<target>/seed_*.

yaml:     the first byte picks the loader (0 config, 1 hairstyle, 2 scenario), then the file: the shipped
          config/hair_sim.yaml, config/scenarios/*.yaml, a three-strip cut of config/hairstyles/default.yaml.
messages: flags byte, then three chunks (uint16 little-endian length + bytes): a serialised
          hair_sim_msgs/Wind, hair_sim_msgs/HairEvent and tf2_msgs/TFMessage (ROS 1 wire format).
Run it from anywhere: python3 test/fuzz_corpus/make_seeds.py
"""
import glob
import math
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))


def write(target, name, data):
    os.makedirs(os.path.join(HERE, target), exist_ok=True)
    with open(os.path.join(HERE, target, "seed_" + name), "wb") as f:
        f.write(data)


def yaml_seeds():
    write("yaml", "config_hair_sim.yaml", b"\x00" + open(os.path.join(ROOT, "config/hair_sim.yaml"), "rb").read())
    for path in sorted(glob.glob(os.path.join(ROOT, "config/scenarios/*.yaml"))):
        write("yaml", "scenario_" + os.path.basename(path), b"\x02" + open(path, "rb").read())
    # A small hairstyle: the header and the first three strips of the default one.
    lines = open(os.path.join(ROOT, "config/hairstyles/default.yaml")).read().split("\n")
    out, strips = [], 0
    for line in lines:
        if line.startswith("  - name:"):
            strips += 1
            if strips > 3:
                break
        out.append(line)
    write("yaml", "hairstyle_default_3_strips.yaml", b"\x01" + ("\n".join(out) + "\n").encode())
    # A scenario with one event of every type.
    events = """duration: 2.0
output_rate: 30
head:
  - {t: 0.0, position: [0, 0, 1.6], rpy: [0, 0, 0]}
  - {t: 1.0, position: [0, 0.01, 1.6], rpy: [0.1, 0.2, 0.3]}
wind:
  - {t: 0.0, velocity: [0, 0, 0]}
  - {t: 1.0, velocity: [2, 0, 0]}
events:
  - {type: wind, start: 0.1, duration: 1.0, ease: 0.2, velocity: [1, 2, 0]}
  - {type: wind_gust, start: 0.2, duration: 1.0, ease: 0.1, mean: [3, 0, 0], peak: 6, period: 0.5, jitter: 0.2, seed: 4}
  - {type: turbulence, start: 0.3, duration: 1.0, intensity: 1.5, length_scale: 0.3, time_scale: 0.5, seed: 9}
  - {type: gravity, start: 0.4, acceleration: [0, 0, -5]}
  - {type: nod, start: 0.5, duration: 1.0, amplitude: 0.3, frequency: 2}
  - {type: shake, start: 0.5, duration: 1.0, amplitude: 0.3, frequency: 2}
  - {type: tilt, start: 0.5, duration: 1.0, amplitude: 0.3, frequency: 2}
  - {type: turn, start: 0.6, ease: 0.3, amplitude: 1.0}
"""
    write("yaml", "scenario_all_events.yaml", b"\x02" + events.encode())


def string(s):
    b = s.encode()
    return struct.pack("<I", len(b)) + b


def header(frame="", secs=0, nsecs=0):
    return struct.pack("<III", 0, secs, nsecs) + string(frame)


def wind(v=(3.0, 0.0, 0.0), turbulence=0.2, ramp=0.5, frame=""):
    return header(frame) + struct.pack("<5d", v[0], v[1], v[2], turbulence, ramp)


def event(kind, duration=1.0, ease=0.2, vector=(0.0, 0.0, 0.0), peak=0.0, period=2.0, jitter=0.0,
          intensity=0.0, length_scale=0.5, time_scale=1.0, amplitude=0.0, frequency=1.0, seed=1, secs=0):
    return (header("", secs) + string(kind) +
            struct.pack("<13dI", duration, ease, vector[0], vector[1], vector[2], peak, period, jitter,
                        intensity, length_scale, time_scale, amplitude, frequency, seed))


def tf(poses):
    out = struct.pack("<I", len(poses))
    for i, (p, q) in enumerate(poses):
        out += header("world", 1, i * 2083333) + string("head") + struct.pack("<7d", *p, *q)
    return out


def message_input(flags, w, e, t):
    out = bytes([flags])
    for chunk in (w, e, t):
        out += struct.pack("<H", len(chunk)) + chunk
    return out


def yaw(a):
    return (0.0, 0.0, math.sin(a / 2), math.cos(a / 2))


def messages_seeds():
    still = [((0.0, 0.0, 1.6), (0.0, 0.0, 0.0, 1.0))] * 4
    turning = [((0.0, 0.0, 1.6), yaw(0.2 * i)) for i in range(8)]
    write("messages", "wind_still_head", message_input(0, wind(), event("wind", vector=(1.0, 0.0, 0.0)), tf(still)))
    write("messages", "gust_turning_head",
          message_input(0, wind((0.0, 5.0, 0.0), 0.0, 0.0), event("wind_gust", vector=(4.0, 0.0, 0.0), peak=8.0,
                                                                  period=0.5, jitter=0.3, seed=3), tf(turning)))
    write("messages", "turbulence",
          message_input(0, wind((0.0, 0.0, 0.0), 0.0, 0.0), event("turbulence", intensity=2.0, length_scale=0.3,
                                                                  time_scale=0.4, seed=5), tf(turning)))
    write("messages", "gravity", message_input(0, wind(), event("gravity", vector=(0.0, 9.81, 0.0)), tf(still)))
    write("messages", "nod", message_input(0, wind(), event("nod", amplitude=0.5, frequency=2.0), tf(turning)))
    write("messages", "turn_stamped",
          message_input(1, wind(frame="head"), event("turn", duration=0.0, amplitude=1.0, secs=1), tf(turning)))
    write("messages", "bad_event_type", message_input(0, wind(), event("whirlwind"), tf(still)))


if __name__ == "__main__":
    yaml_seeds()
    messages_seeds()
