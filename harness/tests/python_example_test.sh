#!/usr/bin/env bash
# The README's Python example, as written there: the `$B/hpa run examples/python/...` command
# (its continuation line joined, its comment dropped) run from the source folder with $B the
# build's bin folder, python3 the one with numpy and --out a fresh folder. Checks: it exits 0
# (every expect bound of the example's own scenario holds), metrics.json names the example's
# scenario and the Python stack, records no run error, and the estimate's mode was flown (a mode
# accuracy and no missed slack event). The README names the scenario file it runs, and that file
# states the seeds its bounds come from.
# usage: python_example_test.sh HPA_BIN SOURCE_DIR PYTHON
set -uo pipefail
# shellcheck source=cli_test_lib.sh
source "$(dirname "$0")/cli_test_lib.sh"
cli_test_start "$@"

line=$(sed -n '/^\$B\/hpa run examples\/python\//,/hover_controller.py"/p' "$src/README.md" |
       sed -e 's/\\$//' -e 's/#.*$//' | tr '\n' ' ')
[ -n "$line" ] || { echo "FAIL: README.md has no \$B/hpa run examples/python/... command"; exit 1; }
scenario=$(grep -o 'examples/python/[a-z_]*\.yaml' <<< "$line")
[ -f "$src/$scenario" ] || fail "the README's example scenario $scenario is not in the tree"
grep -q 'scenario_bounds.py .* --seeds 1-30' "$src/$scenario" ||
  fail "$scenario does not state the seeds its bounds come from"
script=$out/example.sh
{
  echo "set -euo pipefail"
  echo "B=$(dirname "$hpa")"
  sed -e "s|\"python3 |\"$python |" <<< "$line --out $out/run --quiet"
} > "$script"
(cd "$src" && bash "$script") > "$out/run.log" 2>&1
status=$?
[ "$status" -eq 0 ] || fail "the README's Python example exited $status: $(tail -5 "$out/run.log")"

"$python" - "$out/run/metrics.json" <<'PY' || fail "the Python example's metrics"
import json, sys
m = json.load(open(sys.argv[1]))
assert m["scenario"] == "hover_gripper_pull_example", m["scenario"]
assert m["controller"] == "python hover_controller", m["controller"]
assert m["run_error"] is None, m["run_error"]
assert m["expect"]["passed"], m["expect"]["failed"]
# the estimate's mode: slack detected from the tension cue, none missed
assert m["slack_events"] >= 1 and m["slack_detection_latency_s"]["missed"] == 0, m["slack_detection_latency_s"]
assert m["mode_accuracy"] > 0.9, m["mode_accuracy"]
print("README's Python example: %s passes (payload RMSE %s m, mode accuracy %.3f)" % (
    m["scenario"], [round(x, 4) for x in m["payload_rmse_m"]], m["mode_accuracy"]))
PY
[ "$failures" -eq 0 ] || { echo "$failures failure(s)"; exit 1; }
echo "the README's Python example passes its scenario"
