# shellcheck shell=bash
# Sourced by the test scripts that check how programs refuse bad input (bad_parameters.sh,
# tool_arguments.sh). expect_exit STATUS TEXT WHAT PROGRAM ARGS...: PROGRAM exits with STATUS within 30 s
# and prints TEXT on stdout or stderr (kept in $TMP/out.log and $TMP/err.log); WHAT names the case in the
# report (empty: ARGS). Counts the cases in n and the failures in failures; the caller sets TMP, n and failures.
expect_exit() {
  local want=$1 text=$2 what=$3
  shift 3
  [ -n "$what" ] || what="${*:2}"
  n=$((n + 1))
  local status=0 said
  timeout 30 "$@" >"$TMP/out.log" 2>"$TMP/err.log" || status=$?
  said=$(cat "$TMP/err.log" "$TMP/out.log")
  if [ "$status" -ne "$want" ]; then
    echo "FAIL: $what: exit status $status (expected $want)"; tail -5 <<<"$said" | sed 's/^/    /'
    failures=$((failures + 1))
  elif ! grep -qF -- "$text" <<<"$said"; then
    echo "FAIL: $what: no \"$text\" in:"; tail -5 <<<"$said" | sed 's/^/    /'; failures=$((failures + 1))
  else
    echo "ok: $what: $(grep -F -- "$text" <<<"$said" | head -1)"
  fi
}
