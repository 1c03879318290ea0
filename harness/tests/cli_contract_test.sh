#!/usr/bin/env bash
# CLI contract checks for `hpa` (docs/design.md section 7): exit codes 0/1/2, error messages that
# name the file and the key, determinism of metrics.json, render-frame output.
# usage: cli_contract_test.sh HPA_BIN SCENARIOS_DIR OUT_DIR
set -uo pipefail
hpa=$1; scen=$2; out=$3
rm -rf "$out"; mkdir -p "$out"
# shellcheck source=cli_test_lib.sh
source "$(dirname "$0")/cli_test_lib.sh"

base="$out/base.yaml"
printf 'name: base\nduration: 1.0\ncontroller: {type: geometric}\nestimation: {ground_truth: true, camera: analytic}\n' > "$base"

echo "== bad input: exit 2, message names the file and the key"
expect_exit 2 "nonexistent.yaml.*cannot (open|read)" run "$out/nonexistent.yaml" --out "$out/x"
printf 'name: [broken\n' > "$out/broken.yaml"
expect_exit 2 "broken.yaml.*malformed YAML" run "$out/broken.yaml" --out "$out/x"
printf 'name: t\nduration: 1.0\ncontroler: {type: hpa_mpc}\n' > "$out/typo.yaml"
expect_exit 2 "typo.yaml: key 'controler': unknown key" run "$out/typo.yaml" --out "$out/x"
printf 'name: t\nduration: 1.0\nworld: {payload_mass: -0.1}\n' > "$out/range.yaml"
expect_exit 2 "range.yaml: key 'world.payload_mass'.*out of range" run "$out/range.yaml" --out "$out/x"
printf 'name: t\nduration: 1.0\nevents:\n  - {at: 0.5, type: impulse, impulse: up}\n' > "$out/type.yaml"
expect_exit 2 "type.yaml: key 'events.0.impulse': expected a list of 3 numbers" run "$out/type.yaml" --out "$out/x"
expect_exit 2 "key '--controller'.*hpa_mpc" run "$base" --controller pid --out "$out/x"
expect_exit 2 "hpa run: --camera: lidar not in" run "$base" --camera lidar --out "$out/x"
expect_exit 2 "hpa run: .*not expected: --frobnicate" run "$base" --frobnicate
expect_exit 2 "hpa run: --seed: .*4294967295" run "$base" --seed 1e30 --out "$out/x"
expect_exit 2 "key 'estimation.camera_latency'.*out of range" run "$base" --set estimation.camera_latency=0.8 --out "$out/x"
expect_exit 2 "key 'events.4.at'.*not an index" run "$base" --set events.4.at=1 --out "$out/x"
expect_exit 2 "unknown command" fly "$base"
printf 'gravity_mps2: 9.81\n' > "$out/params.yaml"
expect_exit 2 "params.yaml: key 'quadrotor': missing" run "$base" --params "$out/params.yaml" --out "$out/x"
expect_exit 0 "hpa run SCENARIO.yaml" --help
expect_exit 0 "hpa sweep \\[OPTIONS\\] SWEEP.yaml" sweep --help

echo "== exit 0 when every bound holds, 1 when one fails (named)"
expect_exit 0 "wrote" run "$base" --out "$out/ok"
expect_exit 1 "EXPECT FAILED quad_position_deviation_min" run "$base" --out "$out/fail" \
  --set expect.quad_position_deviation_min=1.0
[ -s "$out/fail/metrics.json" ] || fail "a failed expectation must still write metrics.json"
grep -q '"passed": false' "$out/fail/metrics.json" || fail "metrics.json lacks expect.passed false"

echo "== determinism: same scenario and seed -> identical metrics (but wall-time fields)"
# metrics.json without the fields that time the machine, keys sorted
strip() {
  python3 -c 'import json, sys
m = json.load(open(sys.argv[1]))
for k in ["wall_time_s", "mpc_solve_ms", "render_ms", "detector_ms", "image_model_ms"]: m.pop(k, None)
print(json.dumps(m, indent=1, sort_keys=True))' "$1"
}
# log.csv without its timing column (solve_ms)
strip_log() {
  awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == "solve_ms") skip = i }
           { line = ""; for (i = 1; i <= NF; i++) if (i != skip) line = line (line == "" ? "" : ",") $i; print line }' "$1"
}
args=(run "$scen/lissajous_T5.yaml" --set duration=6 --set estimation.ground_truth=false --camera analytic --quiet)
"$hpa" "${args[@]}" --out "$out/det1" >/dev/null 2>&1
"$hpa" "${args[@]}" --out "$out/det2" >/dev/null 2>&1
"$hpa" "${args[@]}" --out "$out/det3" --seed 2 >/dev/null 2>&1
diff <(strip "$out/det1/metrics.json") <(strip "$out/det2/metrics.json") > /dev/null \
  || fail "two runs with the same seed differ: $(diff <(strip "$out/det1/metrics.json") <(strip "$out/det2/metrics.json"))"
diff <(strip_log "$out/det1/log.csv") <(strip_log "$out/det2/log.csv") > /dev/null \
  || fail "two runs with the same seed wrote different log.csv rows (solve_ms aside)"
head -1 "$out/det1/log.csv" | grep -q ',solve_ms,' || fail "log.csv has no solve_ms column"
diff <(strip "$out/det1/metrics.json") <(strip "$out/det3/metrics.json") > /dev/null \
  && fail "a different seed gave identical metrics: the noise is not seeded by the scenario"
# the rendered path too: off-screen rendering, the detector on its pixels, the onboard filters
rargs=(run "$base" --set duration=2 --set controller.type=hpa_mpc --set estimation.ground_truth=false --camera render --quiet)
"$hpa" "${rargs[@]}" --out "$out/rdet1" >/dev/null 2>&1
"$hpa" "${rargs[@]}" --out "$out/rdet2" >/dev/null 2>&1
python3 -c 'import json, sys; m = json.load(open(sys.argv[1])); assert m["camera"] == "render" and m["render_ms"]["median"] > 0, m' \
  "$out/rdet1/metrics.json" || fail "the rendered determinism run did not render"
diff <(strip "$out/rdet1/metrics.json") <(strip "$out/rdet2/metrics.json") > /dev/null \
  || fail "two rendered runs with the same seed differ: $(diff <(strip "$out/rdet1/metrics.json") <(strip "$out/rdet2/metrics.json"))"
diff <(strip_log "$out/rdet1/log.csv") <(strip_log "$out/rdet2/log.csv") > /dev/null \
  || fail "two rendered runs with the same seed wrote different log.csv rows (solve_ms aside)"

echo "== a world-only override does not reach flight code through its initial state"
"$hpa" run "$base" --out "$out/override" --quiet --set world.cable_length=0.42 \
  --set estimation.ground_truth=false > /dev/null 2>&1
col=$(head -1 "$out/override/log.csv" | tr ',' '\n' | grep -n '^est_mode$' | cut -d: -f1)
[ "$(awk -F, -v c="$col" 'NR==2{print $c}' "$out/override/log.csv")" = "1" ] \
  || fail "the estimator started from the world's (overridden) cable length"

echo "== render-frame writes a 1280x720 PNG"
expect_exit 0 "wrote" render-frame "$scen/hover.yaml" --at 1.0 --out "$out/frame.png"
size=$(od -An -tu1 -j16 -N8 "$out/frame.png" | tr -s ' ')
[ "$size" = " 0 0 5 0 0 0 2 208" ] || fail "frame.png is not 1280x720 (IHDR bytes:$size)"
expect_exit 2 "key '--at'" render-frame "$scen/hover.yaml" --at 99 --out "$out/frame2.png"
expect_exit 2 "--gl: unknown GL back end 'vulkan'" render-frame "$scen/hover.yaml" --at 1.0 \
  --out "$out/frame3.png" --gl vulkan

echo "== plots and video"
expect_exit 0 "plot" run "$base" --out "$out/plots" --plots --video "$out/plots/run.mp4"
for f in tracking.png xy_path.png retaut.png run.mp4; do
  [ -s "$out/plots/$f" ] || fail "missing $out/plots/$f"
done

echo "== hostile and careless input"
# an unexpected crash (no expect block) exits 1
cat > "$out/crash.yaml" <<'YAML'
name: crash_no_expect
duration: 2.0
controller: {type: geometric}
estimation: {ground_truth: true, camera: analytic}
events:
  - {at: 0.1, type: impulse, body: quadrotor, impulse: [0, 0, -30]}
YAML
expect_exit 1 "crashed .* does not expect a crash" run "$out/crash.yaml" --out "$out/crash" --quiet
# a full disk is an error, never exit 0: exit 4, an output that could not be written
mkdir -p "$out/full_disk" && ln -sf /dev/full "$out/full_disk/metrics.partial.json"
expect_exit 4 "cannot write" run "$out/crash.yaml" --set duration=0.1 --out "$out/full_disk" --quiet
expect_exit 2 "render-frame|PNG" render-frame "$scen/hover.yaml" --at 0.1 --out "$out/frame.jpg"
printf 'base: %s/hover.yaml\nruns: 2\nvary:\n  seed: {uniform: [1, 9]}\n' "$scen" > "$out/seed_sweep.yaml"
expect_exit 2 "seed cannot be varied" sweep "$out/seed_sweep.yaml" --out "$out/seed_sweep"
printf 'base: %s/hover.yaml\nruns: 2\nvary:\n  duration: {uniform: [1, 2]}\n' "$scen" > "$out/ok_sweep.yaml"
expect_exit 2 "shard" sweep "$out/ok_sweep.yaml" --out "$out/junk_shard" --shard 1/2junk
mkdir -p "$out/bad_shard/runs.jsonl"
expect_exit 2 "not a readable file" merge "$out/bad_shard" --out "$out/bad_merge"
expect_exit 2 "controllers" compare "$scen/hover.yaml" --out "$out/cmp" --controllers ,,
expect_exit 2 "unknown controller 'pid'" compare "$scen/hover.yaml" --out "$out/cmp2" --controllers geometric,pid
[ -e "$out/cmp2/geometric" ] && fail "compare ran geometric before refusing pid"
# compare's paired table: both controllers' metrics and the difference, equal to their metrics
"$hpa" compare "$base" --out "$out/cmp3" --controllers geometric,hpa_mpc --set duration=0.5 --quiet \
  > /dev/null 2>&1
python3 - "$out/cmp3" <<'PY' || fail "compare's comparison.md does not match the runs' metrics"
import json, sys
d = sys.argv[1]
rows = {l.split("|")[1].strip(): [c.strip() for c in l.split("|")[2:-1]]
        for l in open(d + "/comparison.md") if l.startswith("| ") and "---" not in l}
a = json.load(open(d + "/geometric/metrics.json"))["quad_position_deviation_max_m"]
b = json.load(open(d + "/hpa_mpc/metrics.json"))["quad_position_deviation_max_m"]
got = [float(x) for x in rows["quad deviation max [m]"]]
assert abs(got[0] - a) <= 1e-3 * max(a, 1e-9) and abs(got[1] - b) <= 1e-3 * max(b, 1e-9), got
assert abs(got[2] - (b - a)) <= 1e-3 * max(abs(b - a), 1e-6) + 1e-6, got
PY
# a directory given as a file, malformed values, complex keys: bad input naming file and key
expect_exit 2 "not a regular file" run "$out" --out "$out/x"
expect_exit 2 "not a regular file" run "$base" --params "$out" --out "$out/x"
expect_exit 2 "not a regular file" sweep "$out" --out "$out/dir_sweep"
expect_exit 2 "--set: key 'duration': malformed value" run "$base" --set 'duration=[1' --out "$out/x"
expect_exit 2 "--set duration=\{a: 1\}: key 'duration': expected a number" run "$base" --set 'duration={a: 1}' --out "$out/x"
printf '? [a, b]\n: 1\nname: t\nduration: 1.0\n' > "$out/complex_key.yaml"
expect_exit 2 "complex_key.yaml.*plain name" run "$out/complex_key.yaml" --out "$out/x"
printf 'base: %s\nruns: 2\nvary:\n  duration: {list: [1, [2]]}\n' "$base" > "$out/list_sweep.yaml"
expect_exit 2 "list_sweep.yaml: key 'vary.duration.list': expected a list of scalars" \
  sweep "$out/list_sweep.yaml" --out "$out/list_sweep"
# every draw is validated before the first run, not only the first: a quarter of these
# durations are past the 3600 s limit
printf 'base: %s\nruns: 20\nvary:\n  duration: {uniform: [1, 4800]}\n' "$base" > "$out/draw_sweep.yaml"
expect_exit 2 "draw_sweep.yaml: key 'vary': run [0-9]+ \\(duration=[0-9.e+]+\\) is not a valid scenario" \
  sweep "$out/draw_sweep.yaml" --out "$out/draw_sweep"
[ -e "$out/draw_sweep/runs.jsonl" ] && fail "an invalid sweep started running"
# --retry-errors runs the recorded errors again (e.g. a run killed from outside)
printf 'base: %s\nruns: 2\nvary:\n  duration: {uniform: [0.3, 0.5]}\n' "$base" > "$out/retry_sweep.yaml"
"$hpa" sweep "$out/retry_sweep.yaml" --out "$out/retry" --jobs 1 > /dev/null 2>&1 || fail "retry sweep"
python3 - "$out/retry/runs.jsonl" <<'PY'
import json, sys
lines = [json.loads(l) for l in open(sys.argv[1])]
lines[0].update(status="error", error="worker killed by signal Killed", metrics=None)
open(sys.argv[1], "w").write("".join(json.dumps(l) + "\n" for l in lines))
PY
expect_exit 2 "retry-errors.*only with --resume" sweep "$out/retry_sweep.yaml" --out "$out/retry" --retry-errors
expect_exit 0 "1 error record dropped" sweep "$out/retry_sweep.yaml" --out "$out/retry" --resume --retry-errors
python3 -c 'import json, sys; r = [json.loads(l) for l in open(sys.argv[1])]; assert sorted(x["run"] for x in r) == [0, 1] and all(x["status"] == "ok" for x in r), r' \
  "$out/retry/runs.jsonl" || fail "--retry-errors: runs.jsonl does not hold both runs, ok, once each"
# a slack-events video of a run without slack: nothing written, and said
expect_exit 0 "no slack event in this run: no video written" run "$base" --video-slack-events --out "$out/novideo" --quiet
[ -e "$out/novideo/slack_events.mp4" ] && fail "an empty slack-events video was written"

# --version names the version and the commit the binary was built from
expect_exit 0 "^hpa [0-9]+\.[0-9]+\.[0-9]+ \(commit ([0-9a-f]{12}|unknown)" --version

# SIGTERM mid-run: the metrics and log so far are written, and the run says it was stopped
"$hpa" run "$scen/hover.yaml" --set duration=3000 --out "$out/sigterm" --quiet > /dev/null 2>&1 &
pid=$!
sleep 1  # a loaded machine may still be setting up the world: the stop then comes at t = 0
kill -TERM "$pid"
wait "$pid"; status=$?
[ "$status" -eq 143 ] || fail "SIGTERM: exit $status, expected 143 (128 + SIGTERM)"
python3 -c 'import json, sys; m = json.load(open(sys.argv[1])); assert "signal 15" in m["run_error"] and 0 <= m["sim_time_s"] < 3000, m' \
  "$out/sigterm/metrics.json" || fail "SIGTERM: no partial metrics.json naming the signal"
[ -s "$out/sigterm/log.csv" ] || fail "SIGTERM: no partial log.csv"

if [ $failures -ne 0 ]; then echo "$failures failure(s)"; exit 1; fi
echo "all CLI contract checks passed"
