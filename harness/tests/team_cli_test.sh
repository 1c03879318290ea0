#!/usr/bin/env bash
# Team runs through the real `hpa` (docs/cooperative.md): a team scenario's bad input named by
# key, the same run twice the same (metrics and log row for row), log.csv's per-vehicle columns,
# the team plots, the rate table, a push that slackens the named vehicle's cable, and the
# baseline flying the same scenario.
# usage: team_cli_test.sh HPA_BIN SOURCE_DIR PYTHON
source "$(dirname "$0")/cli_test_lib.sh"
cli_test_start "$@"
base=$src/scenarios/ci/team2_cable_slack.yaml

# bad input: each refused with exit 2, naming the key and what was wrong
expect_exit 2 "a payload block belongs to a team scenario" run "$src/scenarios/hover.yaml" \
  --set payload.mass_kg=0.2 --out "$out/bad"
expect_exit 2 "vehicles.*1 to 3 vehicles" run "$base" --set 'vehicles=[{}, {}, {}, {}]' \
  --out "$out/bad"
expect_exit 2 "vehicles.*1 to 3 vehicles" run "$base" --set 'vehicles=[]' --out "$out/bad"
expect_exit 2 "vehicles.0.cable_length_m" run "$base" --set vehicles.0.cable_length_m=-1 \
  --out "$out/bad"
expect_exit 2 "vehicles.1.start_slack_m" run "$base" --set vehicles.1.start_slack_m=0.6 \
  --out "$out/bad"
expect_exit 2 "vehicles.0.*attach_m" run "$base" --set 'vehicles.0.attach_m=[0, 0]' \
  --out "$out/bad"
expect_exit 2 "vehicles.0.*wheels" run "$base" --set vehicles.0.wheels=4 --out "$out/bad"
expect_exit 2 "world.contact.*not the single vehicle's contacts" run "$base" \
  --set world.contact.enabled=true --out "$out/bad"
expect_exit 2 "controller.type.*cooperative" run "$base" --set controller.type=nonhybrid_mpc \
  --out "$out/bad"
expect_exit 2 "--controller.*unknown controller 'geometric'" run "$base" --controller geometric \
  --out "$out/bad"
expect_exit 2 "events.0.vehicle.*vehicle 2 is not in the scenario \(2 vehicles" run "$base" \
  --set events.0.vehicle=2 --out "$out/bad"
expect_exit 2 "events.0.vehicle.*vehicle 1 is not in the scenario \(1 vehicle," run \
  "$src/scenarios/line_impulse.yaml" --set events.0.body=quadrotor --set events.0.vehicle=1 \
  --out "$out/bad"
expect_exit 2 "events.0.*impulse, velocity_change and fault events only, not 'wind'" run "$base" \
  --set 'events.0={at: 1.0, type: wind, force: [1, 0, 0], duration: 1.0}' --out "$out/bad"
expect_exit 2 "payload.mass_kg" run "$base" --set payload.mass_kg=0 --out "$out/bad"
# faults: a motor's reaches a team's vehicle, named by index; a sensor's only when it flies on board
expect_exit 2 "events.0.component.*estimates its own state on board.*'vio' fault" run "$base" \
  --set 'events.0={at: 1.0, type: fault, vehicle: 0, component: vio, mode: off, duration: 1.0}' \
  --out "$out/bad"
expect_exit 2 "events.0.vehicle.*a team's fault names its vehicle \(0 to 1\)" run "$base" \
  --set 'events.0={at: 1.0, type: fault, component: motor, mode: off, motor: 0, duration: 0.1}' \
  --out "$out/bad"
expect_exit 2 "events.0.vehicle.*vehicle 2 is not in the scenario" run "$base" \
  --set 'events.0={at: 1.0, type: fault, vehicle: 2, component: motor, mode: off, motor: 0}' \
  --out "$out/bad"
expect_exit 2 "expect.fault_health_flag_max.*a team run does not measure" run \
  "$src/scenarios/ci/team2_motor_loss.yaml" --set expect.fault_health_flag_max=1 --out "$out/bad"
# a start no team can fly from is refused; a team too weak to lift its payload is warned about
expect_exit 2 "vehicles.*vehicles 0 and 1 start 0 m apart, their bodies overlapping" run "$base" \
  --set 'vehicles.1.attach_m=[0.35, 0, 0]' --out "$out/bad"
expect_exit 1 "full thrust, 40.2 N, cannot lift its weight, 995 N" run "$base" \
  --set payload.mass_kg=100 --out "$out/weak"

# the same run twice is the same run; its log has every vehicle's columns and its plots are
# written
"$hpa" run "$base" --out "$out/a" --plots --quiet || fail "team run a exited $?"
"$hpa" run "$base" --out "$out/b" --quiet || fail "team run b exited $?"
same_run "$out/a" "$out/b" "a team run twice" --rows 500
head -1 "$out/a/log.csv" | grep -q "v1_tension_N,v1_mode,v1_taut_seen" ||
  fail "log.csv lacks vehicle 1's columns: $(head -1 "$out/a/log.csv")"
for plot in tracking team_cables; do
  [ -s "$out/a/$plot.png" ] || fail "no $plot.png"
done
"$python" - "$out/a/metrics.json" << 'PY' || fail "team metrics"
import json, sys
m = json.load(open(sys.argv[1]))
t = m["team"]
assert t["vehicle_count"] == 2 and len(t["vehicles"]) == 2, t
# the push on vehicle 1 slackens its cable and not vehicle 0's
assert t["vehicles"][1]["slack_events"] >= 1 and t["vehicles"][1]["retaut_count"] >= 1, t
assert t["vehicles"][0]["slack_time_s"] == 0.0, t
# what a team run does not measure is null, not a perfect-looking value
for key in ("quad_rmse_m", "mode_accuracy", "payload_in_fov_fraction", "contacts"):
    assert m[key] is None, (key, m[key])
assert m["camera"] == "mocap" and m["controller"] == "cooperative", m
PY

# the rate table lists the motion capture and each vehicle's loops
"$hpa" schema rates "$base" > "$out/rates.md" || fail "schema rates exited $?"
grep -q "motion capture" "$out/rates.md" || fail "rate table lacks the motion capture"

# the baseline flies the same scenario
"$hpa" run "$base" --controller hpa_mpc --out "$out/mpc" --quiet || fail "hpa_mpc team run"
grep -q '"controller": "hpa_mpc"' "$out/mpc/metrics.json" || fail "baseline not named"

# hpa compare flies both team controllers by default and names an unknown one
"$hpa" compare "$base" --out "$out/compare" --quiet || fail "team compare exited $?"
for c in cooperative hpa_mpc; do
  [ -s "$out/compare/$c/metrics.json" ] || fail "compare flew no $c"
done
[ -s "$out/compare/comparison.png" ] || fail "no team comparison plot"
expect_exit 2 "--controllers.*unknown controller 'nonhybrid_mpc'" compare "$base" \
  --controllers cooperative,nonhybrid_mpc --out "$out/compare_bad"

# the shipped team sweeps run (a fifth of each: every 5th run, which walks through all six grid
# cells, both controllers among them)
for sweep in team_cables team_attachment; do
  "$hpa" sweep "$src/scenarios/sweeps/$sweep.yaml" --shard 1/5 --jobs 2 --out "$out/$sweep" \
    > /dev/null 2>&1 || fail "sweep $sweep exited $?"
  "$python" - "$out/$sweep/runs.jsonl" << 'PY' || fail "sweep $sweep records"
import json, sys
runs = [json.loads(line) for line in open(sys.argv[1])]
assert len(runs) == 12, len(runs)
bad = [r["run"] for r in runs if r["status"] != "ok" or not r["metrics"]["team"]]
assert not bad, "runs without team metrics: %s" % bad
flown = {r["controller"] for r in runs}
assert flown == {"cooperative", "hpa_mpc"}, flown
PY
done

# a motor fault on vehicle 1: its recovery names the vehicle, and what a camera and an onboard
# estimator would count is null (a team has neither)
"$hpa" run "$src/scenarios/ci/team2_motor_loss.yaml" --out "$out/fault" --quiet ||
  fail "team2_motor_loss exited $?"
"$python" - "$out/fault/metrics.json" << 'PY' || fail "team fault metrics"
import json, sys
m = json.load(open(sys.argv[1]))
f = m["faults"][0]
assert f["vehicle"] == 1 and f["component"] == "motor" and f["mode"] == "loss", f
assert f["tracking_left_bound"] and f["tracking_recovered_s"] is not None, f
for key in ("payload_lost", "estimator_resets", "rejected_updates", "health_flag_s",
            "estimate_error_max_m"):
    assert f[key] is None, (key, f[key])
assert m["fault_recovery"]["tracking_error_max_m"] > 0.1, m["fault_recovery"]
PY
# hpa compare on a team: the team's metrics, none of what a team does not measure
"$hpa" compare "$base" --out "$out/compare" --quiet > /dev/null 2>&1 || fail "team compare exited $?"
for row in "cable tension max \[N\]" "vehicle separation min \[m\]" "payload tilt max \[deg\]"; do
  grep -Eq "^\| $row \| [0-9]" "$out/compare/comparison.md" ||
    fail "team comparison lacks the row '$row': $(cat "$out/compare/comparison.md")"
done
grep -q "mode accuracy\|payload in view" "$out/compare/comparison.md" &&
  fail "team comparison has rows a team does not measure: $(cat "$out/compare/comparison.md")"
[ "$failures" -eq 0 ] && echo "team CLI: all checks passed"
exit "$failures"
