#!/bin/bash
# What each part of the model costs the step: runs hair_sim_step_profile (Release, build-release/) with
# config/hair_sim.yaml and four copies of it (no bodies and no springs; no bodies; the head alone; no springs),
# ROUNDS times through all five in turn at each number of strips, on one core, and prints each configuration's
# median ns per update, the real-time factor at 240 substeps per second, the share of strips in the exact
# step and the state hash (docs/benchmarks.md, stop 42).
#
# usage: scripts/step_parts.sh [ROUNDS=3] [STRIPS...=100 1000 10000]
#   AB_CORE (default 1): the core. Substeps after 240 of warm-up: 2,400 at 100 strips or fewer, 480 up to
#   1,000, 240 above.
set -euo pipefail
export PATH=/usr/bin:/bin:$PATH
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
ROUNDS=${1:-3}
if ! [[ "$ROUNDS" =~ ^[1-9][0-9]*$ ]]; then
  echo "step_parts.sh: ROUNDS must be a whole number >= 1, not '$ROUNDS'" >&2
  exit 2
fi
shift || true
SIZES=("$@")
[ ${#SIZES[@]} -gt 0 ] || SIZES=(100 1000 10000)
for n in "${SIZES[@]}"; do
  [[ "$n" =~ ^[1-9][0-9]*$ ]] || {
    echo "step_parts.sh: STRIPS must be whole numbers >= 1, not '$n'" >&2
    exit 2
  }
done
CORE=${AB_CORE:-1}

# The Release build of ./run.sh bench (its dependencies are those of ./run.sh bench or test).
name=step_parts.sh
# shellcheck source=scripts/ab_build.sh
. "$(dirname "$0")/ab_build.sh"
release_configure "$ROOT" "$ROOT/build-release"
cmake --build "$ROOT/build-release" -j"$(nproc)" --target hair_sim_step_profile >/dev/null
BIN="$ROOT/build-release/devel/lib/hair_sim/hair_sim_step_profile"

WORK=$(mktemp -d /tmp/hair_sim_parts.XXXXXX)
trap 'rm -rf "$WORK"' EXIT
# The four copies: the springs switched off and the bodies cut by text, each change checked. (Their hairstyle
# path is never read: hair_sim_step_profile generates its strips.)
/usr/bin/python3 - "$ROOT/config/hair_sim.yaml" "$WORK" <<'EOF'
import os, sys
src, out = sys.argv[1], sys.argv[2]
text = open(src).read()
cut = text.index("\nbodies:")
settings, bodies = text[:cut], text[cut:]
lines = bodies.split("\n")
head = [l for l in lines if l.strip().startswith("- {name: head,")]
assert len(head) == 1, "config/hair_sim.yaml: no single body named head"
no_springs = settings
for key in ("within_strips", "between_strips"):
    assert "  %s: true" % key in no_springs, "config/hair_sim.yaml: springs.%s is not true" % key
    no_springs = no_springs.replace("  %s: true" % key, "  %s: false" % key)
configs = {
    "full": settings + bodies,
    "dynamics_alone": no_springs + "\nbodies: []\n",
    "springs": settings + "\nbodies: []\n",
    "springs_head": settings + "\nbodies:\n" + head[0] + "\n",
    "bodies": no_springs + bodies,
}
for name, body in configs.items():
    open(os.path.join(out, name + ".yaml"), "w").write(body)
EOF

CONFIGS=(dynamics_alone springs springs_head bodies full)
: >"$WORK/runs.txt"
for r in $(seq 1 "$ROUNDS"); do
  for c in "${CONFIGS[@]}"; do
    for n in "${SIZES[@]}"; do
      if [ "$n" -le 100 ]; then s=2400; elif [ "$n" -le 1000 ]; then s=480; else s=240; fi
      line=$(taskset -c "$CORE" "$BIN" --strips "$n" --warmup 240 --substeps "$s" --config "$WORK/$c.yaml" |
        sed -n 's/.*"control_points": \([0-9]*\),.*"ns_per_update": \([0-9.]*\), "exact_share": \([0-9.]*\), "state_hash": "\([0-9a-f]*\)".*/\1 \2 \3 \4/p')
      [ -n "$line" ] || {
        echo "step_parts.sh: no result from $c at $n strips" >&2
        exit 1
      }
      echo "$c $n $line" >>"$WORK/runs.txt"
      echo "round $r: $c, $n strips: $line" >&2
    done
  done
done
/usr/bin/python3 - "$WORK/runs.txt" "${CONFIGS[@]}" <<'EOF'
import statistics, sys
runs = {}
for line in open(sys.argv[1]):
    c, n, points, ns, share, h = line.split()
    runs.setdefault((c, int(n)), []).append((float(ns), float(share), h, int(points)))
sizes = sorted({n for _, n in runs})
print("| configuration | strips | ns per update, median (range) | real-time factor | exact step | state hash |")
print("|---|---|---|---|---|---|")
for c in sys.argv[2:]:
    for n in sizes:
        r = runs[(c, n)]
        ns = [x[0] for x in r]
        med = statistics.median(ns)
        hashes = sorted({x[2] for x in r})
        print(f"| {c} | {n} | {med:.1f} ({min(ns):.1f}-{max(ns):.1f}) | {1.0 / (med * 1e-9 * r[0][3] * 240):.2f} "
              f"| {100 * r[0][1]:.1f} % | {', '.join(hashes)} |")
EOF
