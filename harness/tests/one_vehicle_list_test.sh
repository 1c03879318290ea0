#!/usr/bin/env bash
# A `vehicles:` list of one is the single vehicle (docs/cooperative.md, "One vehicle"): the same
# scenario with and without it is the same run, metrics and log row for row (hover, and the
# rendered line with its payload push); a list's cable length and payload mass are the params
# block's; and what only a team has (an attachment off the centre, a start slack, an inertia, a
# team controller), a team event that names no vehicle, or a bound on what the kind of run does
# not measure, is refused naming the key.
# usage: one_vehicle_list_test.sh HPA_BIN SOURCE_DIR PYTHON
source "$(dirname "$0")/cli_test_lib.sh"
cli_test_start "$@"
hover=$src/scenarios/hover.yaml
line=$src/scenarios/line_impulse.yaml
team=$src/scenarios/ci/team2_cable_slack.yaml

# the same run, bit for bit
"$hpa" run "$hover" --out "$out/hover" --quiet || fail "hover exited $?"
"$hpa" run "$hover" --set 'vehicles=[{cable_length_m: 0.5}]' --out "$out/hover1" --quiet ||
  fail "hover with a one-vehicle list exited $?"
same_run "$out/hover" "$out/hover1" "hover with and without a one-vehicle list" --rows 1000
"$hpa" run "$line" --out "$out/line" --quiet || fail "line_impulse exited $?"
"$hpa" run "$line" --set 'vehicles=[{}]' --set 'payload={mass_kg: 0.1}' --out "$out/line1" \
  --quiet || fail "line_impulse with a one-vehicle list exited $?"
same_run "$out/line" "$out/line1" "line_impulse with and without a one-vehicle list" --rows 1000

# a one-vehicle list's cable and payload are the params block's
"$hpa" run "$hover" --set 'params={cable: {length_m: 0.45}, payload: {mass_kg: 0.12}}' \
  --out "$out/params" --quiet || fail "hover with a params block exited $?"
"$hpa" run "$hover" --set 'vehicles=[{cable_length_m: 0.45}]' --set 'payload={mass_kg: 0.12}' \
  --out "$out/list" --quiet || fail "hover with a 0.45 m one-vehicle list exited $?"
same_run "$out/params" "$out/list" "a one-vehicle list against the params block" --rows 1000
"$python" - "$out/hover/metrics.json" "$out/list/metrics.json" << 'PY' || fail "0.45 m differs"
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:])
assert a["payload_rmse_m"] != b["payload_rmse_m"], "a shorter cable flew the same run"
assert "team" not in b, "a one-vehicle list wrote team metrics"
PY

# what only a team has, refused naming the key
expect_exit 2 "vehicles.0.attach_m.*point mass" run "$hover" \
  --set 'vehicles=[{attach_m: [0.1, 0, 0]}]' --out "$out/bad"
expect_exit 2 "vehicles.0.start_slack_m.*taut" run "$hover" \
  --set 'vehicles=[{start_slack_m: 0.1}]' --out "$out/bad"
expect_exit 2 "payload.inertia_kgm2.*rigid payload" run "$hover" --set 'vehicles=[{}]' \
  --set 'payload={inertia_kgm2: [0.01, 0.01, 0.01]}' --out "$out/bad"
expect_exit 2 "payload.on_ground" run "$hover" --set 'vehicles=[{}]' \
  --set 'payload={on_ground: true}' --out "$out/bad"
expect_exit 2 "vehicles.0.cable_length_m.*params.cable.length_m" run "$hover" \
  --set 'vehicles=[{cable_length_m: 0.4}]' --set 'params={cable: {length_m: 0.45}}' \
  --out "$out/bad"
expect_exit 2 "controller.type.*cooperative" run "$hover" --set 'vehicles=[{}]' \
  --set controller.type=cooperative --out "$out/bad"
# a team's leftovers: a quadrotor push that names no vehicle, a vehicle named on a payload push,
# a team vehicle without its attachment point
expect_exit 2 "events.0.vehicle.*names its vehicle \(0 to 1\)" run "$team" \
  --set 'events.0={at: 3.0, type: impulse, body: quadrotor, impulse: [0, 0, -1.0]}' \
  --out "$out/bad"
expect_exit 2 "events.0.vehicle.*acts on the payload" run "$line" --set events.0.vehicle=0 \
  --out "$out/bad"
expect_exit 2 "vehicles.1.attach_m.*where its cable holds the payload" run "$team" \
  --set 'vehicles.1={cable_length_m: 0.5}' --out "$out/bad"
expect_exit 2 "vehicles.3" run "$team" --set vehicles.3.cable_length_m=0.4 --out "$out/bad"
# a bound on what the kind of run does not measure
expect_exit 2 "expect.team_tilt_max.*flies one vehicle" run "$hover" --set expect.team_tilt_max=10 \
  --out "$out/bad"
expect_exit 2 "expect.payload_in_fov_min.*a team run does not measure" run "$team" \
  --set expect.payload_in_fov_min=0.9 --out "$out/bad"
expect_exit 2 "expect.quad_rmse_max.*a team run does not measure" run "$team" \
  --set 'expect.quad_rmse_max=[0.1, 0.1, 0.1]' --out "$out/bad"

[ "$failures" -eq 0 ] || exit 1
echo "one-vehicle lists: the single vehicle's runs bit for bit; team-only keys refused"
