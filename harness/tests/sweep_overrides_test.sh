#!/usr/bin/env bash
# `hpa sweep FILE --runs N --set PATH=VALUE` changes a sweep without copying its file: N draws
# (times the grid), every run with the set keys (in its record's values, its replay command and
# inputs.json); the overrides are part of the sweep's identity (a resume without them is
# refused, with them it has nothing left to do; merge still knows the run count); a set on a
# varied key, a bad set value and a run count out of range are refused (exit 2).
# usage: sweep_overrides_test.sh HPA_BIN SOURCE_DIR PYTHON
source "$(dirname "$0")/cli_test_lib.sh"
cli_test_start "$@"

# five draws of a hover's wind gust, two controllers: 10 runs as written
cat > "$out/wind.yaml" <<YAML
base: $src/scenarios/hover.yaml
runs: 5
seed: 9
vary:
  events.0.force.0: {uniform: [0.1, 0.3]}
  controller.type: {grid: [geometric, hpa_mpc]}
YAML
cp "$out/wind.yaml" "$out/wind.before"
sets=(--set duration=1 --set events.0.at=0.2)
"$hpa" sweep "$out/wind.yaml" --out "$out/S" --runs 2 "${sets[@]}" --jobs 2 > "$out/s.log" 2>&1 \
  || fail "the sweep with --runs and --set: $(tail -3 "$out/s.log")"
grep -q "4 runs in all" "$out/s.log" || fail "--runs 2 of a 2-cell grid: $(head -1 "$out/s.log")"
cmp -s "$out/wind.yaml" "$out/wind.before" || fail "the sweep file was changed"
"$python" - "$out/S" <<'PY' || fail "the records and inputs.json of the overridden sweep"
import json, sys
d = sys.argv[1]
records = [json.loads(line) for line in open(d + "/runs.jsonl")]
assert len(records) == 4 and all(r["status"] == "ok" for r in records), records
for r in records:
    assert r["values"]["duration"] == 1 and r["values"]["events.0.at"] == 0.2, r["values"]
    assert r["metrics"]["sim_time_s"] == 1.0, r["metrics"]["sim_time_s"]
    assert 0.1 <= r["values"]["events.0.force.0"] <= 0.3
inputs = json.load(open(d + "/inputs.json"))
assert inputs["runs"] == 2 and inputs["sets"] == [["duration", "1"], ["events.0.at", "0.2"]], inputs
summary = open(d + "/summary.md").read()
assert "--set duration=1" in summary and "--set events.0.at=0.2`" in summary, \
    "no replay command with the sets"
# the main binned quantity stays the drawn force, not a set key
assert "events.0.force.0" in summary and "| duration" not in summary
PY

# the overrides are the sweep's identity: a resume needs the same ones
expect_exit 2 "holds runs of a different sweep.*--set" sweep "$out/wind.yaml" --out "$out/S" \
  --resume
expect_exit 2 "holds runs of a different sweep" sweep "$out/wind.yaml" --out "$out/S" --resume \
  --runs 3 "${sets[@]}"
expect_exit 0 "0 to run \(4 already done\)" sweep "$out/wind.yaml" --out "$out/S" --resume \
  --runs 2 "${sets[@]}"
# merge reads the overrides from inputs.json: the run count is known, nothing is missing
"$hpa" merge "$out/S" --out "$out/M" > "$out/m.log" 2>&1 || fail "merge: $(tail -3 "$out/m.log")"
grep -q "missing runs not checked" "$out/m.log" && fail "merge lost the run count: $(cat "$out/m.log")"

# refused before any run
expect_exit 2 "--set events.0.force.0.*varies events.0.force.0" sweep "$out/wind.yaml" \
  --out "$out/bad1" --set events.0.force.0=0.2
expect_exit 2 "--set events.*varies events.0.force.0" sweep "$out/wind.yaml" --out "$out/bad2" \
  --set 'events=[]'
expect_exit 2 "--set.*duration" sweep "$out/wind.yaml" --out "$out/bad3" --set duration=-1
expect_exit 2 "--set.*PATH=VALUE" sweep "$out/wind.yaml" --out "$out/bad4" --set duration
expect_exit 2 "--runs" sweep "$out/wind.yaml" --out "$out/bad5" --runs 0
expect_exit 2 "--runs" sweep "$out/wind.yaml" --out "$out/bad6" --runs 1000001
for d in bad1 bad2 bad3 bad4 bad5 bad6; do
  [ -e "$out/$d" ] && fail "a refused sweep made its output folder $d"
done
"$hpa" sweep --help | grep -q -- "--runs" || fail "hpa sweep --help lacks --runs"
"$hpa" --help | grep -q -- "--set PATH=VALUE\]\.\.\." || fail "hpa --help lacks sweep's --set"

[ "$failures" -eq 0 ] && echo "sweep_overrides: all checks passed"
exit $((failures > 0))
