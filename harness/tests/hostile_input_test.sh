#!/usr/bin/env bash
# Hostile input to `hpa`, one check per case: each gets a clear message naming what was wrong
# and the documented exit code, or a safe result, and never loses results already computed.
# usage: hostile_input_test.sh HPA_BIN SCENARIOS_DIR OUT_DIR
set -uo pipefail
hpa=$1; scen=$(cd "$2" && pwd); out=$3
rm -rf "$out"; mkdir -p "$out"
# shellcheck source=cli_test_lib.sh
source "$(dirname "$0")/cli_test_lib.sh"

# a short ground-truth hover and a sweep of it (seconds each)
base="$out/base.yaml"
cat > "$base" <<'YAML'
name: base
duration: 1.0
seed: 1
controller: {type: geometric}
estimation: {ground_truth: true, camera: analytic}
reference: {type: hover, payload_position: [0, 0, 0.7]}
YAML
sweep="$out/sweep.yaml"
cat > "$sweep" <<YAML
base: $base
runs: 80
seed: 3
vary:
  world.payload_mass: {uniform: [0.09, 0.11]}
  duration: {list: [3.0]}
YAML

echo "== SIGTERM / SIGINT stop a sweep at once, record nothing unstarted, exit 143 / 130"
for sig in TERM INT; do
  dir="$out/signal_$sig"
  "$hpa" sweep "$sweep" --out "$dir" --jobs 2 > "$dir.log" 2>&1 &
  pid=$!
  for _ in $(seq 1 200); do [ -s "$dir/runs.jsonl" ] && break; sleep 0.05; done
  kill -"$sig" "$pid"
  start=$(date +%s.%N)
  wait "$pid"; status=$?
  took=$(echo "$(date +%s.%N) - $start" | bc)
  want=$([ "$sig" = TERM ] && echo 143 || echo 130)
  [ "$status" -eq "$want" ] || fail "SIG$sig: exit $status, expected $want: $(tail -2 "$dir.log")"
  echo "$took < 3" | bc -l | grep -q 1 || fail "SIG$sig: took $took s to stop"
  errors=$(grep -c '"status":"error"\|"status": "error"' "$dir/runs.jsonl")
  [ "$errors" -eq 0 ] || fail "SIG$sig: $errors error records written for runs that never ran"
  recorded=$(wc -l < "$dir/runs.jsonl")
  [ "$recorded" -lt 80 ] || fail "SIG$sig: the sweep was not stopped ($recorded runs recorded)"
  "$hpa" sweep "$sweep" --out "$dir" --jobs 2 --resume > "$dir.resume.log" 2>&1 \
    || fail "SIG$sig: --resume failed: $(tail -2 "$dir.resume.log")"
  ok=$(grep -c '"status":"ok"\|"status": "ok"' "$dir/runs.jsonl")
  [ "$ok" -eq 80 ] || fail "SIG$sig: --resume left $ok of 80 runs done"
done

echo "== editing the base scenario during a sweep changes no run (the sweep runs its snapshot)"
cp "$base" "$out/edited_base.yaml"
sed "s|^base: .*|base: $out/edited_base.yaml|" "$sweep" > "$out/edited_sweep.yaml"
"$hpa" sweep "$out/edited_sweep.yaml" --out "$out/edited" --jobs 2 > "$out/edited.log" 2>&1 &
pid=$!
for _ in $(seq 1 200); do [ -s "$out/edited/runs.jsonl" ] && break; sleep 0.05; done
printf 'name: broken\nduration: -5\n' > "$out/edited_base.yaml"
wait "$pid" || fail "the sweep failed after its base was edited: $(tail -2 "$out/edited.log")"
ok=$(grep -c '"status":"ok"\|"status": "ok"' "$out/edited/runs.jsonl")
[ "$ok" -eq 80 ] || fail "editing the base mid-sweep changed runs: $ok of 80 ok"
expect_exit 2 "holds runs of a different sweep" sweep "$out/edited_sweep.yaml" --out "$out/edited" --resume
echo "== --resume --allow-changed-inputs continues with changed inputs and marks the new records"
{ cat "$base"; echo "# edited"; } > "$out/edited_base.yaml"
head -n 78 "$out/edited/runs.jsonl" > "$out/edited/part" && mv "$out/edited/part" "$out/edited/runs.jsonl"
expect_exit 2 "allow-changed-inputs" sweep "$out/edited_sweep.yaml" --out "$out/edited" --resume
"$hpa" sweep "$out/edited_sweep.yaml" --out "$out/edited" --resume --allow-changed-inputs \
  > "$out/allowed.log" 2>&1 || fail "--allow-changed-inputs failed: $(tail -2 "$out/allowed.log")"
grep -q "warning: the sweep or base file changed" "$out/allowed.log" || fail "no warning for changed inputs"
python3 - "$out/edited/runs.jsonl" <<'PY' || fail "records after --allow-changed-inputs are not marked"
import json, sys
records = [json.loads(l) for l in open(sys.argv[1]) if l.strip()]
assert len(records) == 80, len(records)
assert len({r["sweep_id"] for r in records}) == 1, "sweep_id changed"
marked = [r for r in records if "inputs_id" in r]
assert len(marked) == 2 and all(r["inputs_id"] != r["sweep_id"] for r in marked), marked
PY
"$hpa" merge "$out/edited" --out "$out/edited_merged" > /dev/null 2>&1 || fail "merge of a resumed-with-changed-inputs folder failed"

echo "== merge: missing runs (exit 1), empty input (exit 2), conflicting records (a warning)"
"$hpa" sweep "$sweep" --out "$out/half" --shard 1/2 --jobs 2 > /dev/null 2>&1 || fail "shard 1/2 failed"
expect_exit 1 "merge incomplete: 40 of 80 runs missing \(1, 3, 5" merge "$out/half" --out "$out/half_merged"
[ -s "$out/half_merged/runs.jsonl" ] || fail "an incomplete merge wrote no runs.jsonl"
mkdir -p "$out/empty" && : > "$out/empty/runs.jsonl"
expect_exit 2 "no runs recorded" merge "$out/empty" --out "$out/empty_merged"
mkdir -p "$out/conflict"
python3 - "$out/half/runs.jsonl" "$out/conflict/runs.jsonl" <<'PY'
import json, sys
lines = [json.loads(l) for l in open(sys.argv[1])]
lines[0]["metrics"]["quad_position_deviation_max_m"] += 1.0
open(sys.argv[2], "w").write(json.dumps(lines[0]) + "\n")
PY
expect_exit 1 "recorded twice with different results" merge "$out/half" "$out/conflict" \
  --out "$out/conflict_merged"

echo "== a shard spec that overflows is refused"
expect_exit 2 "shard.*1 <= K <= N" sweep "$sweep" --out "$out/shard" --shard 4294967297/4294967297

echo "== one list element under two spellings is refused"
cat > "$out/spelling.yaml" <<YAML
base: $scen/line_impulse.yaml
runs: 2
seed: 3
vary:
  events.0.impulse.2: {uniform: [0.1, 0.2]}
  events.0.impulse.02: {uniform: [0.3, 0.4]}
YAML
expect_exit 2 "'02' is not an index" sweep "$out/spelling.yaml" --out "$out/spelling"
expect_exit 2 "'02' is not an index" run "$scen/line_impulse.yaml" --set events.0.impulse.02=0.3 \
  --out "$out/x"

echo "== multi-document YAML and tagged scalars are refused"
{ cat "$base"; printf -- '---\nname: second\n'; } > "$out/two_docs.yaml"
expect_exit 2 "two_docs.yaml: holds more than one YAML document" run "$out/two_docs.yaml" --out "$out/x"
expect_exit 2 "holds more than one YAML document" run "$base" --set "duration=1
---
2" --out "$out/x"
sed 's/^duration: 1.0/duration: !!str 2/' "$base" > "$out/tag_str.yaml"
expect_exit 2 "key 'duration'.*tagged" run "$out/tag_str.yaml" --out "$out/x"
sed 's/^duration: 1.0/duration: !foo 1/' "$base" > "$out/tag_foo.yaml"
expect_exit 2 "key 'duration'.*tagged '!foo'" run "$out/tag_foo.yaml" --out "$out/x"

echo "== messages: whole-number bounds, the --set argument, the valid keys, the --video problem"
sed 's/^seed: 1/seed: 4294967295.5/' "$base" > "$out/seed.yaml"
expect_exit 2 "value 4294967295.5 out of range.*\[0, 4294967295\]" run "$out/seed.yaml" --out "$out/x"
expect_exit 2 "^hpa: error: --set duration=-1: key 'duration'" run "$base" --set duration=-1 --out "$out/x"
printf 'name: t\nduration: 1.0\nseeed: 2\n' > "$out/typo.yaml"
expect_exit 2 "unknown key; valid keys here: .*duration.*seed" run "$out/typo.yaml" --out "$out/x"
expect_exit 2 "the folder is the problem" run "$base" --out "$out/x" --video "$out/no_such_folder/v.mp4"
expect_exit 2 "the extension is the problem" run "$base" --out "$out/x" --video "$out/v.avi"

echo "== a payload reference below the ground is refused"
expect_exit 2 "reference.*below the ground" run "$base" --set "reference.payload_position=[0, 0, -0.3]" \
  --out "$out/x"

echo "== the quadrotor slammed onto the payload lying on the ground is a crash"
cat > "$out/slam.yaml" <<'YAML'
name: slam
duration: 2.0
seed: 1
controller: {type: hpa_mpc}
estimation: {ground_truth: true, camera: analytic}
reference: {type: hover, payload_position: [0, 0, 0.05]}
events:
  - {at: 1.0, type: impulse, body: quadrotor, impulse: [0, 0, -12.0]}
YAML
expect_exit 1 "crashed \(quadrotor contact with the payload lying on the ground" run "$out/slam.yaml" \
  --out "$out/slam"

echo "== a run killed with -9 leaves no complete-looking metrics.json"
"$hpa" run "$base" --out "$out/killed" --quiet || fail "first run failed"
[ -s "$out/killed/metrics.json" ] || fail "no metrics.json from the first run"
"$hpa" run "$scen/lissajous_T5.yaml" --camera analytic --set duration=60 --out "$out/killed" \
  --overwrite --quiet > /dev/null 2>&1 &
pid=$!
# killed once it has started (the previous run's outputs are gone), however loaded the machine
for _ in $(seq 600); do [ -e "$out/killed/metrics.json" ] || break; sleep 0.05; done
kill -9 "$pid"; wait "$pid" 2> /dev/null
[ ! -e "$out/killed/metrics.json" ] || fail "the killed run left a metrics.json"
[ ! -e "$out/killed/log.csv" ] || fail "the killed run left a log.csv"

echo "== golden: refuses aborted or failing runs, blank reasons, bad tolerances, bad maps"
golden="$out/golden.json"
mkdir -p "$out/from"
printf '{"tolerances": {"default": {"rel": 1e-3}}, "scenarios": {}}' > "$golden"
expect_exit 2 "reason.*not blank" golden --golden "$golden" --update --reason '   ' --from "$out/from"
printf '{"tolerances": {"default": {"rel": "tight"}}, "scenarios": {}}' > "$golden"
expect_exit 2 "golden.json: key 'tolerances.default.rel': expected a number" golden --golden "$golden" \
  --from "$out/from"
printf '{"tolerances": {"default": {"rel": 1e-3}}, "scenarios": []}' > "$golden"
expect_exit 2 "key 'scenarios': expected a map of scenario name to metrics, got a JSON array" \
  golden --golden "$golden" --from "$out/from"
printf '{"tolerances": {"default": {"rel": 1e-3}}}' > "$golden"
expect_exit 2 "key 'scenarios': missing" golden --golden "$golden" --from "$out/from"
# an aborted run's metrics (run_error set) are never recorded
python3 - "$scen" "$out/from" <<'PY'
import glob, json, os, sys
scen, out = sys.argv[1], sys.argv[2]
names = sorted([os.path.splitext(os.path.basename(p))[0] for p in glob.glob(scen + "/*.yaml")] +
               ["ci_" + os.path.splitext(os.path.basename(p))[0] for p in glob.glob(scen + "/ci/*.yaml")])
for i, n in enumerate(names):
    os.makedirs(os.path.join(out, n), exist_ok=True)
    m = {"scenario": n, "expect": {"passed": True, "failed": []}, "run_error": None}
    if i == 0:
        m["run_error"] = "stopped by signal 15 (at t = 1.2 s)"
    json.dump(m, open(os.path.join(out, n, "metrics.json"), "w"))
PY
printf '{"tolerances": {"default": {"rel": 1e-3}}, "scenarios": {}}' > "$golden"
expect_exit 2 "aborted.*not recorded as golden" golden --golden "$golden" --update --reason test \
  --from "$out/from" --quiet

echo "== golden and sweep-diff refuse FIFOs and devices (no hang, no unbounded read)"
mkfifo "$out/fifo"
expect_exit 2 "not a regular file" golden --golden "$out/fifo" --from "$out/from"
expect_exit 2 "not a regular file" golden --golden /dev/zero --from "$out/from"
mkdir -p "$out/fifo_sweep"
mkfifo "$out/fifo_sweep/runs.jsonl"
expect_exit 2 "not a regular file" sweep-diff "$out/fifo_sweep" "$out/fifo_sweep" --out "$out/d"

echo "== an output that cannot be written: exit 4"
expect_exit 4 "cannot write" render-frame "$base" --at 0.5 --out /dev/full/frame.png
: > "$out/a_file"
expect_exit 4 "cannot write.*a_file.*output folder" run "$base" --out "$out/a_file"

echo "== physics that cannot fly is refused before the run, naming the parameter (exit 2)"
for case in "params.quadrotor.mass_kg=100|cannot hover: .* 982 N .* at most 20.09 N" \
    "params.rotor.k_f_N_per_radps2=1e-12|k_m_Nm_per_radps2.*k_m / k_f" \
    "params.rotor.motor_speed_max_radps=101|cannot hover" \
    "params.gravity_mps2=100|cannot hover" \
    "params.payload.mass_kg=100|cannot hover" \
    "params.cable.length_m=10|the vehicle, 10 m above it, would be outside the 20 x 20 x 10 m arena" \
    "params.quadrotor.body_half_size_m=[5,5,5]|into the body \\(half height 5 m\\)" \
    "params.payload.radius_m=0.6|payload of radius 0.6 m into the body" \
    "params.cable.slack_epsilon_m=1.0|slack_epsilon_m': must be below the cable's length_m \\(0.5\\)" \
    "params.rotor.k_m_Nm_per_radps2=1.0|k_m / k_f .* expected at most 0.2 m" \
    "params.rotor.motor_speed_min_radps=2000|motor_speed_min_radps': must be below motor_speed_max_radps" \
    "reference.payload_position=[0,0,50]|payload at \\(0, 0, 50\\) m at t = 0 s: the vehicle.* outside" \
    "reference.payload_position=[500,0,0.7]|payload at \\(500, 0, 0.7\\) m"; do
  expect_exit 2 "${case#*|}" run "$base" --quiet --out "$out/unflyable" --set "${case%%|*}"
done
[ -e "$out/unflyable/metrics.json" ] && fail "an unflyable scenario wrote metrics"

echo "== an empty option value is refused, never read as the default"
expect_exit 2 "key '--out': an empty value" run "$base" --quiet --out ""

echo "== SIGINT during hpa run and hpa golden: exit 130, what was computed is written"
long="$out/long.yaml"
sed 's/^duration: .*/duration: 600.0/' "$base" > "$long"
"$hpa" run "$long" --quiet --out "$out/sig_run" > "$out/sig_run.log" 2>&1 &
pid=$!; sleep 1.5; kill -INT "$pid"; wait "$pid"; status=$?
[ "$status" -eq 130 ] || fail "hpa run stopped by SIGINT exited $status, expected 130: $(cat "$out/sig_run.log")"
grep -q '"run_error": "stopped by signal 2' "$out/sig_run/metrics.json" 2>/dev/null \
  || fail "the stopped run's metrics.json does not say it was stopped"
HPA_DATA_DIR=$(dirname "$scen") "$hpa" golden --quiet > "$out/sig_golden.log" 2>&1 &
pid=$!; sleep 1.5; kill -INT "$pid"; wait "$pid"; status=$?
[ "$status" -eq 130 ] || fail "hpa golden stopped by SIGINT exited $status, expected 130: $(cat "$out/sig_golden.log")"
grep -q "stopped by signal 2.*nothing compared or written" "$out/sig_golden.log" \
  || fail "golden does not say it was stopped: $(cat "$out/sig_golden.log")"

echo "== golden --from and sweep-diff refuse records of the wrong shape (exit 2, not 3)"
mkdir -p "$out/shape"
for n in $(python3 -c "import glob,os,sys; print(' '.join([os.path.splitext(os.path.basename(p))[0] for p in glob.glob(sys.argv[1]+'/*.yaml')] + ['ci_' + os.path.splitext(os.path.basename(p))[0] for p in glob.glob(sys.argv[1]+'/ci/*.yaml')]))" "$scen"); do
  mkdir -p "$out/shape/$n"; echo '[1,2]' > "$out/shape/$n/metrics.json"
done
printf '{"tolerances": {"default": {"rel": 1e-3}}, "scenarios": {}}' > "$out/shape/golden.json"
expect_exit 2 "expected a metrics.json object, got array" golden --golden "$out/shape/golden.json" \
  --from "$out/shape" --quiet
mkdir -p "$out/oops"
echo '{"sweep_id":"x","sweep":"s","base":"b","run":0,"draw":0,"seed":1,"values":{},"controller":"c","status":"ok","error":null,"metrics":"oops"}' \
  > "$out/oops/runs.jsonl"
expect_exit 2 "runs.jsonl: key 'line 1: metrics': expected a metrics.json object or null" \
  sweep-diff "$out/oops" "$out/oops" --out "$out/oops_diff"

echo "== a sweep flies the reference CSV it was started with; a resume refuses it edited"
mkdir -p "$out/csv_sweep"
cp "$scen/references/figure_eight_path.csv" "$out/csv_sweep/path.csv"
cat > "$out/csv_sweep/base.yaml" <<'YAML'
name: csv_base
duration: 2.0
controller: {type: geometric}
estimation: {ground_truth: true, camera: analytic}
reference: {type: csv, file: path.csv}
YAML
printf 'base: base.yaml\nruns: 6\nseed: 2\nvary:\n  estimation.camera: {list: [analytic]}\n' \
  > "$out/csv_sweep/sweep.yaml"
"$hpa" sweep "$out/csv_sweep/sweep.yaml" --out "$out/csv_sweep/out" --jobs 1 \
  > "$out/csv_sweep/sweep.log" 2>&1 &
pid=$!
for _ in $(seq 1 400); do [ -s "$out/csv_sweep/out/runs.jsonl" ] && break; sleep 0.05; done
rm "$out/csv_sweep/path.csv"  # gone mid-sweep: the runs still to come fly the snapshot
wait "$pid" || fail "the sweep failed once its CSV was gone: $(tail -3 "$out/csv_sweep/sweep.log")"
python3 - "$out/csv_sweep/out/runs.jsonl" "$out/csv_sweep/out/inputs.json" <<'PY' \
  || fail "a run did not fly the snapshot of the CSV"
import json, sys
runs = [json.loads(l) for l in open(sys.argv[1])]
assert len(runs) == 6 and all(r["status"] == "ok" for r in runs), [r["error"] for r in runs]
roles = [f["role"] for f in json.load(open(sys.argv[2]))["files"]]
assert roles[:3] == ["sweep", "base", "reference.file"] and "params" in roles, roles
PY
cp "$scen/references/figure_eight_path.csv" "$out/csv_sweep/path.csv"
sed -i '5s/.*/0.02,0.05,0.0,0.8/' "$out/csv_sweep/path.csv"
expect_exit 2 "holds runs of a different sweep" sweep "$out/csv_sweep/sweep.yaml" \
  --out "$out/csv_sweep/out" --resume

echo "== compare clears what an earlier comparison left before it runs (no old and new mixed)"
mkdir -p "$out/cmp_stale/nonhybrid_mpc" "$out/cmp_stale/geometric"
echo '{"stale": true}' > "$out/cmp_stale/nonhybrid_mpc/metrics.json"
echo '{"stale": true}' > "$out/cmp_stale/geometric/metrics.json"
echo "stale" > "$out/cmp_stale/comparison.md"
"$hpa" compare "$base" --controllers geometric --out "$out/cmp_stale" --quiet \
  > "$out/cmp_stale.log" 2>&1 || fail "compare failed: $(tail -2 "$out/cmp_stale.log")"
[ -e "$out/cmp_stale/nonhybrid_mpc/metrics.json" ] && fail "a stale controller's metrics survived"
grep -q stale "$out/cmp_stale/geometric/metrics.json" "$out/cmp_stale/comparison.md" \
  && fail "stale comparison outputs survived"

echo "== hpa schema params lists every parameter's range"
"$hpa" schema params > "$out/schema_params.md" 2>&1
grep -q '`params.cable.length_m` | m | 0.05 to 10 |' "$out/schema_params.md" \
  || fail "schema params does not list the cable length's range: $(head -5 "$out/schema_params.md")"

[ $failures -eq 0 ] && echo "hostile input: all checks passed"
exit $((failures > 0))
