#!/usr/bin/env bash
# CTest tool_arguments: hair_sim_generate and hair_sim_soak refuse bad flags with exit status 2 and a
# message naming the flag and the value (no silent truncation, wrap or saturation), hair_sim_generate keeps
# within the limits of the hairstyle loader and does not write a hairstyle that the loader would refuse
# (exit 1, naming the flags that made it), and hair_sim_soak finds an unwritable --json-out before its run.
# Usage: tool_arguments.sh HAIR_SIM_GENERATE HAIR_SIM_SOAK SOURCE_ROOT
set -uo pipefail
GENERATE=$1 SOAK=$2 SOURCE=$3
TMP=$(mktemp -d /tmp/hair_sim_tool_arguments.XXXXXX)
trap 'rm -rf "$TMP"' EXIT
failures=0
n=0
# shellcheck source=test/expect_exit.sh
. "$(dirname "$0")/expect_exit.sh"
OUT=$TMP/style.yaml
# --- hair_sim_generate: flags (exit 2, the flag and the value named) ---
expect_exit 2 "--strips: 'abc' is not an integer" "" "$GENERATE" --out "$OUT" --strips abc
expect_exit 2 "--strips: '12abc' is not an integer" "" "$GENERATE" --out "$OUT" --strips 12abc
expect_exit 2 "--strips: '1e9' is not an integer" "" "$GENERATE" --out "$OUT" --strips 1e9
expect_exit 2 "--strips: ' 3' is not an integer" "" "$GENERATE" --out "$OUT" --strips " 3"
expect_exit 2 "--strips: 99999999999 is above the maximum 100000" "" "$GENERATE" --out "$OUT" --strips 99999999999
expect_exit 2 "--length-front: '1e400' is out of range" "" "$GENERATE" --out "$OUT" --length-front 1e400
expect_exit 2 "--length-front: 1e-9 is below the minimum 0.002 m" "" "$GENERATE" --out "$OUT" --length-front 1e-9
expect_exit 2 "--seed: '-1' is not a non-negative integer" "" "$GENERATE" --out "$OUT" --seed -1
expect_exit 2 "--columns: 1 is below the minimum 2" "" "$GENERATE" --out "$OUT" --columns 1
# The loader's limits (these used to write files that hair_sim_offline refuses) and the caps.
expect_exit 2 "--columns: 65 is above the maximum 64" "" "$GENERATE" --out "$OUT" --columns 65
expect_exit 2 "--rows: 300 is above the maximum 256" "" "$GENERATE" --out "$OUT" --rows 300
expect_exit 2 "--length-back: 20 is above the maximum 9 m" "" "$GENERATE" --out "$OUT" --length-back 20
expect_exit 2 "--rings: 1000000 is above the maximum 1000" "" "$GENERATE" --out "$OUT" --rings 1000000
expect_exit 2 "control points, above the maximum 1000000" "" "$GENERATE" --out "$OUT" --strips 1000 --columns 64 --rows 256
[ -e "$OUT" ] && { echo "FAIL: a refused run wrote $OUT"; failures=$((failures + 1)); }
# A hairstyle the loader refuses: the flags that made it are named, --out is neither blamed nor written.
expect_exit 1 "the hairstyle made by --strips 100 --rings 5 --columns 2 --rows 256 --length-front 0.002 --length-back 0.002 --seed 7 fails the hairstyle loader's checks, so $OUT was not written: strips[0].points[2]: segment length" "" \
  "$GENERATE" --out "$OUT" --length-front 0.002 --length-back 0.002 --rows 256
sed -e "s|^hairstyle: .*|hairstyle: $SOURCE/config/hairstyles/default.yaml|" \
  -e '/name: head,/s|center: \[[^]]*\]|center: [150.0, 0.0, 0.0]|' "$SOURCE/config/hair_sim.yaml" >"$TMP/far_head.yaml"
expect_exit 1 "--config $TMP/far_head.yaml --head-z 1.6 fails the hairstyle loader's checks, so $OUT was not written: scalp.center: [150, 0, 0] has a coordinate beyond +-100 m" "" \
  "$GENERATE" --out "$OUT" --config "$TMP/far_head.yaml"
# A body in a frame that is neither the world nor the head: refused as hair_sim_offline refuses it.
sed -e "s|^hairstyle: .*|hairstyle: $SOURCE/config/hairstyles/default.yaml|" \
  -e '/name: neck,/s|frame: [a-z]*|frame: neck|' "$SOURCE/config/hair_sim.yaml" >"$TMP/neck_frame.yaml"
expect_exit 1 "$TMP/neck_frame.yaml: bodies: body 'neck' is in frame 'neck': the generator knows only head_frame 'head' and world_frame 'world'" "" \
  "$GENERATE" --out "$OUT" --config "$TMP/neck_frame.yaml"
[ -e "$OUT" ] && { echo "FAIL: a refused hairstyle was written to $OUT"; failures=$((failures + 1)); }
# Good runs: the limits themselves, and the committed default hairstyle byte for byte.
expect_exit 0 "control points -> $OUT" "" "$GENERATE" --out "$OUT" --length-front 9 --length-back 9 --rows 4 --columns 64 \
  --strips 15 --seed 4294967295
expect_exit 0 "100 strips, 1000 control points -> $OUT" "" "$GENERATE" --out "$OUT" --config "$SOURCE/config/hair_sim.yaml"
cmp -s "$OUT" "$SOURCE/config/hairstyles/default.yaml" || { echo "FAIL: default.yaml not reproduced"; failures=$((failures + 1)); }
# --- hair_sim_soak ---
expect_exit 2 "--seconds: 1 is below the minimum 80 s" "" "$SOAK" --seconds 1
expect_exit 2 "--seconds: 79.9 is below the minimum 80 s" "" "$SOAK" --seconds 79.9
expect_exit 2 "--seed: '-1' is not a non-negative integer" "" "$SOAK" --seed -1
expect_exit 2 "--seed: '99999999999999999999999' is out of range" "" "$SOAK" --seed 99999999999999999999999
# Found before the run: nothing on stdout (it used to print the whole run's summary, "passed": true).
expect_exit 2 "--json-out $TMP/missing/s.json: cannot open for writing: No such file or directory" "" \
  "$SOAK" --seconds 80 --json-out "$TMP/missing/s.json"
[ -s "$TMP/out.log" ] && { echo "FAIL: the soak ran before refusing --json-out"; failures=$((failures + 1)); }
echo "$n cases, $failures failures"
[ "$failures" -eq 0 ]
