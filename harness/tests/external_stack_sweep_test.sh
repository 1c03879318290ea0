#!/usr/bin/env bash
# An external flight stack is a first-class controller: the Python example stack
# (examples/python/hover_controller.py) against hpa_mpc through `hpa compare`, through sweeps of
# a short hover (A in process; B flown by the stack from the sweep file's flight_stack:, two
# workers, keeping the worst run's log; C the same from --flight-stack, as two shards of the
# Slurm array's script, merged; H through hpa-flight, equal to A) and through `hpa sweep-diff`.
# Checks that every run is labelled by what flew (metrics.json's controller, the records, the
# summary, the comparison table and plot), that parallel workers' stacks do not collide, that
# the stack is part of the sweep's identity (a resume or merge with another stack is refused),
# that a failing stack is its run's error and not the sweep's, and that the diff pairs the runs
# and gives verdicts.
# Usage: external_stack_sweep_test.sh HPA_BINARY SOURCE_DIR PYTHON
set -uo pipefail
source "$2/harness/tests/cli_test_lib.sh"
cli_test_start "$@"  # hpa, src, python; out: a folder removed at exit
export PYTHONPATH="$src/python${PYTHONPATH:+:$PYTHONPATH}" PYTHONDONTWRITEBYTECODE=1
stack="$python $src/examples/python/hover_controller.py"
start_s=$(date +%s.%N)
elapsed() { "$python" -c "import sys, time; print('%.1f s' % (time.time() - float(sys.argv[1])))" "$start_s"; }

# a short hover on the analytic camera with a side wind: both controllers fly it to its end
cat > "$out/ext_hover.yaml" <<'YAML'
name: ext_hover
duration: 3.0
seed: 1
controller: {type: hpa_mpc}
estimation: {camera: analytic}
reference: {type: hover, payload_position: [0, 0, 0.7]}
events:
  - {at: 1.0, type: wind, force: [0.2, 0.1, 0], duration: 1.0}
YAML

# 1. compare: a registered controller and a named stack, each in its own folder, column and
# legend entry; the stack's run is labelled by the name it gave in its hello
"$hpa" compare "$out/ext_hover.yaml" --out "$out/cmp" --controllers hpa_mpc \
  --flight-stack py="$stack" > "$out/cmp.log" 2>&1 || fail "compare failed: $(tail -5 "$out/cmp.log")"
"$python" - "$out/cmp" <<'PY' || fail "compare's labels"
import csv, json, sys
d = sys.argv[1]
a = json.load(open(d + "/hpa_mpc/metrics.json"))
b = json.load(open(d + "/py/metrics.json"))
assert a["controller"] == "hpa_mpc" and a["flight_stack"] == "in_process", (a["controller"], a["flight_stack"])
assert b["run_error"] is None, b["run_error"]
# a stack that names no controller is labelled by its own name, never by the scenario's type
assert b["controller"] == b["flight_stack"] and b["controller"] not in ("hpa_mpc", "external"), b["controller"]
md = open(d + "/comparison.md").read()
header = next(l for l in md.splitlines() if l.startswith("| metric"))
assert [c.strip() for c in header.split("|")[2:-1]] == ["hpa_mpc", "py", "py - hpa_mpc"], header
assert "- py: the flight stack `" in md and b["controller"] in md, md[:400]
legend = {row["series"] for row in csv.DictReader(open(d + "/comparison.csv"))}
assert "hpa_mpc" in legend and "py" in legend, legend
print("compare: hpa_mpc and py (%s), deviation %.3f vs %.3f m"
      % (b["controller"], a["quad_position_deviation_max_m"], b["quad_position_deviation_max_m"]))
PY
grep -q "ext_hover \[$("$python" -c "import json,sys; print(json.load(open(sys.argv[1]))['controller'])" "$out/cmp/py/metrics.json")," "$out/cmp.log" \
  || fail "the console summary does not show the stack's name: $(grep ext_hover "$out/cmp.log")"
expect_exit 2 "NAME=CMD" compare "$out/ext_hover.yaml" --out "$out/cmp_bad" --flight-stack "$stack"
expect_exit 2 "registered controller" compare "$out/ext_hover.yaml" --out "$out/cmp_bad" \
  --flight-stack hpa_mpc="$stack"
expect_exit 2 "safe folder name" compare "$out/ext_hover.yaml" --out "$out/cmp_bad" \
  --flight-stack ../x="$stack"
echo "compare done at $(elapsed)"

# 2. two sweeps of the same draws: A in process, B flown by the stack (the sweep file's key)
cat > "$out/a.yaml" <<YAML
base: $out/ext_hover.yaml
runs: 8
seed: 5
time_limit: 120
vary:
  events.0.force.0: {uniform: [0.1, 0.3]}
YAML
{ cat "$out/a.yaml"; echo "flight_stack: $stack"; } > "$out/b.yaml"
"$hpa" sweep "$out/a.yaml" --out "$out/A" --jobs 2 > "$out/a.log" 2>&1 \
  || fail "sweep A failed: $(tail -3 "$out/a.log")"
"$hpa" sweep "$out/b.yaml" --out "$out/B" --jobs 2 --keep-logs worst:1 > "$out/b.log" 2>&1 \
  || fail "sweep B failed: $(tail -3 "$out/b.log")"
grep -q "WARNING" "$out/b.log" && fail "the kept log's replay differs: $(grep WARNING "$out/b.log")"
echo "sweeps done at $(elapsed)"
"$python" - "$out" "$stack" <<'PY' || fail "sweep records"
import json, sys
d, stack = sys.argv[1], sys.argv[2]
load = lambda p: [json.loads(l) for l in open(p) if l.strip()]
a, b = load(d + "/A/runs.jsonl"), load(d + "/B/runs.jsonl")
assert len(a) == 8 and len(b) == 8, (len(a), len(b))
# every stack run finished: two workers' stacks never met on a socket or a ring
assert all(r["status"] == "ok" for r in a + b), [r["error"] for r in a + b if r["status"] != "ok"]
assert {r["controller"] for r in a} == {"hpa_mpc"}, {r["controller"] for r in a}
names = {r["metrics"]["flight_stack"] for r in b}
assert len(names) == 1 and {r["controller"] for r in b} == names, ({r["controller"] for r in b}, names)
assert all(r["flight_stack"] == stack for r in b) and all("flight_stack" not in r for r in a)
# same draws and seeds on either side; the stack is part of the sweep's identity
assert sorted((r["run"], r["seed"], r["values"]["events.0.force.0"]) for r in a) == \
       sorted((r["run"], r["seed"], r["values"]["events.0.force.0"]) for r in b)
assert a[0]["sweep_id"] != b[0]["sweep_id"]
inputs = json.load(open(d + "/B/inputs.json"))
assert inputs["flight_stack"] == stack, inputs.get("flight_stack")
summary = open(d + "/B/summary.md").read()
name = names.pop()
assert "| " + name + " | 8 |" in summary, summary[:600]
assert "--flight-stack '" + stack + "'" in summary, "no replay command with the stack"
# the worst run's log, replayed by the stack that flew it
kept = [json.load(open(p)) for p in __import__("glob").glob(d + "/B/logs/run_*/metrics.json")]
assert len(kept) == 1 and kept[0]["controller"] == name, kept
print("sweeps: A %s, B %s, 8 runs each" % ({r["controller"] for r in a}, {r["controller"] for r in b}))
PY
# the stack is part of the sweep's identity: a resume with another stack is refused, one with
# the same has nothing left to do
expect_exit 2 "runs flown by the flight stack" sweep "$out/b.yaml" --out "$out/B" --resume \
  --flight-stack "$python $src/examples/python/hover_controller.py --other"
expect_exit 2 "runs flown by the flight stack" sweep "$out/a.yaml" --out "$out/B" --resume \
  --allow-changed-inputs
"$hpa" sweep "$out/b.yaml" --out "$out/B" --resume > "$out/resume.log" 2>&1 \
  || fail "resume with the same stack: $(tail -3 "$out/resume.log")"
grep -q "0 to run (8 already done)" "$out/resume.log" || fail "resume: $(head -2 "$out/resume.log")"
# the command line's stack flies the same runs as the file's key: sweep A's file with
# --flight-stack, as two shards through the Slurm array's script (HPA_FLIGHT_STACK; its tasks run
# here without Slurm), merged (the merge finds every run: it loads the sweep with the stack its
# records name), equals B run for run
for k in 1 2; do
  SLURM_ARRAY_TASK_ID=$k SLURM_ARRAY_TASK_COUNT=2 SLURM_CPUS_PER_TASK=2 HPA_BIN="$hpa" \
    HPA_SWEEP="$out/a.yaml" HPA_OUT="$out/C" HPA_FLIGHT_STACK="$stack" \
    bash "$src/scenarios/slurm/sweep.sbatch" > "$out/c$k.log" 2>&1 \
    || fail "sweep.sbatch with HPA_FLIGHT_STACK, task $k: $(tail -3 "$out/c$k.log")"
done
"$hpa" merge "$out/C/shard1" "$out/C/shard2" --out "$out/C" > "$out/mergec.log" 2>&1 \
  || fail "merge of --flight-stack shards: exit $?: $(tail -3 "$out/mergec.log")"
"$python" - "$out/B/runs.jsonl" "$out/C/runs.jsonl" <<'PY' || fail "--flight-stack differs from flight_stack:"
import json, sys
timing = {"wall_time_s", "mpc_solve_ms", "render_ms", "image_model_ms", "detector_ms"}
strip = lambda m: {k: v for k, v in m.items() if k not in timing}
b, c = ({r["run"]: r for r in map(json.loads, open(p))} for p in sys.argv[1:3])
assert sorted(b) == sorted(c) == list(range(8)), (sorted(b), sorted(c))
assert all(strip(b[i]["metrics"]) == strip(c[i]["metrics"]) for i in b), "metrics differ"
PY
expect_exit 2 "mixes sweeps" merge "$out/A" "$out/C/shard1" --out "$out/AC"
# hpa-flight names the controller it flies: its sweep's runs are hpa_mpc's and equal A's exactly
# (every metric but the timings, what flew and the camera's region fraction)
"$hpa" sweep "$out/a.yaml" --out "$out/H" --jobs 2 --flight-stack hpa-flight > "$out/h.log" 2>&1 \
  || fail "sweep through hpa-flight: $(tail -3 "$out/h.log")"
"$python" - "$out/A/runs.jsonl" "$out/H/runs.jsonl" <<'PY' || fail "hpa-flight's sweep differs from A"
import json, sys
skip = {"wall_time_s", "mpc_solve_ms", "render_ms", "image_model_ms", "detector_ms",
        "camera_region_fraction", "flight_stack"}
a, h = ({r["run"]: r for r in map(json.loads, open(p))} for p in sys.argv[1:3])
assert sorted(a) == sorted(h) == list(range(8)), (sorted(a), sorted(h))
assert {r["controller"] for r in h.values()} == {"hpa_mpc"}, {r["controller"] for r in h.values()}
bad = [(i, k) for i in a for k in a[i]["metrics"]
       if k not in skip and a[i]["metrics"][k] != h[i]["metrics"].get(k)]
assert not bad, bad[:5]
PY

# 3. a stack that fails is its run's error, not the sweep's: every run recorded, summary written
cat > "$out/fail.yaml" <<YAML
base: $out/ext_hover.yaml
runs: 2
flight_stack: exit 1
YAML
"$hpa" sweep "$out/fail.yaml" --out "$out/F" --jobs 2 > "$out/fail.log" 2>&1 \
  || fail "a failing stack failed the sweep: $(tail -3 "$out/fail.log")"
"$python" - "$out/F/runs.jsonl" <<'PY' || fail "failing stack records"
import json, sys
runs = [json.loads(l) for l in open(sys.argv[1])]
assert len(runs) == 2 and all(r["status"] == "error" for r in runs), runs
assert all("exited with status 1 before connecting" in r["error"] for r in runs), runs[0]["error"]
assert all(r["controller"] == "external" for r in runs), [r["controller"] for r in runs]
PY
[ -f "$out/F/summary.md" ] || fail "no summary after the failing stack's sweep"
printf 'base: %s\nruns: 1\nflight_stack: "  "\n' "$out/ext_hover.yaml" > "$out/blank.yaml"
expect_exit 2 "blank.yaml: key 'flight_stack': expected a shell command" sweep "$out/blank.yaml" \
  --out "$out/blank"

# 4. sweep-diff pairs A's runs with B's and gives every metric a verdict
"$hpa" sweep-diff "$out/A" "$out/B" --out "$out/diff" > "$out/diff.log" 2>&1 \
  || fail "sweep-diff failed: $(tail -3 "$out/diff.log")"
"$python" - "$out/diff/diff.json" <<'PY' || fail "sweep-diff's pairs and verdicts"
import json, sys
d = json.load(open(sys.argv[1]))
assert d["runs_paired"] == 8, d["runs_paired"]
verdicts = {m: v["verdict"] for m, v in d["metrics"].items() if v["pairs"] > 0}
known = {"better", "worse", "no difference shown", "inconclusive", "not compared"}
assert verdicts and set(verdicts.values()) <= known, verdicts
# the example holds the vehicle from VIO and the IMU: on these 8 draws it deviates 1.4 to 2.2
# times as far as hpa_mpc in every pair (measured +0.015 to +0.034 m, the minimum effect 0.01 m),
# which 8 pairs can show (the signed-rank test's smallest p is 2 / 2^8 = 0.008)
dev = d["metrics"]["quad_position_deviation_max_m"]
assert dev["pairs"] == 8 and dev["verdict"] == "worse", dev
differs = " | ".join(d["differs"])
assert "controller (what flew): hpa_mpc (A)" in differs, differs
assert "flight stack: in process (A)" in differs, differs
print("sweep-diff: %d pairs; quad deviation %s (B - A = %+.3f m)"
      % (d["runs_paired"], dev["verdict"], dev["difference"]))
PY
echo "external_stack_sweep_test: $failures failure(s) in $(elapsed)"
[ "$failures" -eq 0 ]
