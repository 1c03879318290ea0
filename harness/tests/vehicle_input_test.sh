#!/usr/bin/env bash
# Bad input around vehicles is refused before anything flies (exit 2), the message naming the key
# path: a vehicle index out of range or not a whole number in an event, a fault or a --set path;
# a team's key on a single-vehicle scenario; and a single vehicle's key on a team (its gripper,
# wind, camera, estimator, realism profile and the params a team gives per vehicle), which a team
# run would otherwise fly without it changing anything. Vehicle 0 on a single-vehicle scenario is
# the documented default and is flown.
# usage: vehicle_input_test.sh HPA_BIN SOURCE_DIR
set -u
. "$(dirname "$0")/cli_test_lib.sh"
cli_test_start "$1" "$2"

team=$src/scenarios/ci/team2_cable_slack.yaml  # events.0: a push on vehicle 1
hover=$src/scenarios/hover.yaml          # events.0: wind
gripper=$src/scenarios/hover_gripper_pull.yaml
bad=$out/bad
fault='{at: 1.0, type: fault, component: motor, mode: off, motor: 0'
vio_fault='{at: 1.0, type: fault, component: vio, mode: off, duration: 0.5'
push='{at: 1.0, type: impulse, body: quadrotor, impulse: [0, 0, 0.1]'

# 1. a vehicle index out of range or not a whole number: in an event, in a fault, in a --set path
for v in -1 2 5 1.5 one; do
  case $v in
    2 | 5) why="vehicle $v is not in the scenario \(2 vehicles, counted from 0\)" ;;
    *) why="expected a vehicle index, a whole number counted from 0, not $v" ;;
  esac
  expect_exit 2 "events.0.vehicle.*$why" run "$team" --set "events.0.vehicle=$v" --out "$bad"
  expect_exit 2 "events.0.vehicle.*$why" run "$team" --set "events.0=$fault, vehicle: $v}" \
    --out "$bad"
done
for v in -1 1 3 0.5; do
  expect_exit 2 "events.0.vehicle" run "$hover" --set "events.0=$push, vehicle: $v}" --out "$bad"
  expect_exit 2 "events.0.vehicle" run "$hover" --set "events.0=$vio_fault, vehicle: $v}" \
    --out "$bad"
done
expect_exit 2 "events.0.vehicle.*vehicle 1 is not in the scenario \(1 vehicle, counted from 0\)" \
  run "$hover" --set "events.0=$vio_fault, vehicle: 1}" --out "$bad"
for path in vehicles.2.cable_length_m vehicles.5.attach_m vehicles.-1.cable_length_m \
  vehicles.x.cable_length_m; do
  expect_exit 2 "error: --set: key '$path'" run "$team" --set "$path=0.4" --out "$bad"
done
# a vehicle's map takes no index: an unknown key of vehicle 1, named with the set
expect_exit 2 "error: --set vehicles.1.0.cable_length_m=0.4: key 'vehicles.1.0': unknown key" run "$team" \
  --set vehicles.1.0.cable_length_m=0.4 --out "$bad"
expect_exit 2 "key 'vehicles.5.attach_m': '5' is not an index of the list vehicles \(it has 2 \
entries, indices 0 to 1" run "$team" --set 'vehicles.5.attach_m=[0, 0, 0]' --out "$bad"
expect_exit 2 "key 'vehicles.-1.cable_length_m': '-1' is not an index of the list vehicles" \
  run "$team" --set vehicles.-1.cable_length_m=0.4 --out "$bad"
expect_exit 2 "key 'events.3.vehicle': '3' is not an index of the list events \(it has 1 entry" \
  run "$team" --set events.3.vehicle=0 --out "$bad"
expect_exit 2 "error: --set: key 'vehicles.0.cable_length_m': 'vehicles' is not in the base scenario" \
  run "$hover" --set vehicles.0.cable_length_m=0.4 --out "$bad"

# a sweep's drawn path is checked the same way before any run, naming the sweep file
printf 'base: %s\nruns: 2\nvary:\n  vehicles.5.cable_length_m: {uniform: [0.4, 0.6]}\n' "$team" \
  > "$out/sweep.yaml"
expect_exit 2 "sweep.yaml.*key 'vehicles.5.cable_length_m': '5' is not an index of the list" \
  sweep "$out/sweep.yaml" --out "$out/sweep"

# vehicle 0 on a single vehicle is the documented default: flown (a short run; exit 0 or 1)
for event in "$push, vehicle: 0}" "$vio_fault, vehicle: 0}"; do
  text=$(timeout 120 "$hpa" run "$hover" --set "events.0=$event" --set duration=1.2 \
    --set 'estimation={ground_truth: true, camera: analytic}' --set 'controller={type: geometric}' \
    --out "$out/zero" --quiet 2>&1)
  status=$?
  [ "$status" -le 1 ] || fail "vehicle 0 on a single vehicle ($event) exited $status: $text"
done

# 2a. a team's key on a single-vehicle scenario
expect_exit 2 "events.0.vehicle.*vehicle 2 is not in the scenario \(1 vehicle" run "$hover" \
  --set "events.0=$push, vehicle: 2}" --out "$bad"
expect_exit 2 "controller.type.*cooperative" run "$hover" --set controller.type=cooperative \
  --out "$bad"
expect_exit 2 "key '--controller': unknown controller 'cooperative'" run "$hover" \
  --controller cooperative --out "$bad"
expect_exit 2 "payload block belongs to a team scenario" run "$hover" --set 'payload={mass_kg: 0.2}' \
  --out "$bad"
expect_exit 2 "mocap" run "$hover" --set 'mocap={rate_hz: 100}' --out "$bad"
expect_exit 2 "expect.team_tilt_max.*flies one vehicle" run "$hover" --set expect.team_tilt_max=10 \
  --out "$bad"
expect_exit 2 "key '--team-stack': this scenario flies one vehicle" run "$hover" \
  --flight-stack hpa-flight --team-stack one --out "$bad"

# 2b. a single vehicle's key on a team: events, estimation, world, params, CLI options
expect_exit 2 "events.0.*only, not 'gripper_grab'" run "$team" \
  --set 'events.0={at: 1.0, type: gripper_grab}' --out "$bad"
expect_exit 2 "events.0.*only, not 'wind'" run "$team" \
  --set 'events.0={at: 1.0, type: wind, force: [1, 0, 0], duration: 1}' --out "$bad"
for key in "estimator: hybrid" "slack_tension_cue: false" "camera_randomize: true"; do
  name=${key%%:*}
  expect_exit 2 "key 'estimation.$name': a team's payload is seen by the motion-capture system" \
    run "$team" --set "estimation={$key}" --out "$bad"
done
expect_exit 2 "key '--camera': a team scenario flies on motion capture" run "$team" \
  --camera analytic --out "$bad"
expect_exit 2 "key '--camera': a team scenario flies on motion capture" compare "$team" \
  --camera render --out "$bad"
for key in "payload_mass: 0.3" "cable_length: 0.6" "contact: {enabled: true}" \
  "camera: {noise: true}"; do
  name=${key%%:*}
  expect_exit 2 "key 'world.$name': a team flies the profile's parts on every vehicle" \
    run "$team" --set "world={profile: ideal, $key}" --out "$bad"
done
# where a vehicle's own state comes from: a team's choice; a single vehicle's is on board
expect_exit 2 "key 'estimation.vehicle_state': a single vehicle flies on its onboard estimator" \
  run "$hover" --set estimation.vehicle_state=motion_capture --out "$bad"
expect_exit 2 "key 'estimation.vehicle_state': onboard and ground_truth: true contradict" \
  run "$team" --set 'estimation={vehicle_state: onboard, ground_truth: true}' --out "$bad"
# a vehicle's IMU, VIO and rate gyro fly only on board: their faults need it
expect_exit 2 "events.0.component.*estimates its own state on board.*'vio' fault" run "$team" \
  --set "events.0=$vio_fault, vehicle: 0}" --out "$bad"
expect_exit 2 "key 'params.cable.length_m': a team does not fly it: .*cable_length_m" run "$team" \
  --set 'params={cable: {length_m: 0.6}}' --out "$bad"
expect_exit 2 "key 'params.payload.mass_kg': a team does not fly it: .*payload.mass_kg" \
  run "$team" --set 'params={payload: {mass_kg: 0.3}}' --out "$bad"
expect_exit 2 "controller.*perception_weight" run "$team" --set controller.perception_weight=1 \
  --out "$bad"
expect_exit 2 "expect.payload_in_fov_min.*a team run does not measure" run "$team" \
  --set expect.payload_in_fov_min=0.5 --out "$bad"
expect_exit 2 "key '--team-stack': only with --flight-stack" run "$team" --team-stack one \
  --out "$bad"

# 3. a team has no gripper: neither its fault nor its events
expect_exit 2 "events.0.component.*no gripper and no payload camera: a 'gripper' fault" run "$team" \
  --set 'events.0={at: 1.0, type: fault, vehicle: 0, component: gripper, mode: early}' --out "$bad"
for type in gripper_release "gripper_move, to: [0, 0, 1], duration: 1"; do
  expect_exit 2 "events.0.*impulse, velocity_change and fault events only" run "$team" \
    --set "events.0={at: 1.0, type: $type}" --out "$bad"
done
# the single vehicle's gripper acts on no vehicle: a gripper event that names one is refused
expect_exit 2 "events.0.*vehicle" run "$gripper" --set events.0.vehicle=0 --out "$bad"

[ "$failures" -eq 0 ] || exit 1
echo "vehicle input: every case refused naming its key, vehicle 0 of one vehicle flown"
