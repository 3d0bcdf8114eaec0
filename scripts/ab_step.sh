#!/bin/bash
# Compares the step's wall time of another commit with the working tree's, in one sitting: builds
# hair_sim_step_profile (Release) of OLD in a git worktree under AB_DIR and of the working tree in
# build-release/, then runs the two alternately on one core (taskset: this VM's two vCPUs do not run alike)
# and prints each pair's ns per update, both medians and the median of the pairs' ratios (new / old). Each
# run also prints its state hash: the same hash means the same hair bit for bit.
#
# usage: scripts/ab_step.sh OLD_COMMIT [STRIPS=1000] [ROUNDS=8] [SUBSTEPS=480]
#   AB_DIR (default /tmp/hair_sim_ab): the old commit's source and build; AB_CORE (default 0): the core;
#   AB_THREADS (default 1): the step's threads (--threads); above 1 the runs are pinned to AB_CORES
#   (default: every core) instead of AB_CORE.
# On this shared VM one binary's runs differ by 20-30 % minutes apart: a change of a few per cent needs many
# rounds, and a median ratio within 0.95-1.05 is no evidence either way (docs/benchmarks.md).
set -euo pipefail
if [ $# -lt 1 ]; then
  sed -n '2,13p' "$0" >&2
  exit 2
fi
STRIPS=${2:-1000}
ROUNDS=${3:-8}
SUBSTEPS=${4:-480}
CORE=${AB_CORE:-0}
THREADS=${AB_THREADS:-1}
if ! [[ "$THREADS" =~ ^[1-9][0-9]*$ ]]; then
  echo "ab_step.sh: AB_THREADS must be a whole number >= 1, not '$THREADS'" >&2
  exit 2
fi
if [ "$THREADS" -gt 1 ]; then CORE=${AB_CORES:-0-$(($(nproc) - 1))}; fi
# shellcheck source=scripts/ab_build.sh
. "$(dirname "$0")/ab_build.sh"
ab_build "$1" hair_sim_step_profile

run() {  # binary -> "ns_per_update state_hash"
  taskset -c "$CORE" "$1" --strips "$STRIPS" --warmup 240 --substeps "$SUBSTEPS" --threads "$THREADS" |
    sed -n 's/.*"ns_per_update": \([0-9.]*\).*"state_hash": "\([0-9a-f]*\)".*/\1 \2/p'
}

echo "old $OLD, new: the working tree ($(git -C "$ROOT" rev-parse --short HEAD) + changes); $STRIPS strips," \
  "$SUBSTEPS substeps after 240, $THREADS thread(s), $ROUNDS rounds on core(s) $CORE"
results="$AB_DIR/results.txt"
: >"$results"
for i in $(seq 1 "$ROUNDS"); do
  read -r o oh <<<"$(run "$OLD_BIN")"
  read -r n nh <<<"$(run "$NEW_BIN")"
  echo "$o $n" >>"$results"
  printf 'round %d: old %s ns (%s), new %s ns (%s), new / old %.3f\n' "$i" "$o" "$oh" "$n" "$nh" \
    "$(echo "$n / $o" | bc -l)"
done
/usr/bin/python3 - "$results" <<'EOF'
import statistics, sys
rows = [tuple(map(float, line.split())) for line in open(sys.argv[1]) if line.strip()]
old = [o for o, _ in rows]
new = [n for _, n in rows]
ratios = [n / o for o, n in rows]
print(f"median ns per update: old {statistics.median(old):.1f}, new {statistics.median(new):.1f}; "
      f"new / old per pair: median {statistics.median(ratios):.3f}, {min(ratios):.3f}-{max(ratios):.3f}")
EOF
