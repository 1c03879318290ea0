#!/usr/bin/env bash
# The flight stack as its own process (docs/protocol.md): hpa-flight gives the in-process
# metrics exactly; the Python example flies hover_gripper_pull; a stack that does not start,
# hangs, dies, speaks another version, or answers NaN or garbage is a run error naming what
# happened (exit 3, metrics.json written), never a hung simulator; the Python loaders read
# what a run writes. Usage: flight_stack_test.sh HPA_BINARY SOURCE_DIR PYTHON
set -uo pipefail
source "$2/harness/tests/cli_test_lib.sh"
cli_test_start "$@"  # hpa, src, python; out: a folder removed at exit

# 1. hpa-flight flies the rendered hover_gripper_pull exactly as the in-process stack does:
# every metric but the wall-clock timings and what flew (it reads each frame at its capture,
# region first, so even the camera's region fraction is the in-process one)
"$hpa" run "$src/scenarios/hover_gripper_pull.yaml" --quiet --out "$out/in" \
  || fail "in-process run failed"
"$hpa" run "$src/scenarios/hover_gripper_pull.yaml" --quiet --out "$out/ex" \
  --flight-stack hpa-flight || fail "hpa-flight run failed"
same_run "$out/in" "$out/ex" "hover_gripper_pull through hpa-flight" --stack-b hpa-flight

# the analytic camera's detections cross too: the file-reference scenario, exactly
"$hpa" run "$src/scenarios/csv_reference.yaml" --quiet --out "$out/csv_in" || fail "csv in process"
"$hpa" run "$src/scenarios/csv_reference.yaml" --quiet --out "$out/csv_ex" \
  --flight-stack hpa-flight || fail "csv through hpa-flight"
same_run "$out/csv_in" "$out/csv_ex" "csv through hpa-flight" --stack-b hpa-flight

# batched ticks (hpa-flight's default) against a reply every tick (--per-tick, the protocol's
# first behaviour): the same metrics and the same log, solve times aside
"$hpa" run "$src/scenarios/csv_reference.yaml" --quiet --out "$out/csv_tick" \
  --flight-stack "hpa-flight --per-tick" || fail "csv through hpa-flight --per-tick"
# and with a video, whose frames read the estimate at their ticks (a reply read at once, some
# at control ticks: their commands are still taken when due, so the log keeps its order)
for how in "hpa-flight" "hpa-flight --per-tick"; do
  "$hpa" run "$src/scenarios/csv_reference.yaml" --quiet --set duration=2 \
    --out "$out/video_${how##* }" --video "$out/video_${how##* }.mp4" --flight-stack "$how" \
    > /dev/null 2>&1 || fail "csv with a video through $how"
done
same_run "$out/video_--per-tick" "$out/video_hpa-flight" "batched ticks with a video" --rows 250
same_run "$out/csv_tick" "$out/csv_ex" "batched ticks against per-tick" --rows 1000

# the Python client batches too: the example controller commanding on its declared control
# rate's ticks (tick.control_due), with and without batched_ticks, flies the same run
cat > "$out/on_the_clock.py" <<PY
import sys
sys.path[:0] = ["$src/python", "$src/examples/python"]
from hover_controller import CONTROL_RATE_HZ, HoverController
from hpa_sim import run


class OnTheClock(HoverController):
    def step(self, tick):
        self.next_control_s = 0.0 if tick.control_due else float("inf")
        return super().step(tick)


sys.exit(run(OnTheClock, name="on the clock", control_rate_hz=CONTROL_RATE_HZ,
             batched_ticks=sys.argv[1] == "batched"))
PY
for how in batched per_tick; do
  "$hpa" run "$src/scenarios/csv_reference.yaml" --quiet --out "$out/py_$how" \
    --flight-stack "$python $out/on_the_clock.py $how" > /dev/null 2>&1
done
same_run "$out/py_per_tick" "$out/py_batched" "the Python client's batched ticks" --rows 900

# 2. the Python example controller flies hover_gripper_pull to its end through the interface;
# its bound: 0.217 m deviation measured by an earlier example (a hold on VIO alone) times 1.5;
# the example on VIO, the IMU and its tension cue measures 0.058 m
"$hpa" run "$src/scenarios/hover_gripper_pull.yaml" --quiet --out "$out/py" \
  --flight-stack "$python $src/examples/python/hover_controller.py" > /dev/null 2>&1
"$python" - "$out/py" "$src/python" <<'PY' || fail "the Python controller's run"
import sys
sys.path.insert(0, sys.argv[2])
from hpa_sim import load_log, load_metrics
m = load_metrics(sys.argv[1] + "/metrics.json")
assert m["run_error"] is None, m["run_error"]
assert not m["crashed"], m["crash_reason"]
assert m["sim_time_s"] == 12.0, m["sim_time_s"]
assert m["flight_stack"] == "python hover_controller", m["flight_stack"]
assert m["quad_position_deviation_max_m"] < 0.33, m["quad_position_deviation_max_m"]
log = load_log(sys.argv[1] + "/log.csv")
assert len(log["time_s"]) > 1000, len(log["time_s"])  # one row per control step, 100 Hz
assert abs(log["time_s"][-1] - 12.0) < 0.02, log["time_s"][-1]
print("python: deviation %.3f m over %d control steps" % (m["quad_position_deviation_max_m"], len(log["time_s"])))
PY

# 3. hostile stacks: a clear run error, exit 3, within the step timeout, metrics kept
hostile="$python $src/harness/tests/hostile_flight_stack.py"
hover="$src/scenarios/hover.yaml"
expect_exit 3 "exited with status 1 before connecting" run "$hover" --quiet --out "$out/h0" \
  --flight-stack "exit 1"
expect_exit 3 "tick at t = 0.000000 s: no answer within 0.5" run "$hover" --quiet \
  --out "$out/h1" --flight-timeout 0.5 --flight-stack "$hostile hang"
expect_exit 3 "speaks protocol version 99" run "$hover" --quiet --out "$out/h2" \
  --flight-stack "$hostile version"
expect_exit 3 "non-finite command" run "$hover" --quiet --out "$out/h3" \
  --flight-stack "$hostile nan"
expect_exit 3 "magic" run "$hover" --quiet --out "$out/h4" --flight-timeout 2 \
  --flight-stack "$hostile garbage"
expect_exit 3 "exited with status 7" run "$hover" --quiet --out "$out/h5" \
  --flight-stack "$hostile die"
# a stack that declared batched ticks: its silence is found when a command is due, and a control
# tick answered without a command breaks its declaration
expect_exit 3 "the command of the control step at t = 0.000000 s: no answer within 0.5" run \
  "$hover" --quiet --out "$out/h6" --flight-timeout 0.5 --flight-stack "$hostile batched_hang"
expect_exit 3 "no command at a tick of its declared control rate" \
  run "$hover" --quiet --out "$out/h7" --flight-stack "$hostile batched_nocommand"
grep -q '"run_error": "flight stack' "$out/h5/metrics.json" \
  || fail "the dead stack's run error is not in metrics.json"
grep -q '"sim_time_s": 0.05' "$out/h5/metrics.json" \
  || fail "the dead stack's run lost the 50 ticks it flew: $(grep sim_time "$out/h5/metrics.json")"

# 4. the Python loader of a sweep's runs.jsonl: one dict per run with its drawn values
cat > "$out/tiny_sweep.yaml" <<YAML
base: $src/scenarios/hover.yaml
runs: 2
seed: 3
vary:
  duration: {list: [2.5]}
  events.0.force.0: {uniform: [0.1, 0.3]}
YAML
"$hpa" sweep "$out/tiny_sweep.yaml" --out "$out/sweep" > /dev/null 2>&1 || fail "tiny sweep failed"
"$python" - "$out/sweep/runs.jsonl" "$src/python" <<'PY' || fail "load_runs"
import sys
sys.path.insert(0, sys.argv[2])
from hpa_sim import load_runs
runs = load_runs(sys.argv[1])
assert len(runs) == 2, len(runs)
assert sorted(r["run"] for r in runs) == [0, 1], [r["run"] for r in runs]
forces = [r["values"]["events.0.force.0"] for r in runs]
assert all(0.1 <= f <= 0.3 for f in forces) and forces[0] != forces[1], forces
assert all(r["status"] == "ok" for r in runs), [r["status"] for r in runs]
print("load_runs: %d runs, forces %s" % (len(runs), forces))
PY

echo "flight_stack_test: $failures failure(s)"
[ "$failures" -eq 0 ]
