#!/bin/bash
# Compares Google Benchmark results of another commit with the working tree's, in one sitting: builds
# hair_sim_bench (Release) of OLD in a git worktree under AB_DIR and of the working tree in build-release/,
# then runs the two alternately on one core, each run the benchmarks matching FILTER once, and prints each
# benchmark's time per item (1e9 / items_per_second, e.g. ns per vertex) per round, both medians and the
# median of the pairs' ratios (new / old), with their range.
#
# usage: scripts/ab_bench.sh OLD_COMMIT FILTER [ROUNDS=8] [MIN_TIME=0.5]
#   AB_DIR (default /tmp/hair_sim_ab): the old commit's source and build; AB_CORE (default 1): the core.
# Alternating pairs cancel the host's slow drifts; only a median ratio whose range stays off 1.0 is evidence
# (docs/benchmarks.md).
set -euo pipefail
if [ $# -lt 2 ]; then
  sed -n '2,11p' "$0" >&2
  exit 2
fi
FILTER="$2"
ROUNDS=${3:-8}
MIN_TIME=${4:-0.5}
CORE=${AB_CORE:-1}
# shellcheck source=scripts/ab_build.sh
. "$(dirname "$0")/ab_build.sh"
ab_build "$1" hair_sim_bench

echo "old $OLD, new: the working tree ($(git -C "$ROOT" rev-parse --short HEAD) + changes);" \
  "benchmarks '$FILTER', $ROUNDS rounds on core $CORE"
runs="$AB_DIR/bench_runs"
rm -rf "$runs"
mkdir -p "$runs"
for i in $(seq 1 "$ROUNDS"); do
  for side in old new; do
    bin="$OLD_BIN"
    [ "$side" = new ] && bin="$NEW_BIN"
    taskset -c "$CORE" "$bin" --benchmark_filter="$FILTER" --benchmark_min_time="$MIN_TIME" \
      --benchmark_format=json >"$runs/$side.$i.json" 2>/dev/null
  done
done
/usr/bin/python3 - "$runs" "$ROUNDS" <<'PY'
import json, os, statistics, sys
runs, rounds = sys.argv[1], int(sys.argv[2])
def per_item(path):
    with open(path) as f:
        return {b['name']: 1e9 / b['items_per_second'] for b in json.load(f)['benchmarks']
                if b.get('items_per_second')}
pairs = [(per_item(os.path.join(runs, 'old.%d.json' % i)), per_item(os.path.join(runs, 'new.%d.json' % i)))
         for i in range(1, rounds + 1)]
names = [n for n in pairs[0][0] if all(n in o and n in m for o, m in pairs)]
if not names:
    sys.exit('ab_bench: no benchmark with items_per_second matched in both builds')
for name in names:
    old = [o[name] for o, _ in pairs]
    new = [m[name] for _, m in pairs]
    ratios = [m / o for o, m in zip(old, new)]
    print('%s: ns per item, old %s' % (name, ' '.join('%.2f' % x for x in old)))
    print('%s  new %s' % (' ' * len(name), ' '.join('%.2f' % x for x in new)))
    print('%s  medians old %.2f, new %.2f; new / old per pair: median %.3f, %.3f-%.3f' % (
        ' ' * len(name), statistics.median(old), statistics.median(new), statistics.median(ratios),
        min(ratios), max(ratios)))
PY
