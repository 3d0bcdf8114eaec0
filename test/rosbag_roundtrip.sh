#!/usr/bin/env bash
# CTest rosbag_roundtrip: record tf and wind from a live run, replay them with use_sim_time into a fresh
# hair_sim_node, and compare its hair_state with the live run's (rosbag_compare.py).
#   live:   hair_sim_node + head_driver (translate: 0.3 m sideways in 0.5 s, 9 s after its start, head
#           at z = 2 m clear of the shoulders, as in hair_node_checks.test) + a wind of 2 m/s along +y sent 3 s into the recording
#           (ramp 0.5 s, stamped 0.2 s ahead, sent once both subscribers are connected); `rosbag record /tf /tf_static /wind /hair_state` for 10 s.
#   replay: use_sim_time, hair_sim_node, `rosbag play --clock` of /tf /tf_static /wind from that bag;
#           `rosbag record /hair_state`.
# Usage: rosbag_roundtrip.sh SOURCE_ROOT DEVEL_PREFIX OUT_DIR
set -eo pipefail
ROOT=$1 DEVEL=$2 OUT=$3
export PATH=/usr/bin:/bin:/usr/sbin:/sbin:$PATH
mkdir -p "$OUT"
rm -f "$OUT"/*.bag
set +u
# shellcheck disable=SC1091
source "$DEVEL/setup.bash"
export ROS_HOSTNAME=localhost ROS_HOME=${ROS_HOME:-$OUT/ros_home}
CONFIG=$ROOT/config/hair_sim.yaml
PIDS=()
stop_all() { for p in "${PIDS[@]}"; do kill -INT "$p" 2>/dev/null || true; done; for p in "${PIDS[@]}"; do wait "$p" 2>/dev/null || true; done; PIDS=(); }
trap stop_all EXIT
wait_topic() {
  for _ in $(seq 1 60); do
    if timeout 3 rostopic echo -n 1 "$1" >/dev/null 2>&1; then return 0; fi
    sleep 0.5
  done
  echo "rosbag_roundtrip: FAIL: no $1"; exit 1
}

# ---- live run
# shellcheck source=test/free_port.sh
. "$(dirname "$0")/free_port.sh"
PORT=$(free_port)
export ROS_MASTER_URI=http://localhost:$PORT
timeout 60 roscore -p "$PORT" >"$OUT/live_roscore.log" 2>&1 & PIDS+=($!)
sleep 2
timeout 60 rosrun hair_sim hair_sim_node _config_file:="$CONFIG" >"$OUT/live_node.log" 2>&1 & PIDS+=($!)
timeout 60 rosrun hair_sim head_driver _mode:=translate _base_z:=2.0 _translate_distance:=0.3 _translate_duration:=0.5 _translate_start:=9.0 >"$OUT/live_driver.log" 2>&1 & PIDS+=($!)
wait_topic /hair_state/header
timeout 30 rosbag record -q -O "$OUT/live.bag" --duration=10 /tf /tf_static /wind /hair_state >"$OUT/live_record.log" 2>&1 &
RECORD=$!
sleep 3
# Published once the live node and the recorder are connected, stamped 0.2 s ahead (within the node's
# max_tf_age of 0.5 s): it reaches both before its stamp, so both runs start the ramp at the stamp. With
# `rostopic pub` and a stamp of "now" it reached them 0.25-0.7 s later (rostopic starts and connects first):
# the live node then started the ramp on its first substep after arrival, the replay on its first after the
# recorder's receipt, a substep apart when the two straddled a boundary (4.2 mm once on a slow VM).
timeout 20 python3 - <<'PY'
import time
import rospy
from hair_sim_msgs.msg import Wind
rospy.init_node('rosbag_roundtrip_wind', anonymous=True)
pub = rospy.Publisher('/wind', Wind, queue_size=1)
deadline = time.time() + 10.0
while pub.get_num_connections() < 2 and time.time() < deadline:  # hair_sim_node and rosbag record
    time.sleep(0.01)
msg = Wind()
msg.header.stamp = rospy.Time.now() + rospy.Duration(0.2)
msg.velocity.y = 2.0
msg.ramp_time = 0.5
pub.publish(msg)
time.sleep(0.5)
PY
wait $RECORD || true
stop_all
[ -f "$OUT/live.bag" ] || { echo "rosbag_roundtrip: FAIL: no live.bag"; exit 1; }

# ---- replay with simulated time
PORT=$(free_port)
export ROS_MASTER_URI=http://localhost:$PORT
timeout 60 roscore -p "$PORT" >"$OUT/replay_roscore.log" 2>&1 & PIDS+=($!)
sleep 2
rosparam set /use_sim_time true
timeout 60 rosrun hair_sim hair_sim_node _config_file:="$CONFIG" >"$OUT/replay_node.log" 2>&1 & PIDS+=($!)
timeout 60 rosbag record -q -O "$OUT/replay.bag" /hair_state >"$OUT/replay_record.log" 2>&1 & PIDS+=($!)
sleep 3  # node and recorder up and subscribed before the first message
timeout 40 rosbag play --clock -q "$OUT/live.bag" --topics /tf /tf_static /wind >"$OUT/replay_play.log" 2>&1
sleep 1
stop_all
python3 "$ROOT/test/rosbag_compare.py" "$OUT/live.bag" "$OUT/replay.bag"
