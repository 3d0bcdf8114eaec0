#!/usr/bin/env bash
# CTest bad_parameters: hair_sim_node started with a bad private parameter or a malformed config file
# stops at once (exit status 1) with a message that names the parameter (or file, key and line) and the
# value; a good start is checked too, so that the test can tell "refused" from "cannot start at all".
# Usage: bad_parameters.sh DEVEL_PREFIX SOURCE_ROOT
set -eo pipefail
DEVEL=$1 SOURCE=$2
export PATH=/usr/bin:/bin:/usr/sbin:/sbin:$PATH
TMP=$(mktemp -d /tmp/hair_sim_bad_params.XXXXXX)
export ROS_HOSTNAME=localhost ROS_HOME=$TMP/ros_home ROS_LOG_DIR=$TMP/ros_home/log
# shellcheck source=test/free_port.sh
. "$(dirname "$0")/free_port.sh"
PORT=$(free_port)
export ROS_MASTER_URI=http://localhost:$PORT
set +u
# shellcheck disable=SC1091
source "$DEVEL/setup.bash"
roscore -p "$PORT" >"$TMP/roscore.log" 2>&1 &
CORE=$!
cleanup() { kill -INT $CORE 2>/dev/null; wait $CORE 2>/dev/null || true; rm -rf "$TMP"; }
trap cleanup EXIT
for _ in $(seq 1 50); do rosparam list >/dev/null 2>&1 && break; sleep 0.2; done
NODE=$DEVEL/lib/hair_sim/hair_sim_node
CONFIG=$SOURCE/config/hair_sim.yaml
failures=0
n=0
# shellcheck source=test/expect_exit.sh
. "$(dirname "$0")/expect_exit.sh"
# expect_refused DESCRIPTION EXPECTED_TEXT ARGS...: $NODE with ARGS stops with status 1 saying EXPECTED_TEXT.
expect_refused() {
  local what=$1 text=$2
  shift 2
  expect_exit 1 "$text" "$what" "$NODE" __name:=hair_sim_bad_$((n + 1)) "$@"
}
expect_refused "no config_file" "parameter ~config_file" 
# A relative path, as `config:=hair_sim.yaml` gives it: roslaunch reads it from the shell's directory, the node
# from its own (it names its working directory and asks for an absolute path).
expect_refused "relative config_file" "parameter ~config_file: 'hair_sim.yaml' is a relative path, and there is no such file in the node's working directory" \
  _config_file:=hair_sim.yaml
expect_refused "publish_rate of the wrong type" "parameter ~publish_rate: 'fast' must be a number" \
  _config_file:="$CONFIG" _publish_rate:=fast
expect_refused "negative publish_rate" "parameter ~publish_rate: '-1' must be in (0, 1/substep] Hz" \
  _config_file:="$CONFIG" _publish_rate:=-1.0
expect_refused "samples_across of the wrong type" "parameter ~samples_across: '2.5' must be an integer" \
  _config_file:="$CONFIG" _samples_across:=2.5
expect_refused "render_mode unknown" "parameter ~render_mode: 'cubes' must be mesh, strands or both" \
  _config_file:="$CONFIG" _render_mode:=cubes
expect_refused "threads 0" "parameter ~threads: '0' must be in 1..64" \
  _config_file:="$CONFIG" _threads:=0
expect_refused "tcp_nodelay of the wrong type" "parameter ~tcp_nodelay: 'maybe' must be true or false" \
  _config_file:="$CONFIG" _tcp_nodelay:=maybe
expect_refused "teleport_distance 0" "parameter ~teleport_distance: '0' must be > 0 m" \
  _config_file:="$CONFIG" _teleport_distance:=0.0
expect_refused "max_tf_age negative" "parameter ~max_tf_age: '-1' must be in (0, 5] s" \
  _config_file:="$CONFIG" _max_tf_age:=-1.0
expect_refused "max_tf_age beyond the tf cache" "parameter ~max_tf_age: '12' must be in (0, 5] s" \
  _config_file:="$CONFIG" _max_tf_age:=12.0
expect_refused "max_substeps_per_update huge" "parameter ~max_substeps_per_update: '1000000' must be in 1..24000" \
  _config_file:="$CONFIG" _max_substeps_per_update:=1000000
expect_refused "max_triangles below the coarsest level" "parameter ~max_triangles: '100' is below the coarsest level's 800 triangles (1 x 1)" \
  _config_file:="$CONFIG" _max_triangles:=100
expect_refused "strands_per_strip huge" "parameter ~strands_per_strip: '1000000' must be in 1..10000" \
  _config_file:="$CONFIG" _strands_per_strip:=1000000
expect_refused "missing config file" "$TMP/none.yaml" _config_file:="$TMP/none.yaml"
sed 's/^  hinge_stiffness: .*/  hinge_stiffness: -3.0/' "$CONFIG" >"$TMP/negative.yaml"
grep -q "hinge_stiffness: -3.0" "$TMP/negative.yaml" || { echo "FAIL: could not write negative.yaml"; exit 1; }
expect_refused "negative hinge_stiffness in the config file" "hinge_stiffness" _config_file:="$TMP/negative.yaml"
grep -n "hinge_stiffness: -3.0" "$TMP/negative.yaml" | head -1
# static_frame.py (avatar.launch's base frame): the same for its parameters.
FRAME=$DEVEL/lib/hair_sim/static_frame.py
NODE=$FRAME expect_refused "static_frame.py without child" "parameter ~child is required"
NODE=$FRAME expect_refused "static_frame.py x not a number" "parameter ~x: 'abc' must be a finite number" \
  _child:=base _x:=abc
NODE=$FRAME expect_refused "static_frame.py yaw nan" "parameter ~yaw: nan must be a finite number" \
  _child:=base _yaw:=.nan
NODE=$FRAME expect_refused "static_frame.py child = parent" "are both 'world': a frame cannot be its own parent" \
  _child:=world
# A good start for comparison: the node runs until timeout stops it (status 124).
status=0
timeout 3 "$NODE" __name:=hair_sim_good _config_file:="$CONFIG" _publish_rate:=30 >"$TMP/good.log" 2>&1 || status=$?
if [ "$status" -ne 124 ]; then
  echo "FAIL: a good start ended with status $status:"; tail -5 "$TMP/good.log"; failures=$((failures + 1))
else
  echo "ok: a good start runs until stopped"
fi
echo "bad_parameters: $failures of $((n + 1)) checks failed"
[ "$failures" -eq 0 ]
