#!/usr/bin/env bash
# What a separate flight stack says is bounded and its replies are counted: an error message of
# megabytes reaches metrics.json cut to its first 4 KiB with its full length stated, and a second
# reply to one tick ends the run at once with a run error naming the stack and the tick it
# answered twice (not read as the next tick's reply), for a single vehicle's stack and a team's.
# usage: stack_replies_test.sh HPA_BIN SOURCE_DIR PYTHON
source "$(dirname "$0")/cli_test_lib.sh"
cli_test_start "$@"

# a stack that acks, then sends an 8 MiB error (long_error) or answers tick 100 twice (double)
cat > "$out/stack.py" <<PY
import json, sys
sys.path.insert(0, "$src/python")
from hpa_sim import lockstep
mode = sys.argv[1]
client = lockstep.FlightStackClient()
client.receive()
client.send(lockstep.HELLO_ACK, json.dumps({"protocol_version": 1, "name": "replies " + mode,
                                            "control_rate_hz": 100}).encode())
if mode == "long_error":
    client.send(lockstep.ERROR, b"E" * (8 << 20))
    sys.exit(1)
ticks = 0
while True:
    kind, body = client.receive()
    tick = lockstep.decode_tick(body)
    reply = lockstep.encode_reply(lockstep.Command([0, 0, 0], 8.0), {"time_s": tick.time_s})
    client.send(lockstep.TICK_REPLY, reply)
    ticks += 1
    if mode == "double" and ticks == 100:  # the tick at t = 0.099 s, answered twice
        client.send(lockstep.TICK_REPLY, reply)
PY
cat > "$out/short.yaml" <<'YAML'
name: replies_short
duration: 0.5
estimation:
  camera: analytic
YAML

# run_error DIR: metrics.json's run_error
run_error() {
  "$python" -c 'import json, sys; print(json.load(open(sys.argv[1]))["run_error"])' "$1/metrics.json"
}

# 1. an 8 MiB error text: the first 4096 bytes and the length, in metrics.json and on stderr
expect_exit 3 "error text of 8388608 bytes, first 4096 shown" run "$out/short.yaml" --quiet \
  --out "$out/long" --flight-stack "$python $out/stack.py long_error"
error=$(run_error "$out/long")
grep -q "the peer reported: E\{4096\} \.\.\. (error text of 8388608 bytes, first 4096 shown)" \
  <<< "$error" || fail "the long error's text: ${error:0:200}"
[ "$(stat -c %s "$out/long/metrics.json")" -lt 20000 ] ||
  fail "metrics.json of the long error is $(stat -c %s "$out/long/metrics.json") bytes"

# 2. a second reply to the tick at t = 0.099 s: a run error at the next tick, naming the stack
expect_exit 3 "second reply" run "$out/short.yaml" --quiet --out "$out/double" \
  --flight-stack "$python $out/stack.py double"
error=$(run_error "$out/double")
grep -q "^flight stack '$python $out/stack.py double': tick at t = 0.100000 s: a second reply to \
the tick at t = 0.099000 s" <<< "$error" || fail "the second reply's run error: $error"

# 3. a team's stack (one for the team) that answers its 50th team_tick twice: a run error at a
# later team_tick naming the stack and the team_tick answered twice (a team_tick_reply carries no
# time, so the bytes waiting before the next send are what shows it)
cat > "$out/team_stack.py" <<PY
import sys
sys.path.insert(0, "$src/python")
from hpa_sim import lockstep
client = lockstep.FlightStackClient()
hello = client.team_hello()
client.team_hello_ack(hello, "double team", 100)
ticks = 0
while True:
    kind, body = client.receive()
    if kind == lockstep.FINISH:
        client.send(lockstep.FINISH_REPLY, b"{}")
        break
    time_s, views = lockstep.decode_team_tick(body)
    reply = lockstep.encode_team_tick_reply(
        [(v.vehicle, lockstep.Command([0, 0, 0], 8.0), True) for v in views])
    client.send(lockstep.TEAM_TICK_REPLY, reply)
    ticks += 1
    if ticks == 50:
        client.send(lockstep.TEAM_TICK_REPLY, reply)
PY
expect_exit 3 "second reply" run "$src/scenarios/ci/team2_line.yaml" --set duration=1 --quiet \
  --out "$out/team_double" --team-stack one --flight-stack "$python $out/team_stack.py"
error=$(run_error "$out/team_double")
grep -q "^flight stack '$python $out/team_stack.py': team_tick at t = [0-9.]* s: a second reply \
to the team_tick at t = [0-9.]* s" <<< "$error" || fail "the team's second reply: $error"

[ "$failures" -eq 0 ] || { echo "$failures check(s) failed"; exit 1; }
echo "stack replies: all checks passed"
