#!/usr/bin/env bash
# Observing a run never changes it: the same scenario and seed with and without --video (the
# whole run, and slack events only) and --plots give the same metrics, every field but the
# timing ones. Nor does how the machine computes it: the controller on the simulation's thread
# (--no-control-thread) and llvmpipe rasterizing on two threads of its own (LP_NUM_THREADS=2). Runs line_impulse (rendered camera, a slack event) and a chaotic wind + impulse
# circle where any change in the loop's detections moves the metrics far.
#   observation_invariance_test.sh HPA_BIN SCENARIOS_DIR OUT_DIR
set -euo pipefail
hpa=$1
scen=$2
out=$3
rm -rf "$out"
mkdir -p "$out"

# metrics that measure the machine, not the run (at any depth: each vehicle's solve_ms)
timing='wall_time_s mpc_solve_ms render_ms image_model_ms detector_ms solve_ms'

same() {  # same A_DIR B_DIR: every metric but timing equal
  python3 - "$1/metrics.json" "$2/metrics.json" "$timing" <<'PY'
import json, sys
timing = set(sys.argv[3].split())
def strip(v):
    if isinstance(v, dict):
        return {k: strip(x) for k, x in v.items() if k not in timing}
    if isinstance(v, list):
        return [strip(x) for x in v]
    return v
a, b = (strip(json.load(open(p))) for p in sys.argv[1:3])
diff = [k for k in sorted(set(a) | set(b)) if a.get(k) != b.get(k)]
for k in diff:
    print(f"  {k}: {a.get(k)!r} != {b.get(k)!r}")
sys.exit(1 if diff else 0)
PY
}

fail=0
for file in line_impulse ci/wind_impulse_chaotic; do
  name=${file//\//_}
  "$hpa" run "$scen/$file.yaml" --out "$out/$name/plain" --quiet
  "$hpa" run "$scen/$file.yaml" --out "$out/$name/video" --quiet --plots \
    --video "$out/$name/video/run.mp4"
  "$hpa" run "$scen/$file.yaml" --out "$out/$name/slack" --quiet \
    --video "$out/$name/slack/run.mp4" --video-slack-events
  "$hpa" run "$scen/$file.yaml" --out "$out/$name/one_thread" --quiet --no-control-thread
  LP_NUM_THREADS=2 "$hpa" run "$scen/$file.yaml" --out "$out/$name/llvmpipe_threads" --quiet
  for observed in video slack one_thread llvmpipe_threads; do
    if same "$out/$name/plain" "$out/$name/$observed"; then
      echo "ok: $file, the $observed run equals the plain run"
    else
      echo "FAIL: $file, the $observed run changed the metrics above" >&2
      fail=1
    fi
  done
  for f in run.mp4 tracking.png; do
    [ -s "$out/$name/video/$f" ] || { echo "FAIL: $file wrote no $f" >&2; fail=1; }
  done
done
exit $fail
