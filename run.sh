#!/usr/bin/env bash
# hair_sim: set up, build and run. Usage: ./run.sh demo | test | bench [flags] | build
# Installs what it needs with apt (as root, or through sudo) on a fresh Debian 12 machine.
set -eo pipefail
cd "$(dirname "$(readlink -f "$0")")"
ROOT=$PWD
# Debian's ROS tools need Debian's python3 (a pyenv python3 first on PATH cannot import rospy).
export PATH=/usr/bin:/bin:/usr/sbin:/sbin:$PATH
export ROS_HOSTNAME=localhost ROS_LANG_DISABLE=genlisp:geneus:gennodejs
export ROS_HOME=$ROOT/build/ros_home ROS_LOG_DIR=$ROOT/build/ros_home/log

PACKAGES="build-essential cmake catkin ros-core-dev rosbash python3-rostest librostest-dev libgtest-dev
  libeigen3-dev libyaml-cpp-dev libtf2-ros-dev libtf2-eigen-dev libvisualization-msgs-dev
  libgeometry-msgs-dev libstd-srvs-dev libtf2-msgs-dev librosbag-storage-dev python3-geometry-msgs
  python3-visualization-msgs python3-std-srvs libbenchmark-dev rviz xvfb imagemagick python3-tf2-ros python3-yaml
  python3-rosbag libdynamic-reconfigure-config-init-mutex-dev python3-dynamic-reconfigure libdiagnostic-updater-dev
  python3-diagnostic-msgs libnodeletlib-dev libnodeletlib-tools python3-nodelet pluginlib-dev catkin-lint
  python3-pil python3-numpy"
# The rviz display plugin hair_sim/HairDisplay (librviz-dev brings Qt 5, OGRE 1.12 and pluginlib) and its test
# (rviz in Python, screenshots read with PIL and numpy).
PACKAGES="$PACKAGES librviz-dev python3-rviz"

install_deps() {
  local missing=()
  for p in $PACKAGES; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  echo "run.sh: installing ${missing[*]}" >&2
  local SUDO=""
  [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
}

build() {
  local type=${1:-RelWithDebInfo}
  # catkin's cached environment (used by CTest for rostests) lists only Python folders that exist at
  # configure time: create the devel space's one first so that the generated message modules are found.
  mkdir -p build/devel/lib/python3/dist-packages
  cmake -S . -B build -DCMAKE_BUILD_TYPE="$type" -DCATKIN_DEVEL_PREFIX="$ROOT/build/devel" >build/cmake.log 2>&1 ||
    { mkdir -p build; cmake -S . -B build -DCMAKE_BUILD_TYPE="$type" -DCATKIN_DEVEL_PREFIX="$ROOT/build/devel"; }
  cmake --build build -j"$(nproc)"
}

mkdir -p build "$ROS_LOG_DIR"
cmd=${1:-}
case "$cmd" in
  build)
    install_deps
    build
    ;;
  demo)
    install_deps
    build
    exec scripts/demo.sh
    ;;
  offline-demo)
    install_deps
    build
    echo "run.sh: offline runner, default hairstyle, head-shake scenario -> build/demo/" >&2
    mkdir -p build/demo
    build/devel/lib/hair_sim/hair_sim_offline --config config/hair_sim.yaml \
      --scenario config/scenarios/head_shake.yaml --out build/demo/control_points.csv \
      --poses-out build/demo/head_poses.csv --mesh-out build/demo/meshes --bag build/demo/hair_sim.bag
    ;;
  bench)
    install_deps
    mkdir -p build-release
    cmake -S . -B build-release -DCMAKE_BUILD_TYPE=Release -DCATKIN_DEVEL_PREFIX="$ROOT/build-release/devel" \
      -DCATKIN_ENABLE_TESTING=OFF >build-release/cmake.log 2>&1
    if [ $# -gt 1 ]; then  # flags: hair_sim_bench alone with them
      cmake --build build-release -j"$(nproc)" --target hair_sim_bench
      exec build-release/devel/lib/hair_sim/hair_sim_bench --benchmark_repetitions="${REPETITIONS:-3}" \
        --benchmark_report_aggregates_only=true "${@:2}"
    fi
    cmake --build build-release -j"$(nproc)"
    exec scripts/bench.sh
    ;;
  test)
    install_deps
    build
    cmake --build build --target tests -j"$(nproc)"
    cd build && ctest --output-on-failure -j"$(nproc)"
    ;;
  load)
    # Load test (issue 8): tf and Wind at 1 kHz into the node for SECONDS (default 60); figures in build/load.json.
    install_deps
    build
    seconds=${2:-60}
    # test/ is beside the package: rostest is told which package the test belongs to (as CTest does).
    timeout $((2 * seconds + 180)) build/devel/env.sh rostest --pkgdir="$ROOT/hair_sim" --package=hair_sim \
      "$ROOT/test/load.test" seconds:="$seconds" out:="$ROOT/build/load.json" && status=0 || status=$?
    cat build/load.json 2>/dev/null || echo "run.sh: no figures (build/load.json)" >&2
    exit $status
    ;;
  *)
    echo "usage: ./run.sh demo | test | offline-demo | bench [benchmark flags] | build" >&2
    exit 2
    ;;
esac
