#!/usr/bin/env bash
# The hair_sim demo: roscore, hair_sim_node, head_driver and rviz (launch/demo.launch).
# With no display it runs rviz under Xvfb and saves a screenshot every few seconds.
# Environment: DEMO_SECONDS (default 60; 0 = until Ctrl-C), SHOT (default build/demo/hair_sim_rviz.png),
# SHOT_EVERY (s, default 5). Called by ./run.sh demo after the build.
set -eo pipefail
cd "$(dirname "$(readlink -f "$0")")/.."
ROOT=$PWD
export PATH=/usr/bin:/bin:/usr/sbin:/sbin:$PATH
export ROS_HOSTNAME=localhost ROS_HOME=${ROS_HOME:-$ROOT/build/ros_home}
export ROS_MASTER_URI=${ROS_MASTER_URI:-http://localhost:11311}
DEMO_SECONDS=${DEMO_SECONDS:-60}
SHOT=${SHOT:-$ROOT/build/demo/hair_sim_rviz.png}
SHOT_EVERY=${SHOT_EVERY:-5}
mkdir -p "$(dirname "$SHOT")" "$ROS_HOME"
set +u
# shellcheck disable=SC1091
source "$ROOT/build/devel/setup.bash"

run_demo() {
  roslaunch "$ROOT/launch/demo.launch" >"$ROOT/build/demo/roslaunch.log" 2>&1 &
  # Global, not local: the EXIT trap runs after run_demo has returned.
  launch=$!
  trap 'kill -INT $launch 2>/dev/null; wait $launch 2>/dev/null' EXIT
  echo "demo: roslaunch launch/demo.launch (log: build/demo/roslaunch.log)"
  local start=$SECONDS next_shot=$((SECONDS + SHOT_EVERY))
  while kill -0 $launch 2>/dev/null; do
    sleep 1
    if [ -n "$HEADLESS" ] && [ $SECONDS -ge $next_shot ]; then
      if /usr/bin/import -window root "$SHOT" 2>/dev/null; then echo "demo: screenshot -> $SHOT"; fi
      next_shot=$((SECONDS + SHOT_EVERY))
    fi
    if [ $(((SECONDS - start) % 5)) -eq 0 ]; then
      status=$(grep -a "simulated" "$ROOT/build/demo/roslaunch.log" | tail -1 | sed 's/.*hair_sim: /hair_sim: /; s/\x1b\[[0-9;]*m//g' || true)
      if [ -n "$status" ]; then echo "demo: $status"; fi
    fi
    if [ "$DEMO_SECONDS" -gt 0 ] && [ $((SECONDS - start)) -ge "$DEMO_SECONDS" ]; then
      echo "demo: $DEMO_SECONDS s done (DEMO_SECONDS=0 runs until Ctrl-C)"
      break
    fi
  done
}

if [ -z "$DISPLAY" ] && [ -z "$INSIDE_XVFB" ]; then
  echo "demo: no display: rviz runs under Xvfb, screenshots every ${SHOT_EVERY} s to $SHOT"
  exec xvfb-run -a -s "-screen 0 1280x800x24" env INSIDE_XVFB=1 HEADLESS=1 "$0" "$@"
fi
run_demo
