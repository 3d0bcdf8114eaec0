# shellcheck shell=bash
# Sourced by the test scripts that start their own roscore. free_port prints a TCP port for its master:
# below the kernel's ephemeral range (32768-60999 on Debian), from which every outgoing connection takes its
# local port, and free when checked (a plain bind on localhost, which a port in TIME_WAIT also fails). A
# random port in 20000-39999 had been taken by such a connection in one CI run ("Address already in use":
# roscore never came up).
free_port() {
  /usr/bin/python3 - <<'PY'
import random
import socket
import sys

low = 20000
high = 32000
try:
    with open('/proc/sys/net/ipv4/ip_local_port_range') as f:
        high = min(high, int(f.read().split()[0]) - 1)
except (OSError, ValueError, IndexError):
    pass
for _ in range(500):
    port = random.randint(low, high)
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        try:
            s.bind(('127.0.0.1', port))
        except OSError:
            continue
    print(port)
    sys.exit(0)
sys.exit('free_port: no free port in %d-%d' % (low, high))
PY
}
