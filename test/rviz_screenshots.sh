#!/usr/bin/env bash
# CTest rviz_screenshots: launch/demo.launch (hair_sim_node, head_driver, rviz) under Xvfb with software
# rendering; three screenshots 1 s apart once the hair is drawn; rviz_pixels.py checks that hair pixels are
# present in each and that they move between frames. The shots stay in OUT_DIR (docs/ pictures are made
# from them: OUT_DIR/hair_sim_rviz.gif).
# Usage: rviz_screenshots.sh SOURCE_ROOT DEVEL_PREFIX OUT_DIR
set -eo pipefail
ROOT=$1 DEVEL=$2 OUT=$3
export PATH=/usr/bin:/bin:/usr/sbin:/sbin:$PATH
mkdir -p "$OUT"
rm -f "$OUT"/shot_*.png "$OUT"/waiting.png
if [ -z "$INSIDE_XVFB" ]; then
  exec xvfb-run -a -s "-screen 0 1280x960x24" env INSIDE_XVFB=1 LIBGL_ALWAYS_SOFTWARE=1 "$0" "$@"
fi
set +u
# shellcheck disable=SC1091
source "$DEVEL/setup.bash"
# shellcheck source=test/free_port.sh
. "$(dirname "$0")/free_port.sh"
PORT=$(free_port)
export ROS_MASTER_URI=http://localhost:$PORT ROS_HOSTNAME=localhost ROS_HOME=${ROS_HOME:-$OUT/ros_home}
timeout 120 roslaunch -p "$PORT" "$ROOT/launch/demo.launch" >"$OUT/roslaunch.log" 2>&1 &
LAUNCH=$!
trap 'kill -INT $LAUNCH 2>/dev/null; wait $LAUNCH 2>/dev/null' EXIT
ok=0
for _ in $(seq 1 60); do
  if timeout 3 rostopic echo -n 1 /hair_state/header >/dev/null 2>&1; then ok=1; break; fi
  sleep 0.5
done
[ $ok = 1 ] || { tail -30 "$OUT/roslaunch.log"; echo "rviz_screenshots: FAIL: no hair_state"; exit 1; }
# rviz draws markers a few seconds after it starts (software rendering is slow to warm up, and an Xvfb
# capture can be all black before rviz's first frame): wait until a capture shows hair, up to 60 s.
drawn=0
for _ in $(seq 1 60); do
  sleep 1
  /usr/bin/import -window root "$OUT/waiting.png" 2>/dev/null || continue
  if python3 "$ROOT/test/rviz_pixels.py" --drawn "$OUT/waiting.png"; then drawn=1; break; fi
done
[ $drawn = 1 ] || echo "rviz_screenshots: no hair drawn within 60 s; taking the shots anyway"
sleep 1
for i in 1 2 3; do
  /usr/bin/import -window root "$OUT/shot_$i.png"
  sleep 1
done
python3 "$ROOT/test/rviz_pixels.py" "$OUT"/shot_1.png "$OUT"/shot_2.png "$OUT"/shot_3.png
/usr/bin/convert -delay 100 -loop 0 "$OUT"/shot_*.png -crop 700x560+290+150 +repage -resize 60% "$OUT/hair_sim_rviz.gif" || true
