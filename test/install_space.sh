#!/usr/bin/env bash
# CTest install_space: installs the build (cmake --install, as `make install` / catkin_make install do)
# into a temporary DESTDIR and runs hair_sim from that install space alone, in a clean environment:
#   1. rospack finds hair_sim in the install space; `roslaunch --files hair_sim demo.launch` resolves
#      every launch, config and rviz file inside it (none from the source tree);
#   2. roslaunch-check passes on the installed launch folder (packages, nodes, dependencies);
#   3. `roslaunch hair_sim demo.launch rviz:=false` (node + head_driver) publishes hair_state, and the
#      node's ~config_file is the installed config;
#   4. `roslaunch hair_sim hair_sim_nodelet.launch head_driver:=true` (the nodelet) publishes hair_state.
# Usage: install_space.sh BUILD_DIR INSTALL_PREFIX SOURCE_ROOT
set -eo pipefail
BUILD=$1 PREFIX=$2 SOURCE=$3
export PATH=/usr/bin:/bin:/usr/sbin:/sbin:$PATH
DEST=$(mktemp -d /tmp/hair_sim_install.XXXXXX)
cleanup() { rm -rf "$DEST"; }
trap cleanup EXIT
DESTDIR=$DEST cmake --install "$BUILD" >"$DEST.log" 2>&1 || { cat "$DEST.log"; rm -f "$DEST.log"; exit 1; }
rm -f "$DEST.log"
SPACE=$DEST$PREFIX
echo "install_space: installed into $SPACE"
# shellcheck source=test/free_port.sh
. "$(dirname "$0")/free_port.sh"
PORT=$(free_port)
env -i HOME="$HOME" PATH=/usr/bin:/bin:/usr/sbin:/sbin ROS_HOSTNAME=localhost ROS_HOME="$DEST/ros_home" \
  ROS_MASTER_URI=http://localhost:$PORT SPACE="$SPACE" SOURCE="$SOURCE" PORT="$PORT" bash -c '
set -eo pipefail
source "$SPACE/setup.bash"
fail() { echo "install_space: FAIL: $*"; exit 1; }
found=$(rospack find hair_sim)
[ "$found" = "$SPACE/share/hair_sim" ] || fail "rospack find hair_sim = $found, not $SPACE/share/hair_sim"
files=$(roslaunch --files hair_sim demo.launch)
echo "$files"
echo "$files" | grep -q "hair_sim.rviz" || true
for f in $files; do
  case $(readlink -f "$f") in "$SPACE"/*) ;; *) fail "demo.launch uses $f, outside the install space" ;; esac
done
[ -f "$SPACE/share/hair_sim/config/hair_sim.rviz" ] || fail "no installed config/hair_sim.rviz"
[ -f "$SPACE/share/hair_sim/config/hairstyles/default.yaml" ] || fail "no installed hairstyle"
/usr/share/roslaunch/scripts/roslaunch-check -o "$HOME/.install_space_check.xml" "$SPACE/share/hair_sim/launch" ||
  fail "roslaunch-check on the installed launch files"
rm -f "$HOME/.install_space_check.xml"
wait_state() {  # $1: launch arguments
  timeout 60 roslaunch -p "$PORT" $1 >"$ROS_HOME/launch.log" 2>&1 &
  local launch=$!
  local ok=0
  for _ in $(seq 1 40); do
    if timeout 3 rostopic echo -n 1 /hair_state/header >/dev/null 2>&1; then ok=1; break; fi
    sleep 0.5
  done
  if [ $ok = 1 ]; then
    config=$(timeout 5 rosparam get /hair_sim/config_file)
    case $config in "$SPACE"/*) ;; *) ok=0; echo "install_space: ~config_file is $config" ;; esac
  fi
  kill -INT $launch 2>/dev/null || true
  wait $launch 2>/dev/null || true
  [ $ok = 1 ] || { tail -30 "$ROS_HOME/launch.log"; fail "no hair_state from: roslaunch $1"; }
  echo "install_space: hair_state from: roslaunch $1"
}
mkdir -p "$ROS_HOME"
wait_state "hair_sim demo.launch rviz:=false"
wait_state "hair_sim hair_sim_nodelet.launch head_driver:=true"
echo "install_space: OK"
'
