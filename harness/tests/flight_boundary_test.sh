#!/usr/bin/env bash
# The flight-stack boundary on hostile input (docs/protocol.md, "What the simulator refuses"):
# a bad --flight-timeout or --flight-stack is bad input (exit 2); SIGINT and SIGTERM end every
# wait on a stack (connect, hello, reply) within a poll slice, exit 130 / 143 with metrics.json
# naming the signal; the time limit bounds a whole reply, not each read; a stack's bytes that are
# not UTF-8, a frame ring it truncates and every out-of-range value it sends end the run with a
# run error naming it (metrics.json written); the stack's processes die with the run, and what
# an hpa killed with SIGKILL left behind (socket folder, ring, stack processes) is reclaimed by
# the next one. Usage: flight_boundary_test.sh HPA_BINARY SOURCE_DIR PYTHON
set -uo pipefail
hpa=$1
src=$2
python=$3
source "$src/harness/tests/cli_test_lib.sh"
out=$(mktemp -d)
started=()  # pids this test started that may outlive a failed check
trap 'for p in "${started[@]}"; do kill -9 "$p" 2>/dev/null; done; rm -rf "$out"' EXIT
stack="$python $src/harness/tests/hostile_boundary_stack.py"
run_error_exit=3  # a run's error exit code (docs/design.md, exit codes)

# a short run; the ideal world's rate loop flies the estimate's body rate, so ticks ask for it
cat > "$out/short.yaml" <<'YAML'
name: boundary_short
duration: 0.3
estimation:
  camera: analytic
YAML
cat > "$out/ideal.yaml" <<'YAML'
name: boundary_ideal
duration: 0.3
world:
  profile: ideal
estimation:
  camera: analytic
YAML
cat > "$out/long.yaml" <<'YAML'
name: boundary_long
duration: 60
estimation:
  camera: analytic
YAML

# run_error DIR: the run_error of DIR/metrics.json (which must be UTF-8 JSON), or NO METRICS
run_error() {
  "$python" - "$1/metrics.json" <<'PY' 2>/dev/null || echo "NO METRICS"
import json, sys
print(json.load(open(sys.argv[1], encoding="utf-8", errors="strict"))["run_error"])
PY
}

# dead PID: the process has ended (gone, or a zombie nobody reaped yet)
dead() {
  local state
  state=$(sed 's/.*) //' "/proc/$1/stat" 2>/dev/null | cut -c1)
  [ -z "$state" ] || [ "$state" = Z ] || [ "$state" = X ]
}

# dies_within SECONDS PID: waits for PID to end
dies_within() {
  local i
  for i in $(seq "$(($1 * 20))"); do dead "$2" && return 0; sleep 0.05; done
  return 1
}

# left_by PID: the socket folders and rings hpa process PID left (none: empty)
left_by() { ls /tmp /dev/shm 2>/dev/null | grep "^hpa-flight-$1-"; }

# 1. --flight-timeout: finite seconds in [0.001, 3600]; --flight-stack: a command
for t in nan inf -inf 0 -1 1e9; do
  expect_exit 2 "--flight-timeout: expected seconds in \[0.001, 3600\], got '$t'" run \
    "$out/short.yaml" --quiet --out "$out/t" --flight-stack hpa-flight "--flight-timeout=$t"
done
for c in "" "   "; do
  expect_exit 2 "--flight-stack" run "$out/short.yaml" --quiet --out "$out/c" --flight-stack "$c"
done
[ ! -e "$out/t/metrics.json" ] && [ ! -e "$out/c/metrics.json" ] || fail "bad input flew a run"

# 2. a signal ends every wait on the stack: stop_run NAME SIGNAL MARK ARGS... starts hpa ARGS
# (HOSTILE_MARK=MARK), sends SIGNAL once the file MARK exists (the stack got that far), and sets
# $status and $stop_s (the signal to hpa's exit); a hung hpa is killed after 20 s
stop_run() {
  local name=$1 signal=$2 mark=$3 i t0 t1 pid watchdog
  shift 3
  rm -f "$mark"
  HOSTILE_MARK=$mark "$hpa" "$@" --quiet --out "$out/$name" > "$out/$name.log" 2>&1 &
  pid=$!
  started+=("$pid")
  for i in $(seq 400); do [ -e "$mark" ] && break; sleep 0.05; done
  [ -e "$mark" ] || fail "$name: the stack never got to $mark"
  sleep 0.3  # well into the wait
  (sleep 20; kill -9 "$pid" 2>/dev/null) &
  watchdog=$!
  t0=$(date +%s%N)
  kill "-$signal" "$pid"
  wait "$pid"
  status=$?
  t1=$(date +%s%N)
  kill "$watchdog" 2>/dev/null
  stop_s=$("$python" -c "print('%.3f' % (($t1 - $t0) / 1e9))")
  echo "$name: SIG$signal to exit $status in $stop_s s"
}
# what each stop must show: the exit code, the time (a wait ends 0.2 s after the signal, within a
# poll slice of 0.05 s; then the metrics are written and the stack reaped: 1 s leaves room for a
# loaded machine) and the run error
check_stop() {
  local name=$1 code=$2 pattern=$3
  [ "$status" -eq "$code" ] || fail "$name: exit $status, expected $code: $(cat "$out/$name.log")"
  "$python" -c "import sys; sys.exit(0 if $stop_s < 1.0 else 1)" \
    || fail "$name: $stop_s s from the signal to the exit"
  grep -Eq -- "$pattern" <<< "$(run_error "$out/$name")" \
    || fail "$name: run_error lacks /$pattern/: $(run_error "$out/$name")"
}
# the connect wait (30 s): a stack that never connects
stop_run connect INT "$out/connect.pid" run "$out/short.yaml" \
  --flight-stack "echo \$\$ > $out/connect.pid; exec sleep 100"
check_stop connect 130 "^stopped by signal 2 while waiting for flight stack '.*' to connect"
dies_within 2 "$(cat "$out/connect.pid")" || fail "connect: the stack outlived the run"
# the hello_ack wait: a stack that connects and says nothing
mute="import os, socket, time; s = socket.socket(socket.AF_UNIX); "
mute+="s.connect(os.environ['HPA_FLIGHT_SOCKET']); open('$out/hello.mark', 'w'); time.sleep(100)"
stop_run hello TERM "$out/hello.mark" run "$out/short.yaml" --flight-timeout 600 \
  --flight-stack "$python -c \"$mute\""
check_stop hello 143 "^stopped by signal 15 while waiting for flight stack .*\(hello\)"
# a reply wait under --flight-timeout 600: a stack that hangs
stop_run reply TERM "$out/reply.mark" run "$out/short.yaml" \
  --flight-timeout 600 --flight-stack "$stack hang"
check_stop reply 143 "^stopped by signal 15 while waiting for flight stack .*\(tick at t = 0"
# between ticks: a stack still answering gets a moment for its report (finish), then the run ends
stop_run running INT "$out/running.mark" run "$out/long.yaml" \
  --flight-stack "$stack ok"
check_stop running 130 "^stopped by signal 2 \(at t = "
"$python" - "$out/running/metrics.json" <<'PY' || fail "running: the stopped run's report"
import json, sys
m = json.load(open(sys.argv[1]))
assert m["estimator"]["variant"] == "boundary", m.get("estimator")
assert 0 < m["sim_time_s"] < 60, m["sim_time_s"]
PY

# 3. the time limit bounds the whole reply: its header at 0.8 s and body at 1.6 s are late for
# --flight-timeout 1
expect_exit "$run_error_exit" "no answer within 1.000000 s \(12 of the message's [0-9]+ bytes" \
  run "$out/short.yaml" --quiet --out "$out/split" --flight-timeout 1 --flight-stack "$stack split"

# 4. a stack's bytes that are not UTF-8 (its error, hello_ack, finish_reply): a run error that
# quotes it (U+FFFD for the bad bytes), metrics.json written
for mode in error_utf8 ack_utf8 finish_utf8; do
  expect_exit "$run_error_exit" "flight stack" run "$out/short.yaml" --quiet --out "$out/$mode" \
    --flight-stack "$stack $mode"
done
grep -q "the peer reported: boundary: bad bytes �� in my error" <<< "$(run_error "$out/error_utf8")" \
  || fail "error_utf8: $(run_error "$out/error_utf8")"
grep -q "malformed hello_ack: .*ill-formed UTF-8.*boundary �" <<< "$(run_error "$out/ack_utf8")" \
  || fail "ack_utf8: $(run_error "$out/ack_utf8")"
grep -q "malformed finish_reply: .*ill-formed UTF-8.*boundary �" <<< "$(run_error "$out/finish_utf8")" \
  || fail "finish_utf8: $(run_error "$out/finish_utf8")"

# 5. a stack that truncates the frame ring (rendered camera): a run error naming the ring, not
# SIGBUS; the ring and the socket folder are gone after the run
"$hpa" run "$out/short.yaml" --camera render --quiet --out "$out/ring" \
  --flight-stack "$stack truncate_ring" > "$out/ring.log" 2>&1 &
pid=$!
wait "$pid"
status=$?
[ "$status" -eq "$run_error_exit" ] || fail "truncate_ring: exit $status: $(cat "$out/ring.log")"
grep -Eq "the frame ring /hpa-flight-$pid-[0-9]+-0 shrank to 0 bytes" <<< "$(run_error "$out/ring")" \
  || fail "truncate_ring: $(run_error "$out/ring")"
[ -z "$(left_by "$pid")" ] || fail "truncate_ring left $(left_by "$pid")"

# 6. values the boundary refuses, each named with its value (a well-behaved stack first)
expect_exit 0 "" run "$out/short.yaml" --quiet --out "$out/ok" --flight-stack "$stack ok"
while read -r mode scenario pattern; do
  expect_exit "$run_error_exit" "$pattern" run "$out/$scenario.yaml" --quiet --out "$out/$mode" \
    --flight-stack "$stack $mode"
  grep -Eq -- "$pattern" <<< "$(run_error "$out/$mode")" \
    || fail "$mode: metrics.json's run_error lacks /$pattern/: $(run_error "$out/$mode")"
done <<'CASES'
frames_1000 short frames_detected 1000, but the tick delivered 0 frame
frames_negative short frames_detected 4294967291 \(at most 2\^31 - 1\)
counters_max short rejected_updates 4294967295 \(at most 2\^31 - 1\)
solve_negative short solve time -1000000000 ms, expected a time in \[0, 3600000\] ms
cost_negative short cost -4.0000000000000003e\+302, expected a finite number >= 0
quaternion_zero short quaternion q_WB of norm 0, expected a unit quaternion
quaternion_double short quaternion q_WB of norm 2, expected a unit quaternion
no_estimate ideal no estimate, but the tick asked for one
version_fraction short protocol version 1.9, this simulator version 1
version_wrap short protocol version 4294967297, this simulator version 1
finish_frames_huge short finish_reply's frames_detected is 1e\+300, expected an integer
finish_frames_negative short frames_detected is -5, expected an integer in \[0, 0\]
health_variant short entry 0 is named 'variant', a key metrics.json's estimator block reserves
CASES

# 7. the stack's processes end with the run: one that left the group for a session of its own
# dies when the run ends
expect_exit "$run_error_exit" "frames_detected 1000" run "$out/short.yaml" --quiet \
  --out "$out/gc" --flight-stack "setsid sleep 300 & echo \$! > $out/gc.pid; exec $stack frames_1000"
started+=("$(cat "$out/gc.pid")")
dies_within 2 "$(cat "$out/gc.pid")" || fail "the stack's own-session child outlived the run"

# hpa killed with SIGKILL mid-run (rendered camera: a ring too): its stack's shell dies with it
# at once (PR_SET_PDEATHSIG); its other processes, the ring and the socket folder are reclaimed by
# the next hpa that flies a stack
rm -f "$out/k9.pids"
HOSTILE_MARK="$out/k9.mark" "$hpa" run "$out/short.yaml" --camera render --quiet \
  --out "$out/k9" --flight-timeout 600 --flight-stack "echo \$\$ >> $out/k9.pids;
setsid sleep 300 & echo \$! >> $out/k9.pids; $stack hang & echo \$! >> $out/k9.pids; wait" \
  > /dev/null 2>&1 &
pid=$!
for i in $(seq 400); do [ -e "$out/k9.mark" ] && break; sleep 0.05; done
read -r -d '' shell_pid sleep_pid python_pid < "$out/k9.pids"
started+=("$shell_pid" "$sleep_pid" "$python_pid")
[ -n "$(left_by "$pid")" ] || fail "kill -9: the run had no folder or ring to leave"
kill -9 "$pid"
wait "$pid" 2> /dev/null
dies_within 1 "$shell_pid" || fail "kill -9: the stack's shell outlived hpa"
expect_exit "$run_error_exit" "exited with status 1 before connecting" run "$out/short.yaml" \
  --quiet --out "$out/next" --flight-stack "exit 1"
for p in "$sleep_pid" "$python_pid"; do
  dies_within 2 "$p" || fail "kill -9: the next hpa left process $p of the killed one's stack"
done
[ -z "$(left_by "$pid")" ] || fail "kill -9: the next hpa left $(left_by "$pid")"

echo "flight_boundary_test: $failures failure(s)"
[ "$failures" -eq 0 ]
