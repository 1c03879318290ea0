# Shared by the CLI test scripts (sourced, after `hpa` holds the binary): a failure counter and
# the exit-code-and-message check.

failures=0
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
