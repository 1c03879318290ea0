#!/usr/bin/env bash
# A run that never flew (a flight stack that does not start, exits before its hello, or a team's
# that does not start) fails its verdict with its cause everywhere it appears: metrics.json,
# a sweep's runs.jsonl and summary, hpa compare's table, and sweep-diff, which leaves its pairs
# out of every rate as run errors (never as crashes).
# usage: never_flew_test.sh HPA_BIN SOURCE_DIR PYTHON
source "$(dirname "$0")/cli_test_lib.sh"
cli_test_start "$@"

# check_never_flew DIR LABEL: DIR/metrics.json has expect.passed false, its first cause
# "never flew: " with the run error, and the run error set
check_never_flew() {
  "$python" - "$1/metrics.json" "$2" <<'PY' || fail "$2: metrics.json's verdict"
import json, sys
m = json.load(open(sys.argv[1]))
assert m["run_error"], "no run error"
assert m["expect"]["passed"] is False, m["expect"]
assert m["expect"]["failed"][0] == "never flew: " + m["run_error"], m["expect"]["failed"]
PY
}

# 1. hpa run, single vehicle and team: exit 3 (a run error), metrics.json written and failed
hover=$src/scenarios/hover.yaml
team=$src/scenarios/ci/team2_line.yaml
expect_exit 3 "exited with status 1 before connecting" run "$hover" --quiet --out "$out/false" \
  --flight-stack false
check_never_flew "$out/false" "a stack that does not start"
expect_exit 3 "exited with status 0 before connecting" run "$hover" --quiet --out "$out/exit0" \
  --flight-stack "sh -c 'exit 0'"
check_never_flew "$out/exit0" "a stack that exits before its hello"
expect_exit 3 "vehicle 0.*before connecting" run "$team" --quiet --out "$out/team" \
  --flight-stack false
check_never_flew "$out/team" "a team's stack that does not start"

# 2. a sweep of two seeds, each run never flown: its records and its summary say failed
cat > "$out/tiny.yaml" <<YAML
base: $hover
runs: 2
seed: 3
vary:
  estimation.camera: {list: [analytic]}
YAML
"$hpa" sweep "$out/tiny.yaml" --out "$out/sweep" --flight-stack false > /dev/null 2>&1 ||
  fail "the sweep of a stack that does not start exited $?"
"$hpa" sweep "$out/tiny.yaml" --out "$out/sweep_ok" > /dev/null 2>&1 ||
  fail "the same sweep in process exited $?"
"$python" - "$out/sweep" <<'PY' || fail "the sweep's records and summary"
import json, sys
d = sys.argv[1]
records = [json.loads(line) for line in open(d + "/runs.jsonl")]
assert len(records) == 2, len(records)
for r in records:
    assert r["status"] == "error", r["status"]
    assert r["metrics"]["expect"]["passed"] is False, r["metrics"]["expect"]
    assert r["metrics"]["expect"]["failed"][0].startswith("never flew: flight stack 'false'"), \
        r["metrics"]["expect"]["failed"]
group = json.load(open(d + "/summary.json"))["controllers"]["external"]
assert group["errors"] == 2 and group["runs"] == 0, group
md = open(d + "/summary.md").read()
assert md.count("ERROR never flew: flight stack 'false'") == 2, md
PY

# 3. hpa compare: the stack's column fails, with its cause above the table (exit 3: a run error)
expect_exit 3 "run error|internal error" compare "$hover" --quiet --controllers hpa_mpc \
  --flight-stack bad=false --out "$out/compare"
grep -q "^- bad: expect failed, never flew: flight stack 'false'" "$out/compare/comparison.md" ||
  fail "compare's table does not name the cause: $(cat "$out/compare/comparison.md")"
grep -Eq '^\| expect passed \| 1 \| 0 \| -1 \|$' "$out/compare/comparison.md" ||
  fail "compare's table does not fail the stack: $(grep expect "$out/compare/comparison.md")"
"$python" - "$out/compare/bad" "$out/compare/hpa_mpc" <<'PY' || fail "compare's metrics.json"
import json, sys
bad, ok = (json.load(open(d + "/metrics.json")) for d in sys.argv[1:])
assert bad["expect"]["passed"] is False and bad["expect"]["failed"][0].startswith("never flew")
assert ok["expect"]["passed"] is True, ok["expect"]
PY

# 4. sweep-diff: the never-flown runs are run errors, left out of every rate, not crashes
"$hpa" sweep-diff "$out/sweep_ok" "$out/sweep" --out "$out/diff" > /dev/null 2>&1 ||
  fail "sweep-diff exited $?"
"$python" - "$out/diff/diff.json" <<'PY' || fail "sweep-diff's counts of run errors"
import json, sys
d = json.load(open(sys.argv[1]))
assert d["runs_paired"] == 2, d["runs_paired"]
for name, m in d["metrics"].items():
    dropped = m["pairs_dropped"]
    assert m["pairs"] == 0, (name, m["pairs"])
    assert dropped["run_error"] == 2 and dropped["crashed"] == 0, (name, dropped)
assert d["metrics"]["expect_failure_rate"]["verdict"] == "inconclusive", d["metrics"]
PY
grep -q "run error / crash / one run / none" "$out/diff/diff.md" || fail "diff.md's header"

[ "$failures" -eq 0 ] || { echo "$failures check(s) failed"; exit 1; }
echo "never flew: all checks passed"
