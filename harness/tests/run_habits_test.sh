#!/usr/bin/env bash
# hpa run's habits as a daily tool: a run never silently replaces another scenario's results in
# its --out folder (refused, exit 2, unless --overwrite; a rerun of the same scenario replaces its
# own), and --set PATH+=VALUE appends an entry to a list (an event, checked as the file's events
# are), where an index past a list's end says how to append.
# usage: run_habits_test.sh HPA_BIN SOURCE_DIR PYTHON
source "$(dirname "$0")/cli_test_lib.sh"
cli_test_start "$@"

impulse_hover_base "$out/a.yaml" habits_a 1.5 0.5
impulse_hover_base "$out/b.yaml" habits_b 1.5 0.5

# 1. another scenario's results are refused, then replaced with --overwrite; a rerun replaces
"$hpa" run "$out/a.yaml" --quiet --out "$out/dir" || fail "the first run exited $?"
cp "$out/dir/metrics.json" "$out/a_metrics.json"
expect_exit 2 "$out/dir holds the results of scenario 'habits_a', and this run is scenario \
'habits_b': give another --out, or --overwrite" run "$out/b.yaml" --quiet --out "$out/dir"
cmp -s "$out/dir/metrics.json" "$out/a_metrics.json" || fail "the refused run changed metrics.json"
"$hpa" run "$out/a.yaml" --quiet --seed 2 --out "$out/dir" || fail "the rerun of habits_a exited $?"
"$hpa" run "$out/b.yaml" --quiet --out "$out/dir" --overwrite || fail "--overwrite exited $?"
grep -q '"scenario": *"habits_b"' "$out/dir/metrics.json" || fail "--overwrite kept habits_a's"
echo "not json" > "$out/foreign.json" && mkdir -p "$out/foreign" &&
  cp "$out/foreign.json" "$out/foreign/metrics.json"
expect_exit 2 "holds a metrics.json that is not a run's" run "$out/a.yaml" --quiet \
  --out "$out/foreign"

# 2. --set 'events+={...}' appends an event: a second push, recorded in run.json
"$hpa" run "$out/a.yaml" --quiet --out "$out/one_push" || fail "one push exited $?"
"$hpa" run "$out/a.yaml" --quiet --out "$out/two_pushes" \
  --set 'events+={at: 1.0, type: impulse, body: payload, impulse: [0, 0, 0.1]}' ||
  fail "events+= exited $?"
"$python" - "$out/one_push" "$out/two_pushes" <<'PY' || fail "the appended event"
import json, sys
one, two = (json.load(open(d + "/metrics.json")) for d in sys.argv[1:])
assert two["slack_events"] > one["slack_events"], (one["slack_events"], two["slack_events"])
sets = json.load(open(sys.argv[2] + "/run.json"))["sets"]
assert sets == [["events+", "{at: 1.0, type: impulse, body: payload, impulse: [0, 0, 0.1]}"]], sets
PY
# an appended event is checked as the file's, and named by its --set and its own index
expect_exit 2 "^hpa: error: --set events\+=\{at: 1.0, type: impulse, body: payload, impulse: \
\[0, 0\]\}: key 'events.1.impulse': expected a list of 3 numbers" run "$out/a.yaml" --quiet \
  --out "$out/x" --set 'events+={at: 1.0, type: impulse, body: payload, impulse: [0, 0]}'
expect_exit 2 "key 'events.1.at'.*after the end" run "$out/a.yaml" --quiet --out "$out/x" \
  --set 'events+={at: 9.0, type: impulse, body: payload, impulse: [0, 0, 0.1]}'
# an index past the end, or += on what is not a list, says how to append
expect_exit 2 "'5' is not an index of the list events.*append one with events\+=VALUE" \
  run "$out/a.yaml" --quiet --out "$out/x" --set 'events.5={at: 1.0}'
expect_exit 2 "'duration' is not a list.*PATH\+=VALUE appends to a list" run "$out/a.yaml" \
  --quiet --out "$out/x" --set 'duration+=1'

[ "$failures" -eq 0 ] || { echo "$failures check(s) failed"; exit 1; }
echo "run habits: all checks passed"
