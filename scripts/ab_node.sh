#!/bin/bash
# Compares hair_sim_node of another commit with the working tree's, in one sitting, as ./run.sh bench measures
# the node: builds hair_sim_node (Release) of OLD in a git worktree under AB_DIR and of the working tree in
# build-release/ (scripts/ab_build.sh), then runs launch/demo.launch (rviz:=false) of the working tree with each
# node in turn (the binary put in build-release's devel space; it loads its own libraries by its RUNPATH) and
# measures it from outside with scripts/bench_node.py for SECONDS: CPU share with the markers subscribed and
# with hair_state alone, tf -> markers latency. Half the rounds run the old node first, half the new one first:
# on this VM the second node of a pair did worse in five of six pairs (docs/benchmarks.md, stop 46). Prints one
# line per window and the medians.
#
# usage: scripts/ab_node.sh OLD_COMMIT [ROUNDS=6] [SECONDS=20]
set -euo pipefail
if [ $# -lt 1 ]; then
  sed -n '2,10p' "$0" >&2
  exit 2
fi
ROUNDS=${2:-6}
SECONDS_PER_WINDOW=${3:-20}
# shellcheck source=scripts/ab_build.sh
. "$(dirname "$0")/ab_build.sh"
ab_build "$1" hair_sim_node
cmake --build "$ROOT/build-release" -j"$(nproc)" --target head_driver latency_probe >/dev/null
SAVED=$(mktemp -d /tmp/hair_sim_ab_node.XXXXXX)
cp "$OLD_BIN" "$SAVED/old"
cp "$NEW_BIN" "$SAVED/new"
trap 'cp "$SAVED/new" "$NEW_BIN"; rm -rf "$SAVED"' EXIT
: >"$SAVED/windows.jsonl"
for round in $(seq "$ROUNDS"); do
  order="old new"
  [ $((round % 2)) -eq 0 ] && order="new old"
  for side in $order; do
    cp "$SAVED/$side" "$NEW_BIN"
    NODE_ONLY=1 NODE_SECONDS=$SECONDS_PER_WINDOW "$ROOT/scripts/bench.sh"  # the node's window, as the bench's
    echo "{\"round\": $round, \"side\": \"$side\", \"node\": $(cat "$ROOT/build-release/node.json")}" >>"$SAVED/windows.jsonl"
    sleep 2
  done
done
/usr/bin/python3 - "$SAVED/windows.jsonl" "$OLD" <<'PY'
import json
import statistics
import sys

rows = [json.loads(line) for line in open(sys.argv[1])]
keys = [('cpu_share', 'CPU %', 100.0), ('state_only_cpu_share', 'CPU % (hair_state alone)', 100.0),
        ('latency_ms_p50', 'tf -> markers p50 ms', 1.0), ('latency_ms_p99', 'tf -> markers p99 ms', 1.0)]
for r in rows:
    n = r['node']
    print('round %d %s: ' % (r['round'], r['side']) +
          ', '.join('%s %.2f' % (label, scale * n[k]) for k, label, scale in keys if k in n))
print('old %s, new: the working tree; medians:' % sys.argv[2][:12])
for k, label, scale in keys:
    old = [scale * r['node'][k] for r in rows if r['side'] == 'old' and k in r['node']]
    new = [scale * r['node'][k] for r in rows if r['side'] == 'new' and k in r['node']]
    if old and new:
        print('  %s: old %.2f, new %.2f' % (label, statistics.median(old), statistics.median(new)))
PY
