# Shared by the CLI test scripts (sourced; each check needs `hpa` to hold the binary, as
# cli_test_start sets it): the arguments, a failure counter and the exit-code-and-message check.

failures=0

# cli_test_start HPA_BINARY SOURCE_DIR [PYTHON]: the arguments every CLI test script takes, as
# hpa, src and python, and out, a temporary folder removed when the script exits
cli_test_start() {
  hpa=$1
  src=$2
  python=${3:-}
  out=$(mktemp -d)
  trap 'rm -rf "$out"' EXIT
}

# same_run A B LABEL [same_run.py options]: the runs in folders A and B are the same run (metrics
# but the timings and what flew; with --rows N, the log row for row but the solve times)
same_run() {
  local a=$1 b=$2 label=$3; shift 3
  "$python" "$src/harness/tests/same_run.py" "$a" "$b" "$@" || fail "$label: the runs differ"
}

# fail MESSAGE...: counts and prints a failed check
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }

# expect_exit CODE PATTERN ARGS...: hpa ARGS (at most 60 s) exits CODE and its stdout+stderr
# matches PATTERN (an extended regex)
expect_exit() {
  local code=$1 pattern=$2; shift 2
  local text status
  text=$(timeout 60 "$hpa" "$@" 2>&1); status=$?
  [ "$status" -eq "$code" ] || fail "hpa $* exited $status, expected $code: $text"
  grep -Eq -- "$pattern" <<< "$text" || fail "hpa $* output lacks /$pattern/: $text"
}

# impulse_hover_base FILE NAME DURATION_S AT_S: writes a fast base scenario for sweeps and plots
# (the geometric controller on ground truth with the analytic camera, a hover, an upward payload
# impulse at AT_S that slackens the cable for a while)
impulse_hover_base() {
  cat > "$1" << YAML
name: $2
duration: $3
controller: {type: geometric}
estimation: {ground_truth: true, camera: analytic}
reference: {type: hover, payload_position: [0, 0, 0.7]}
events:
  - {at: $4, type: impulse, body: payload, impulse: [0, 0, 0.1]}
YAML
}
