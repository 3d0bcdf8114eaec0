#!/usr/bin/env bash
# The benchmark table (called by ./run.sh bench after the Release build in build-release/):
# hair_sim_bench (Google Benchmark, medians of REPETITIONS runs, JSON in build-release/bench.json),
# then the node with the default hairstyle and head_driver for NODE_SECONDS s measured from outside
# (scripts/bench_node.py), then the table (scripts/bench_table.py) on stdout and in
# build-release/benchmarks.md. With NODE_ONLY=1, only the node, into build-release/node.json
# (scripts/ab_node.sh's windows).
set -eo pipefail
cd "$(dirname "$(readlink -f "$0")")/.."
ROOT=$PWD
B=$ROOT/build-release
export PATH=/usr/bin:/bin:/usr/sbin:/sbin:$PATH
export ROS_HOSTNAME=localhost ROS_HOME=$B/ros_home ROS_LOG_DIR=$B/ros_home/log
export ROS_MASTER_URI=http://localhost:${BENCH_PORT:-11611}
REPETITIONS=${REPETITIONS:-3}
NODE_SECONDS=${NODE_SECONDS:-20}
mkdir -p "$ROS_LOG_DIR"

if [ "${NODE_ONLY:-0}" != 1 ]; then
  echo "bench: hair_sim_bench, $REPETITIONS repetitions" >&2
  "$B/devel/lib/hair_sim/hair_sim_bench" --benchmark_repetitions="$REPETITIONS" \
    --benchmark_report_aggregates_only=true --benchmark_out="$B/bench.json" --benchmark_out_format=json >&2
fi

echo "bench: hair_sim_node (default hairstyle, head_driver, no rviz) for $NODE_SECONDS s" >&2
set +u
# shellcheck disable=SC1091
source "$B/devel/setup.bash"
roslaunch -p "${ROS_MASTER_URI##*:}" "$ROOT/launch/demo.launch" rviz:=false >"$B/bench_node.log" 2>&1 &
launch=$!
trap 'kill -INT $launch 2>/dev/null; wait $launch 2>/dev/null || true' EXIT
pid=""
for _ in $(seq 100); do
  pid=$(pgrep -f "$B/devel/lib/hair_sim/hair_sim_node" | head -1 || true)
  [ -n "$pid" ] && break
  sleep 0.2
done
if [ -z "$pid" ]; then
  echo "bench: hair_sim_node did not start (log: $B/bench_node.log)" >&2
  echo '{"error": "hair_sim_node did not start"}' >"$B/node.json"
else
  timeout $((2 * NODE_SECONDS + 60)) /usr/bin/python3 "$ROOT/scripts/bench_node.py" "$pid" "$NODE_SECONDS" "$B/devel/lib/hair_sim/latency_probe" >"$B/node.json" ||
    echo '{"error": "the node measurement failed"}' >"$B/node.json"
fi
[ "${NODE_ONLY:-0}" = 1 ] && exit 0
/usr/bin/python3 "$ROOT/scripts/bench_table.py" "$B/bench.json" "$B/node.json" | tee "$B/benchmarks.md"
