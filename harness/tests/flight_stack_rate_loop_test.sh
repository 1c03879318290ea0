#!/usr/bin/env bash
# A flight stack that owns the rate loop (docs/protocol.md, rate_tick and rate_reply): the
# simulator runs no autopilot and the stack answers each rate-loop step with rotor speeds.
# hpa-flight --own-rate-loop runs the same Autopilot on its side, so its runs equal the in-process
# ones metric for metric, with PX4's rate loop (the flight profile) and with the project's own
# loop (the ideal profile, and the flight profile with rate_loop.px4 false); a stack that answers
# a non-finite or out-of-range rotor speed is a run error naming it (exit 3, metrics.json written
# with the run so far). Usage: flight_stack_rate_loop_test.sh HPA_BINARY SOURCE_DIR PYTHON
set -uo pipefail
source "$2/harness/tests/cli_test_lib.sh"
cli_test_start "$@"  # hpa, src, python; out: a folder removed at exit

# fly NAME SCENARIO [ARGS...]: the scenario in process and through hpa-flight --own-rate-loop
fly() {
  local name=$1 scenario=$2; shift 2
  "$hpa" run "$scenario" --quiet --out "$out/${name}_in" "$@" > /dev/null \
    || fail "$name: in-process run failed"
  "$hpa" run "$scenario" --quiet --out "$out/${name}_own" "$@" \
    --flight-stack "hpa-flight --own-rate-loop" > /dev/null || fail "$name: hpa-flight run failed"
  same_run "$out/${name}_in" "$out/${name}_own" "$name" --rows 100 --stack-b hpa-flight
}

# 1. PX4's rate loop on the rate gyro (the flight profile): the analytic camera with the
# estimator, and the rendered camera read at capture (detects interleave with rate ticks)
fly px4_csv "$src/scenarios/csv_reference.yaml"
fly px4_render "$src/scenarios/hover_gripper_pull.yaml"
# and a stack that answers every tick (no batching) owns it the same way
"$hpa" run "$src/scenarios/csv_reference.yaml" --quiet --out "$out/px4_csv_tick" \
  --flight-stack "hpa-flight --per-tick --own-rate-loop" > /dev/null || fail "per-tick run failed"
same_run "$out/px4_csv_in" "$out/px4_csv_tick" "px4_csv per tick" --rows 100 --stack-b hpa-flight

# 2. the project's own loop on the estimated body rate: the ideal profile with ground truth, and
# the flight profile with PX4's loop switched off (the estimate comes from the stack's estimator)
fly own_truth "$src/scenarios/ci/hover_hpa_mpc_truth.yaml"
fly own_csv "$src/scenarios/csv_reference.yaml" --set world.rate_loop.px4=false
"$python" - "$out/px4_csv_in" "$out/own_csv_in" <<'PY' || fail "the own loop flew as PX4's"
import json, sys
a, b = (json.load(open(p + "/metrics.json")) for p in sys.argv[1:3])
assert a["payload_rmse_m"] != b["payload_rmse_m"], "rate_loop.px4=false changed nothing"
PY

# 3. a stack that owns the rate loop and answers hover speeds, then a bad one at its 100th step
# (t = 0.1 s: PX4's loop steps on each 1 kHz gyro sample, the first after the first physics step)
cat > "$out/bad_rotors.py" <<PY
import math, sys
sys.path[:0] = ["$src/python"]
from hpa_sim import RotorCommand, run

class BadRotors:
    def __init__(self, hello):
        p = hello["config"]["params"]
        thrust_N = (p["quad_mass_kg"] + p["payload_mass_kg"]) * p["gravity_mps2"]
        self.hover_radps = math.sqrt(thrust_N / (4 * p["k_f_N_per_radps2"]))
        self.thrust_N = thrust_N
        self.steps = 0

    def step(self, tick):
        return None

    def rate_loop(self, rate_tick):
        self.steps += 1
        w = [self.hover_radps] * 4
        if self.steps == 100:
            w[int(sys.argv[2])] = float(sys.argv[1])
        return RotorCommand(w, self.thrust_N)

run(BadRotors, owns_rate_loop=True)
PY
hover="$src/scenarios/hover.yaml"
expect_exit 3 "rate loop at t = 0.100000 s: .*a non-finite rotor speed command nan rad/s" \
  run "$hover" --quiet --out "$out/nan" --flight-stack "$python $out/bad_rotors.py nan 2"
expect_exit 3 "rate loop at t = 0.100000 s: rate_reply refused: rotor 1 speed command 5000 rad/s, outside the motors' range \[100, 1830\] rad/s" \
  run "$hover" --quiet --out "$out/fast" --flight-stack "$python $out/bad_rotors.py 5000 1"
expect_exit 3 "rotor 3 speed command -1 rad/s, outside" \
  run "$hover" --quiet --out "$out/negative" --flight-stack "$python $out/bad_rotors.py -1 3"
for run in nan fast negative; do
  "$python" - "$out/$run/metrics.json" <<'PY' || fail "$run: the run so far was not kept"
import json, sys
m = json.load(open(sys.argv[1]))
assert m["run_error"].startswith("flight stack"), m["run_error"]
assert m["sim_time_s"] == 0.1, m["sim_time_s"]
assert m["flight_stack"] == "BadRotors", m["flight_stack"]
PY
done

echo "flight_stack_rate_loop_test: $failures failure(s)"
[ "$failures" -eq 0 ]
