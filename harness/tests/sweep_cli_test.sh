#!/usr/bin/env bash
# Sweep checks (docs/design.md section 6): shards through GNU parallel merge to exactly the unsharded
# sweep; resume after a killed sweep loses nothing and repeats nothing; a worker that dies is
# recorded as an error and the others go on; a worker's runs after its first equal runs in fresh
# workers; the time limit kills a hung run; --keep-logs keeps the worst runs' logs.
# usage: sweep_cli_test.sh HPA_BIN SCENARIOS_DIR OUT_DIR
set -uo pipefail
hpa=$1; scen=$2; out=$3
rm -rf "$out"; mkdir -p "$out"
# shellcheck source=cli_test_lib.sh
source "$(dirname "$0")/cli_test_lib.sh"
# runs.jsonl records without the fields that time the machine, one sorted line each
strip() {
  python3 -c 'import json, sys
for line in open(sys.argv[1]):
    if not line.strip(): continue
    r = json.loads(line)
    for k in ["wall_time_s", "mpc_solve_ms", "render_ms", "detector_ms", "image_model_ms"]:
        (r.get("metrics") or {}).pop(k, None)
    print(json.dumps(r, sort_keys=True))' "$1" | sort
}
count_runs() { if [ -f "$1" ]; then grep -c . "$1"; else echo 0; fi; }
unique_runs() {
  python3 -c 'import json, sys; print(len({json.loads(l)["run"] for l in open(sys.argv[1]) if l.strip()}))' "$1"
}

# a fast base: geometric controller on ground truth, a vertical impulse on the payload
impulse_hover_base "$out/base.yaml" sweep_base 2.0 0.5
cat > "$out/tiny.yaml" <<'YAML'
base: base.yaml
runs: 5
seed: 3
vary:
  events.0.impulse.2: {uniform: [0.05, 0.4]}
  world.payload_mass: {normal: [0.1, 0.01]}
  controller.type: {grid: [geometric, hpa_mpc]}
YAML

echo "== unsharded vs two shards through GNU parallel, merged"
"$hpa" sweep "$out/tiny.yaml" --out "$out/full" --jobs 2 > "$out/full.log" 2>&1 || fail "unsharded sweep failed: $(cat "$out/full.log")"
parallel --will-cite -j2 "$hpa" sweep "$out/tiny.yaml" --out "$out/shard{}" --shard {}/2 ::: 1 2 > "$out/shards.log" 2>&1 \
  || fail "sharded sweep failed: $(cat "$out/shards.log")"
"$hpa" merge "$out/shard1" "$out/shard2" --out "$out/merged" > /dev/null || fail "merge failed"
[ "$(count_runs "$out/full/runs.jsonl")" -eq 10 ] || fail "unsharded sweep has $(count_runs "$out/full/runs.jsonl") runs, expected 10"
[ "$(count_runs "$out/shard1/runs.jsonl")" -eq 5 ] || fail "shard 1 has $(count_runs "$out/shard1/runs.jsonl") runs, expected 5"
diff <(strip "$out/full/runs.jsonl") <(strip "$out/merged/runs.jsonl") > /dev/null \
  || fail "merged shards differ from the unsharded sweep"
for f in summary.md summary.json crash_rate.png; do
  [ -s "$out/merged/$f" ] || fail "merge did not write $f"
done
grep -q -- "--seed" "$out/merged/summary.md" || fail "summary.md lacks replay commands"

echo "== every JSON file written parses with a strict parser (no NaN, one record per line)"
python3 - "$out/full/runs.jsonl" "$out/merged/summary.json" "$out/full/summary.json" <<'PY' || fail "a JSON file is not strict JSON"
import json, sys
def strict(text):
    def refuse(c): raise ValueError("non-standard constant " + c)
    return json.loads(text, parse_constant=refuse)
for path in sys.argv[1:]:
    if path.endswith(".jsonl"):
        for n, line in enumerate(open(path), 1):
            assert line.endswith("\n"), f"{path}:{n} unterminated"
            strict(line)
    else:
        strict(open(path).read())
PY

echo "== merge refuses mixed sweeps; re-running into a used folder needs --resume"
sed 's/seed: 3/seed: 4/' "$out/tiny.yaml" > "$out/other.yaml"
"$hpa" sweep "$out/other.yaml" --out "$out/other" --shard 1/5 > /dev/null 2>&1
"$hpa" merge "$out/shard1" "$out/other" --out "$out/mixed" > /dev/null 2>&1
[ $? -eq 2 ] || fail "merge of two different sweeps did not exit 2"
"$hpa" sweep "$out/tiny.yaml" --out "$out/full" > /dev/null 2>&1
[ $? -eq 2 ] || fail "sweep into a used folder without --resume did not exit 2"

echo "== a replay command from summary.md reproduces its run exactly"
replay=$(grep -m1 -o 'hpa run [^`]*' "$out/full/summary.md" | sed "s|^hpa |$hpa |")
run_index=$(grep -m1 -o '^- run [0-9]*' "$out/full/summary.md" | grep -o '[0-9]*$')
$replay --out "$out/replay" --quiet > /dev/null 2>&1
python3 - "$out/full/runs.jsonl" "$run_index" "$out/replay/metrics.json" <<'PY' || fail "replay of run $run_index differs from its sweep record"
import json, sys
records = [json.loads(l) for l in open(sys.argv[1]) if l.strip()]
record = next(r for r in records if r["run"] == int(sys.argv[2]))
replay = json.load(open(sys.argv[3]))
for key in ["payload_rmse_m", "quad_position_deviation_max_m", "slack_time_s"]:
    assert record["metrics"][key] == replay[key], (key, record["metrics"][key], replay[key])
PY

echo "== a worker flies one run after another as a fresh process flies it"
# rendered camera and onboard estimator, mixed controllers: with --jobs 1 one worker flies all
# four runs (its GL context, tables and caches carried from run to run), with --jobs 4 each run
# has a worker of its own
printf 'base: base.yaml\nruns: 2\nseed: 11\nvary:\n  estimation.ground_truth: {list: [false]}\n  estimation.camera: {list: [render]}\n  events.0.impulse.2: {uniform: [0.05, 0.3]}\n  controller.type: {grid: [hpa_mpc, geometric]}\n' > "$out/reuse.yaml"
"$hpa" sweep "$out/reuse.yaml" --out "$out/one_worker" --jobs 1 > /dev/null 2>&1 || fail "one-worker sweep failed"
"$hpa" sweep "$out/reuse.yaml" --out "$out/own_workers" --jobs 4 > /dev/null 2>&1 || fail "four-worker sweep failed"
[ "$(count_runs "$out/one_worker/runs.jsonl")" -eq 4 ] || fail "one-worker sweep: $(count_runs "$out/one_worker/runs.jsonl") runs, expected 4"
diff <(strip "$out/one_worker/runs.jsonl") <(strip "$out/own_workers/runs.jsonl") \
  || fail "runs flown one after another by one worker differ from runs with a worker each"

echo "== resume after killing the sweep: nothing lost, nothing repeated"
cat > "$out/slow.yaml" <<'YAML'
base: base.yaml
runs: 8
seed: 5
vary:
  events.0.impulse.2: {uniform: [0.05, 0.4]}
  duration: {list: [6.0]}
  controller.type: {list: [hpa_mpc]}
YAML
setsid "$hpa" sweep "$out/slow.yaml" --out "$out/resume" --jobs 1 > /dev/null 2>&1 &
pid=$!
for _ in $(seq 1 600); do
  [ "$(count_runs "$out/resume/runs.jsonl")" -ge 2 ] && break
  sleep 0.1
done
kill -9 -- -"$pid" 2>/dev/null; wait "$pid" 2>/dev/null
before=$(count_runs "$out/resume/runs.jsonl")
[ "$before" -ge 2 ] && [ "$before" -lt 8 ] || fail "kill came at a bad time ($before runs recorded)"
"$hpa" sweep "$out/slow.yaml" --out "$out/resume" --jobs 2 --resume > /dev/null 2>&1 || fail "resume failed"
[ "$(count_runs "$out/resume/runs.jsonl")" -eq 8 ] || fail "after resume: $(count_runs "$out/resume/runs.jsonl") lines, expected 8"
[ "$(unique_runs "$out/resume/runs.jsonl")" -eq 8 ] || fail "after resume: runs repeated or lost"

echo "== a worker killed mid-run is recorded as an error; the sweep goes on"
# runs of 60 simulated seconds (about a wall second each): the worker found is still running
# when it is killed (a run of a few tenths of a second may have ended by then)
printf 'base: base.yaml\nruns: 3\nseed: 5\nvary:\n  duration: {list: [60.0]}\n  controller.type: {list: [hpa_mpc]}\n' > "$out/killed.yaml"
"$hpa" sweep "$out/killed.yaml" --out "$out/isolation" --jobs 1 > /dev/null 2>&1 &
pid=$!
victim=""
for _ in $(seq 1 600); do
  victim=$(pgrep -P "$pid" | head -1)
  [ -n "$victim" ] && break
  sleep 0.05
done
[ -n "$victim" ] && kill -9 "$victim"
wait "$pid" || fail "the sweep stopped because a worker died"
[ "$(count_runs "$out/isolation/runs.jsonl")" -eq 3 ] || fail "crash isolation: $(count_runs "$out/isolation/runs.jsonl") lines, expected 3"
grep -q 'worker killed by signal' "$out/isolation/runs.jsonl" || fail "the killed worker was not recorded as an error"

echo "== the time limit kills a run that takes too long"
printf 'base: base.yaml\nruns: 1\ntime_limit: 1\nvary:\n  duration: {list: [600.0]}\n  controller.type: {list: [hpa_mpc]}\n' > "$out/hang.yaml"
"$hpa" sweep "$out/hang.yaml" --out "$out/hang" > /dev/null 2>&1
grep -q 'killed after the time limit' "$out/hang/runs.jsonl" || fail "time limit not enforced"

echo "== a second sweep on the same folder is refused while the first runs, naming it"
# runs of 60 simulated seconds (a few wall seconds each): still running when checked
sed 's/duration: {list: \[6.0\]}/duration: {list: [60.0]}/' "$out/slow.yaml" > "$out/long.yaml"
"$hpa" sweep "$out/long.yaml" --out "$out/locked" --jobs 1 > /dev/null 2>&1 &
pid=$!
workers=""
for _ in $(seq 1 200); do
  workers=$(pgrep -P "$pid" | tr '\n' ' ')
  [ -n "$workers" ] && break
  sleep 0.05
done
"$hpa" sweep "$out/long.yaml" --out "$out/locked" --jobs 1 --resume > "$out/locked2.log" 2>&1
[ $? -eq 2 ] || fail "a second sweep on a busy folder did not exit 2"
grep -q "another hpa sweep (pid $pid)" "$out/locked2.log" \
  || fail "the refusal does not name the holder: $(cat "$out/locked2.log")"

echo "== kill -9 of a sweep takes its workers with it"
workers=""
for _ in $(seq 1 200); do
  workers=$(pgrep -P "$pid" | tr '\n' ' ')
  [ -n "$workers" ] && break
  sleep 0.01
done
[ -n "$workers" ] || fail "no worker seen to check"
kill -9 "$pid"; wait "$pid" 2> /dev/null
sleep 0.5
# a dead worker may linger as a zombie until init reaps it: only a running one is a failure
for w in $workers; do
  state=$(ps -o stat= -p "$w" 2> /dev/null | tr -d ' ')
  [ -n "$state" ] && [ "${state#Z}" = "$state" ] && fail "worker $w outlived its killed sweep ($state)"
done

echo "== a torn last line (killed mid-write) is dropped on --resume and its run redone"
mkdir -p "$out/torn"
head -n 9 "$out/full/runs.jsonl" > "$out/torn/runs.jsonl"
tail -n 1 "$out/full/runs.jsonl" | head -c 120 >> "$out/torn/runs.jsonl"
"$hpa" sweep "$out/tiny.yaml" --out "$out/torn" --resume > "$out/torn.log" 2>&1 || fail "resume after a torn line failed"
grep -q "unterminated" "$out/torn.log" || fail "the repair was not reported"
[ "$(unique_runs "$out/torn/runs.jsonl")" -eq 10 ] && [ "$(count_runs "$out/torn/runs.jsonl")" -eq 10 ] \
  || fail "after the repair: $(count_runs "$out/torn/runs.jsonl") lines, expected 10 distinct runs"

echo "== a full disk fails the sweep (exit 3), never exit 0"
# runs.jsonl: a file-size limit of 16 KiB holds inputs.json and the first records (about 2.5 KiB
# each), not all ten; SIGXFSZ ignored (inherited through exec) turns the limit into a failed
# write (EFBIG)
(trap '' XFSZ; ulimit -f 16; exec "$hpa" sweep "$out/tiny.yaml" --out "$out/full_jsonl" --jobs 1) \
  > "$out/full_jsonl.log" 2>&1
status=$?
[ "$status" -eq 4 ] || fail "runs.jsonl write past the limit: exit $status, expected 4"
grep -q "cannot append" "$out/full_jsonl.log" || fail "the failed append is not named: $(tail -2 "$out/full_jsonl.log")"
# summary.json on /dev/full (ENOSPC): its partial file, the one it is written to before the
# rename, is the device
mkdir -p "$out/full_summary" && ln -s /dev/full "$out/full_summary/summary.partial.json"
"$hpa" sweep "$out/tiny.yaml" --out "$out/full_summary" > "$out/full_summary.log" 2>&1
status=$?
[ "$status" -eq 4 ] || fail "summary.json on /dev/full: exit $status, expected 4"
grep -q "cannot write.*summary.json" "$out/full_summary.log" || fail "the failed summary write is not named"
# a runs.jsonl that is not a regular file (a device, a folder) is refused before anything runs
mkdir -p "$out/dev_jsonl" && ln -s /dev/full "$out/dev_jsonl/runs.jsonl"
"$hpa" sweep "$out/tiny.yaml" --out "$out/dev_jsonl" > "$out/dev_jsonl.log" 2>&1
status=$?
[ "$status" -eq 2 ] && grep -q "not a regular file" "$out/dev_jsonl.log" \
  || fail "a runs.jsonl on a device: exit $status: $(tail -1 "$out/dev_jsonl.log")"

echo "== --keep-logs worst:N keeps the log of the N worst runs, replayed bit for bit"
"$hpa" sweep "$out/tiny.yaml" --out "$out/keep" --keep-logs worst:3 > "$out/keep.log" 2>&1 \
  || fail "--keep-logs sweep failed: $(tail -3 "$out/keep.log")"
grep -q "WARNING" "$out/keep.log" && fail "a kept run's replay differs from its record"
python3 - "$out/keep" <<'PY' || fail "--keep-logs kept the wrong runs or no logs"
import json, os, sys
d = sys.argv[1]
records = [json.loads(l) for l in open(os.path.join(d, "runs.jsonl")) if l.strip()]
ok = [r for r in records if r["status"] == "ok"]
key = lambda r: (r["metrics"]["crashed"], r["metrics"]["quad_position_deviation_max_m"])
worst = sorted(ok, key=key, reverse=True)[:3]
kept = sorted(int(n.split("_")[1]) for n in os.listdir(os.path.join(d, "logs")))
assert kept == sorted(r["run"] for r in worst), (kept, [r["run"] for r in worst])
for n in kept:
    log = os.path.join(d, "logs", f"run_{n}", "log.csv")
    assert sum(1 for _ in open(log)) > 100, log
PY
expect_exit 2 "expected worst:N" sweep "$out/tiny.yaml" --out "$out/keep_bad" --keep-logs best:2
expect_exit 2 "unranked metric 'slack_time_s'" sweep "$out/tiny.yaml" --out "$out/keep_bad" \
  --keep-logs worst:2:slack_time_s

if [ $failures -ne 0 ]; then echo "$failures failure(s)"; exit 1; fi
echo "all sweep checks passed"
