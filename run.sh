#!/usr/bin/env bash
# hair_sim: set up, build and run. Usage: ./run.sh demo | test | bench [flags] | build | load [s] | fuzz [s] | sanitize | tsan | soak [s]
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
# ./run.sh fuzz: clang and its runtime libraries (libclang_rt.fuzzer, asan, ubsan) for libFuzzer.
PACKAGES="$PACKAGES clang libclang-rt-14-dev"

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

# configure_sanitized DIR SANITIZERS [EXTRA_CXX_FLAGS]: a RelWithDebInfo build in DIR with gcc's
# -fsanitize=SANITIZERS (compiler and linker); the configure log in DIR/cmake.log, shown when it fails.
configure_sanitized() {
  local dir=$1 sanitizers=$2 extra=${3:-}
  mkdir -p "$dir/devel/lib/python3/dist-packages"
  cmake -S . -B "$dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCATKIN_DEVEL_PREFIX="$ROOT/$dir/devel" \
    -DCMAKE_CXX_FLAGS="-fsanitize=$sanitizers $extra -fno-omit-frame-pointer" \
    -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=$sanitizers" -DCMAKE_SHARED_LINKER_FLAGS="-fsanitize=$sanitizers" \
    >"$dir/cmake.log" 2>&1 || { cat "$dir/cmake.log"; exit 1; }
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
    # Fails when an output's rate is off by more than 10 % or its p99 latency exceeds MAX_P99_MS (default 5).
    install_deps
    build
    seconds=${2:-60}
    # test/ is beside the package: rostest is told which package the test belongs to (as CTest does).
    timeout $((2 * seconds + 180)) build/devel/env.sh rostest --pkgdir="$ROOT/hair_sim" --package=hair_sim \
      "$ROOT/test/load.test" seconds:="$seconds" out:="$ROOT/build/load.json" max_p99_ms:="${MAX_P99_MS:-5}" && status=0 || status=$?
    cat build/load.json 2>/dev/null || echo "run.sh: no figures (build/load.json)" >&2
    exit $status
    ;;
  fuzz)
    # libFuzzer on the YAML loaders and the message handling (docs/robustness-suites.md): clang build in
    # build-fuzz/ with ASan and UBSan, SECONDS (default 60) per target from test/fuzz_corpus/<target>/.
    install_deps
    secs=${2:-60}
    mkdir -p build-fuzz/devel/lib/python3/dist-packages
    CC=clang CXX=clang++ cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo -DHAIR_SIM_FUZZ=ON \
      -DCATKIN_ENABLE_TESTING=OFF -DCATKIN_DEVEL_PREFIX="$ROOT/build-fuzz/devel" \
      -DCMAKE_CXX_FLAGS="-fsanitize=address,undefined,fuzzer-no-link -fno-sanitize-recover=undefined -fno-omit-frame-pointer" \
      >build-fuzz/cmake.log 2>&1 || { cat build-fuzz/cmake.log; exit 1; }
    cmake --build build-fuzz -j"$(nproc)" --target fuzz_yaml fuzz_messages
    status=0
    for t in yaml messages; do
      mkdir -p "build-fuzz/corpus/$t" "build-fuzz/crashes/$t"
      echo "run.sh: fuzz_$t for $secs s (new inputs: build-fuzz/corpus/$t, crashers: build-fuzz/crashes/$t)" >&2
      # New inputs go to the first folder; test/fuzz_corpus/<target> (seeds and fixed crashers) is read only.
      build-fuzz/devel/lib/hair_sim/fuzz_$t -max_total_time="$secs" -timeout=10 -rss_limit_mb=2048 \
        -print_final_stats=1 -artifact_prefix="build-fuzz/crashes/$t/" "build-fuzz/corpus/$t" "test/fuzz_corpus/$t" \
        2>&1 | tee "build-fuzz/fuzz_$t.log" | grep -E "^#[0-9]+[[:space:]]+(DONE|INITED)|BUG|ERROR|SUMMARY|stat::" || true
      grep -q "Test unit written to" "build-fuzz/fuzz_$t.log" && status=1
    done
    [ $status -eq 0 ] || echo "run.sh: crashers in build-fuzz/crashes/ (fix, then copy them into test/fuzz_corpus/<target>/)" >&2
    exit $status
    ;;
  tsan)
    # The tests that run the step and the mesh on helper threads (1, 2 and 3 threads, the two sweeps at once)
    # under ThreadSanitizer, in build-tsan/. The kernels' run-time dispatch is left out (-DHAIR_SIM_NO_AVX2):
    # GCC's target_clones resolvers run before the TSan runtime is up and crash the program at load. Address
    # space randomisation is turned off for the tests (setarch -R): TSan's shadow memory needs the classic
    # layout on kernels with 28 bits of mmap randomness.
    install_deps
    configure_sanitized build-tsan thread -DHAIR_SIM_NO_AVX2
    cmake --build build-tsan -j"$(nproc)" --target SimulatorTest HairMeshBuilderTest
    cd hair_sim/test
    for t in "SimulatorTest *Thread*:*SweepGroups*" "HairMeshBuilderTest *Thread*"; do
      set -- $t
      TSAN_OPTIONS=halt_on_error=1:second_deadlock_stack=1 setarch "$(uname -m)" -R \
        "$ROOT/build-tsan/devel/lib/hair_sim/$1" --gtest_filter="$2"
    done
    ;;
  sanitize)
    # The unit tests (gtest), the fuzz replays and the short soak under AddressSanitizer and
    # UndefinedBehaviorSanitizer, in build-asan/ (the rostests are not run here).
    install_deps
    configure_sanitized build-asan address,undefined -fno-sanitize-recover=undefined
    cmake --build build-asan -j"$(nproc)" --target unit_tests
    cd build-asan && ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
      ctest --output-on-failure -j"$(nproc)" -R "_gtest_|FuzzReplay_|SoakShort"
    ;;
  soak)
    # One simulated hour (or SECONDS) of random events and head motion: JSON summary in build/soak.json.
    install_deps
    mkdir -p build/devel/lib/python3/dist-packages
    cmake -S . -B build -DCATKIN_DEVEL_PREFIX="$ROOT/build/devel" >build/cmake.log 2>&1 || { cat build/cmake.log; exit 1; }
    cmake --build build -j"$(nproc)" --target hair_sim_soak
    exec build/devel/lib/hair_sim/hair_sim_soak --seconds "${2:-3600}" --json-out build/soak.json
    ;;
  *)
    echo "usage: ./run.sh demo | test | offline-demo | bench [benchmark flags] | build | load [seconds] | fuzz [seconds] | sanitize | tsan | soak [seconds]" >&2
    exit 2
    ;;
esac
