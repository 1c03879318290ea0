#!/usr/bin/env bash
# A sweep never flies the same thing twice under two labels: flown by a separate flight stack,
# a vary key only the in-process flight code reads (controller.type, a controller setting, the
# estimator) that takes several values is refused before any run (exit 2, naming the key, no
# output folder); one value is no duplicate and flies; hpa-flight, which builds the hello's
# controller, flies each value as its own controller, and its --controller makes it refuse too.
# Stacks compared on the same draws are the sweep's factor: --flight-stack NAME=CMD, twice or
# more, labels each run by its stack (values.flight_stack), pairs them in sweep-diff, and is part
# of the sweep's identity; the factor as a file's vary key and malformed names are refused.
# usage: sweep_stack_keys_test.sh HPA_BIN SOURCE_DIR PYTHON
source "$(dirname "$0")/cli_test_lib.sh"
cli_test_start "$@"
stack="$python $src/examples/python/hover_controller.py"

# sweep FILE VARY_LINE...: a sweep of two draws of hover.yaml with the given vary entries
sweep() {
  local file=$1; shift
  { printf 'base: %s\nruns: 2\nseed: 4\nvary:\n' "$src/scenarios/hover.yaml"
    for line in "$@"; do printf '  %s\n' "$line"; done; } > "$file"
}

# 1. the issue's case: a controller grid flown by the Python example stack
sweep "$out/grid.yaml" "controller.type: {grid: [hpa_mpc, nonhybrid_mpc]}"
expect_exit 2 "vary.controller.type.*ignores controller.type" sweep "$out/grid.yaml" \
  --out "$out/grid" --flight-stack "$stack" --set duration=1
[ -e "$out/grid" ] && fail "the refused sweep made its output folder"
# the same from the sweep file's flight_stack:, a controller setting drawn, the estimator listed
{ cat "$out/grid.yaml"; echo "flight_stack: $stack"; } > "$out/file_stack.yaml"
expect_exit 2 "vary.controller.type" sweep "$out/file_stack.yaml" --out "$out/file_stack"
sweep "$out/weight.yaml" "controller.type: {list: [hpa_mpc]}" \
  "controller.perception_weight: {uniform: [0.5, 2.0]}"
expect_exit 2 "vary.controller.perception_weight" sweep "$out/weight.yaml" --out "$out/weight" \
  --flight-stack "$stack"
sweep "$out/estimator.yaml" "estimation.estimator: {list: [hybrid, always_taut]}"
expect_exit 2 "vary.estimation.estimator" sweep "$out/estimator.yaml" --out "$out/estimator" \
  --flight-stack "$stack"
# hpa-flight told to fly its own controller ignores the hello's as well
expect_exit 2 "vary.controller.type" sweep "$out/grid.yaml" --out "$out/own" \
  --flight-stack "hpa-flight --controller hpa_mpc"

# 2. one value is no duplicate: the README's hover_wind sweep lists controller.type once
sweep "$out/one.yaml" "controller.type: {grid: [hpa_mpc, hpa_mpc]}" \
  "events.0.force.0: {uniform: [0.1, 0.3]}"
"$hpa" sweep "$out/one.yaml" --out "$out/one" --runs 1 --set duration=1 --set 'events.0.at=0.5' \
  --flight-stack "$stack" > "$out/one.log" 2>&1 || fail "one listed controller: $(tail -3 "$out/one.log")"

# 3. hpa-flight flies the hello's controller: each grid value is its own controller
"$hpa" sweep "$out/grid.yaml" --out "$out/hpa_flight" --runs 1 --set duration=1 --set 'events=[]' \
  --jobs 2 --flight-stack hpa-flight > "$out/hpa_flight.log" 2>&1 \
  || fail "a controller grid through hpa-flight: $(tail -3 "$out/hpa_flight.log")"
"$python" - "$out/hpa_flight/runs.jsonl" <<'PY' || fail "hpa-flight's controller grid"
import json, sys
records = [json.loads(line) for line in open(sys.argv[1])]
assert sorted(r["controller"] for r in records) == ["hpa_mpc", "nonhybrid_mpc"], records
assert all(r["values"]["controller.type"] == r["controller"] for r in records)
PY

# 4. the stacks as the sweep's factor: --flight-stack NAME=CMD twice, each draw flown by each
sweep "$out/gust.yaml" "events.0.force.0: {uniform: [0.1, 0.3]}"
"$hpa" sweep "$out/gust.yaml" --out "$out/F" --set duration=1 --set events.0.at=0.3 --jobs 2 \
  --flight-stack py="$stack" --flight-stack mpc=hpa-flight > "$out/f.log" 2>&1 \
  || fail "the stacks factor: $(tail -3 "$out/f.log")"
"$python" - "$out/F" "$stack" <<'PY' || fail "the stacks factor's records"
import json, sys
d, stack = sys.argv[1], sys.argv[2]
records = [json.loads(line) for line in open(d + "/runs.jsonl")]
assert len(records) == 4 and all(r["status"] == "ok" for r in records), records
by = {(r["draw"], r["values"]["flight_stack"]): r for r in records}
for draw in (0, 1):
    py, mpc = by[(draw, "py")], by[(draw, "mpc")]
    assert py["seed"] == mpc["seed"] and py["flight_stack"] == stack, py
    assert mpc["flight_stack"] == "hpa-flight" and mpc["controller"] == "geometric", mpc
    assert py["controller"] not in ("geometric", "external"), py["controller"]
inputs = json.load(open(d + "/inputs.json"))
assert inputs["flight_stacks"] == [["py", stack], ["mpc", "hpa-flight"]], inputs
summary = open(d + "/summary.md").read()
assert "flight_stack=py" in summary and "flight_stack=mpc" in summary, summary[:800]
assert "--flight-stack 'hpa-flight'" in summary and "--set flight_stack" not in summary
PY
expect_exit 0 "2 paired runs; flight_stack: py \(A\) vs mpc \(B\)" sweep-diff "$out/F" "$out/F" \
  --out "$out/FD" --a-where flight_stack=py --b-where flight_stack=mpc
expect_exit 0 "0 to run \(4 already done\)" sweep "$out/gust.yaml" --out "$out/F" --resume \
  --set duration=1 --set events.0.at=0.3 --flight-stack py="$stack" --flight-stack mpc=hpa-flight
expect_exit 2 "holds runs flown by the flight stack 'hpa-flight'" sweep "$out/gust.yaml" \
  --out "$out/F" --resume --allow-changed-inputs --set duration=1 --set events.0.at=0.3 \
  --flight-stack py="$stack" --flight-stack mpc="hpa-flight --per-tick"
# refused: a controller grid with a stack that ignores it, the factor as a file's vary key, names
expect_exit 2 "vary.controller.type" sweep "$out/grid.yaml" --out "$out/bad" \
  --flight-stack py="$stack" --flight-stack mpc=hpa-flight
sweep "$out/file_factor.yaml" "flight_stack: {grid: [a, b]}"
expect_exit 2 "vary.flight_stack.*--flight-stack NAME=CMD" sweep "$out/file_factor.yaml" \
  --out "$out/bad"
expect_exit 2 "given 2 times, so each is NAME=CMD" sweep "$out/gust.yaml" --out "$out/bad" \
  --flight-stack py="$stack" --flight-stack hpa-flight
expect_exit 2 "NAME 'py' is given twice" sweep "$out/gust.yaml" --out "$out/bad" \
  --flight-stack py="$stack" --flight-stack py=hpa-flight
expect_exit 2 "not a safe name" sweep "$out/gust.yaml" --out "$out/bad" \
  --flight-stack ../py="$stack" --flight-stack mpc=hpa-flight
[ -e "$out/bad" ] && fail "a refused sweep made its output folder"

[ "$failures" -eq 0 ] && echo "sweep_stack_keys: all checks passed"
exit $((failures > 0))
