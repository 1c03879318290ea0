#!/usr/bin/env bash
# Faults reach a separate flight stack as they reach the in-process one (docs/faults.md): a VIO
# and an IMU-path fault (analytic camera), a garbage payload camera and a distractor in the
# rendered scene (rendered frames: the noise and the twin in the pixels the stack reads) flown in
# process and through hpa-flight give the same metrics, recovery metrics included, timings and
# the stack's name aside.
# Usage: fault_flight_stack_test.sh HPA_BINARY SOURCE_DIR PYTHON
set -uo pipefail
source "$2/harness/tests/cli_test_lib.sh"
cli_test_start "$@"  # hpa, src, python; out: a folder removed at exit

for name in fault_vio_wrong fault_imu_bias fault_payload_camera_garbage \
    fault_payload_camera_distractor; do
  "$hpa" run "$src/scenarios/ci/$name.yaml" --quiet --out "$out/$name/in" \
    || fail "$name in process failed"
  "$hpa" run "$src/scenarios/ci/$name.yaml" --quiet --out "$out/$name/ex" \
    --flight-stack hpa-flight || fail "$name through hpa-flight failed"
  same_run "$out/$name/in" "$out/$name/ex" "$name" --stack-b hpa-flight --nonempty faults \
    --skip camera_region_fraction
  # the resets by cause in each fault's span are counted from both stacks' per-step reports
  "$python" -c 'import json, sys
f = json.load(open(sys.argv[1]))["faults"]
assert all(isinstance(e["health_resets"], dict) for e in f), [e["health_resets"] for e in f]' \
    "$out/$name/ex/metrics.json" || fail "$name: no per-fault health_resets through hpa-flight"
done
echo "fault_flight_stack_test: $failures failure(s)"
[ "$failures" -eq 0 ]
