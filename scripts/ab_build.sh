# shellcheck shell=bash disable=SC2034
# Sourced by ab_step.sh and ab_bench.sh: builds TARGET (Release) of the commit OLD in a git worktree under
# AB_DIR and of the working tree in build-release/, and sets OLD_BIN and NEW_BIN to the two executables.
# usage (after set -euo pipefail): ab_build OLD_COMMIT TARGET
# (step_parts.sh uses release_configure alone.)

# Configures the source tree SRC for a Release build in BUILD (as ./run.sh bench does, log in BUILD/cmake.log),
# or exits 1 naming the log; $name names the calling script.
release_configure() {
  local src="$1" build="$2"
  mkdir -p "$build"
  cmake -S "$src" -B "$build" -DCMAKE_BUILD_TYPE=Release -DCATKIN_DEVEL_PREFIX="$build/devel" \
    -DCATKIN_ENABLE_TESTING=OFF >"$build/cmake.log" 2>&1 || {
    echo "$name: cmake failed for $src (see $build/cmake.log)" >&2
    exit 1
  }
}

ab_build() {
  export PATH=/usr/bin:$PATH
  ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
  OLD="$(git -C "$ROOT" rev-parse --verify -q "$1^{commit}")" || {
    echo "$(basename "$0"): '$1' is not a commit of this repository" >&2
    exit 2
  }
  local target="$2" name
  name="$(basename "$0" .sh)"
  AB_DIR=${AB_DIR:-/tmp/hair_sim_ab}
  mkdir -p "$AB_DIR"
  if [ "$(git -C "$AB_DIR/src" rev-parse --show-toplevel 2>/dev/null)" = "$AB_DIR/src" ]; then
    git -C "$AB_DIR/src" checkout -q --detach "$OLD"
  else  # none yet, or a directory left without its worktree
    rm -rf "$AB_DIR/src"
    git -C "$ROOT" worktree prune
    git -C "$ROOT" worktree add -q --detach "$AB_DIR/src" "$OLD"
  fi
  local pair
  for pair in "$AB_DIR/src:$AB_DIR/build" "$ROOT:$ROOT/build-release"; do
    release_configure "${pair%%:*}" "${pair#*:}"
  done
  cmake --build "$AB_DIR/build" -j"$(nproc)" --target "$target" >"$AB_DIR/build.log" 2>&1 || {
    echo "$name: build of $OLD failed (see $AB_DIR/build.log)" >&2
    exit 1
  }
  cmake --build "$ROOT/build-release" -j"$(nproc)" --target "$target" >"$AB_DIR/build-new.log" 2>&1 || {
    echo "$name: build of the working tree failed (see $AB_DIR/build-new.log)" >&2
    exit 1
  }
  OLD_BIN="$AB_DIR/build/devel/lib/hair_sim/$target"
  NEW_BIN="$ROOT/build-release/devel/lib/hair_sim/$target"
}
