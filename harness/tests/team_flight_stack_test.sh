#!/usr/bin/env bash
# A team's separate flight stacks (docs/protocol.md, Teams): hpa-flight per vehicle (the default,
# each started with HPA_VEHICLE set) and one hpa-flight for the whole team (--team-stack one) fly
# the team exactly as in process: metrics.json equal but for the timings and what flew (the
# team block too, but for its solve times), log.csv row for row but for the solve times. A stack
# that answers a non-finite command, a reply for another vehicle or a reply cut short ends the run
# with a run error naming it (exit 3, metrics.json written with the run so far).
# Usage: team_flight_stack_test.sh HPA_BINARY SOURCE_DIR PYTHON
set -uo pipefail
source "$2/harness/tests/cli_test_lib.sh"
cli_test_start "$@"  # hpa, src, python; out: a folder removed at exit

# same_team_run A B LABEL: the same run, metrics (timings left out at any depth) and log row for
# row (every vehicle's solve time left out), B flown by hpa-flight
same_team_run() {
  same_run "$1" "$2" "$3" --rows 100 --stack-b hpa-flight
}

# 1. team2_line (two vehicles, the cooperative controller) and team3_lift (three, lifting from the
# ground) in process, per vehicle and as one stack; team2_line with hpa_mpc on each vehicle. The
# runs are cut short, so an expect bound may fail (exit 1): the same in every run, compared too
flown() {
  local status=$1 label=$2
  [ "$status" -le 1 ] || fail "$label failed (exit $status)"
}
fly() {
  local name=$1 scenario=$2; shift 2
  "$hpa" run "$scenario" --quiet --out "$out/${name}_in" "$@" > /dev/null
  flown $? "$name in process"
  "$hpa" run "$scenario" --quiet --out "$out/${name}_per" "$@" --flight-stack hpa-flight \
    > /dev/null
  flown $? "$name per vehicle"
  same_team_run "$out/${name}_in" "$out/${name}_per" "$name per vehicle"
  "$hpa" run "$scenario" --quiet --out "$out/${name}_one" "$@" --flight-stack hpa-flight \
    --team-stack one > /dev/null
  flown $? "$name one stack"
  same_team_run "$out/${name}_in" "$out/${name}_one" "$name one stack"
}
fly line "$src/scenarios/ci/team2_line.yaml" --set duration=3
fly lift "$src/scenarios/ci/team3_lift.yaml" --set duration=3
fly line_mpc "$src/scenarios/ci/team2_line.yaml" --set duration=1.5 --controller hpa_mpc

# 2. each per-vehicle stack is started with HPA_VEHICLE, and a stack for another vehicle than its
# HPA_VEHICLE says is refused by hpa-flight itself
"$hpa" run "$src/scenarios/ci/team2_line.yaml" --quiet --out "$out/env" --set duration=0.2 \
  --flight-stack 'echo "vehicle $HPA_VEHICLE" >&2; exec hpa-flight' 2> "$out/env.err" > /dev/null \
  || fail "the HPA_VEHICLE run failed"
grep -q "vehicle 0" "$out/env.err" && grep -q "vehicle 1" "$out/env.err" \
  || fail "HPA_VEHICLE was not set per vehicle: $(cat "$out/env.err")"
expect_exit 3 "HPA_VEHICLE=1, but the team_hello asks for 2 vehicle" run \
  "$src/scenarios/ci/team2_line.yaml" --quiet --out "$out/env_one" --set duration=0.2 \
  --flight-stack "HPA_VEHICLE=1 hpa-flight" --team-stack one

# 3. bad replies at the stack's 20th control step: a run error naming the value, the vehicle and
# the step; metrics.json written with the run so far
cat > "$out/bad_team.py" <<PY
import json, sys, time
sys.path[:0] = ["$src/python"]
from hpa_sim import lockstep

ids = {name: kind for kind, name in lockstep.MESSAGE_TYPES.items()}
mode = sys.argv[1]
client = lockstep.FlightStackClient()
kind, body = client.receive()
hello = json.loads(body)
client.send(ids["team_hello_ack"], json.dumps({
    "protocol_version": lockstep.PROTOCOL_VERSION, "name": "bad team", "control_rate_hz": 100.0,
    "vehicles": hello["vehicles"]}).encode())
steps = 0
while True:
    kind, body = client.receive()
    if kind == ids["finish"]:
        client.send(ids["finish_reply"], b"{}")
        break
    tick = lockstep.decode("team_tick", body, "team_tick")
    steps += 1
    bad = steps == 20
    if bad and mode == "hang":
        time.sleep(30)
    replies = []
    for v in tick["views"]:
        thrust_N = float("nan") if bad and mode == "nan" else 5.0
        vehicle = v["vehicle"] + (7 if bad and mode == "vehicle" else 0)
        replies.append({"vehicle": vehicle, "cable_taut": True,
                        "output": {"command": {"w_B_radps": [0.0, 0.0, 0.0], "thrust_N": thrust_N},
                                   "status": "success", "solve_time_ms": 0.0, "cost": 0.0}})
    data = lockstep.encode("team_tick_reply", {"replies": replies})
    client.send(ids["team_tick_reply"], data[:-4] if bad and mode == "short" else data)
PY
bad_run() {
  local mode=$1 pattern=$2; shift 2
  expect_exit 3 "$pattern" run "$src/scenarios/ci/team2_line.yaml" --quiet --out "$out/bad_$mode" \
    --set duration=1 --flight-stack "$python $out/bad_team.py $mode" "$@"
  "$python" - "$out/bad_$mode" "$pattern" <<'PY' || fail "bad $mode: metrics.json lacks the error"
import json, re, sys
m = json.load(open(sys.argv[1] + "/metrics.json"))
assert m["run_error"] and re.search(sys.argv[2], m["run_error"]), m["run_error"]
assert m["flight_stack"] == "bad team", m["flight_stack"]
PY
}
bad_run nan "\(vehicle 0\): team_tick at t = 0\.200000 s: malformed team_tick_reply message: a non-finite command \(body rate or thrust\) \(reply 0, vehicle 0\)"
bad_run vehicle "team_tick at t = 0\.200000 s: team_tick_reply refused: reply 0 is for vehicle 7, expected vehicle 0" --team-stack one
bad_run short "team_tick at t = 0\.200000 s: malformed team_tick_reply message: replies count 2, more than the rest of the message holds" --team-stack one

# 4. a single vehicle's stack is greeted with a team_hello, which it refuses: a run error
expect_exit 3 "expected a hello, got a team_hello message" run \
  "$src/scenarios/ci/team2_line.yaml" --quiet --out "$out/single" --set duration=0.2 \
  --flight-stack "$python $src/examples/python/hover_controller.py"
# and hpa-flight refuses to own a team vehicle's rate loop (the simulator keeps it)
expect_exit 3 "a team's stack owns no rate loop" run "$src/scenarios/ci/team2_line.yaml" --quiet \
  --out "$out/own" --set duration=0.2 --flight-stack "hpa-flight --own-rate-loop"

# 5. SIGINT while the stacks are waited for, to connect and to reply: stopped (exit 130), the
# run's files written, no stack left running
stopped() {
  local label=$1 wait_s=$2; shift 2
  "$hpa" run "$src/scenarios/ci/team2_line.yaml" --quiet --out "$out/$label" "$@" \
    > /dev/null 2>&1 &
  local pid=$!
  sleep "$wait_s"
  kill -INT "$pid"
  wait "$pid"
  local status=$?
  [ "$status" -eq 130 ] || fail "$label: exit $status after SIGINT, expected 130"
  grep -q "stopped by signal 2" "$out/$label/metrics.json" || fail "$label: no stop in metrics.json"
}
stopped stop_connect 0.5 --flight-stack "sleep 30"
stopped stop_reply 2 --flight-stack "$python $out/bad_team.py hang" --team-stack one
pgrep -f "$out/bad_team.py" > /dev/null && fail "a stack outlived its stopped run"

exit $((failures > 0))
