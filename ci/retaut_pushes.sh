#!/usr/bin/env bash
# The paper's re-taut claim (section VI-B2: hpa_mpc meets the re-taut more gently than the
# non-hybrid baseline) on more than one push: line_impulse with a push straight up, diagonal and
# sideways, and hover_gripper_pull's lift (the gripper releasing the lifted payload). Each case is
# a sweep of RUNS paired draws (the push's time jittered by +-0.1 s, every draw its own seed;
# analytic camera, flight profile) flown by hpa_mpc, hpa_mpc with the re-taut predicted in its
# horizon (controller.predict_retaut) and nonhybrid_mpc; `hpa sweep-diff` compares each hpa arm
# with the baseline on the re-taut figures (paired Wilcoxon). Writes DIR/retaut_pushes.md.
# A developer tool (about 2 min with RUNS=20 on 2 cores), not a CI step:
#   ci/retaut_pushes.sh DIR [RUNS]
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:?usage: ci/retaut_pushes.sh DIR [RUNS]}
runs=${2:-20}
hpa=${HPA_BUILD_DIR:-build}/bin/hpa
mkdir -p "$out"

# case name | base scenario | the vary lines that make the case
cases=(
  "line|line_impulse|  events.0.at: {uniform: [3.4, 3.6]}"
  "diagonal|line_impulse|  events.0.at: {uniform: [3.4, 3.6]}\n  events.0.impulse.0: {list: [0.15]}\n  events.0.impulse.1: {list: [0.15]}\n  events.0.impulse.2: {list: [0.30]}"
  "sideways|line_impulse|  events.0.at: {uniform: [3.4, 3.6]}\n  events.0.impulse.0: {list: [0.0]}\n  events.0.impulse.1: {list: [0.25]}\n  events.0.impulse.2: {list: [0.25]}"
  "gripper lift|hover_gripper_pull|  events.3.at: {uniform: [7.9, 8.1]}"
)
for c in "${cases[@]}"; do
  name=${c%%|*}; rest=${c#*|}; base=${rest%%|*}; vary=${rest#*|}
  for predict in false true; do
    dir="$out/${name// /_}/predict_$predict"
    mkdir -p "$dir"
    printf 'base: %s\nruns: %s\nseed: 11\nvary:\n%b\n  estimation.camera: {list: [analytic]}\n  controller.predict_retaut: {list: [%s]}\n  controller.type: {grid: [hpa_mpc, nonhybrid_mpc]}\n' \
      "$PWD/scenarios/$base.yaml" "$runs" "$vary" "$predict" > "$dir/sweep.yaml"
    rm -rf "$dir/sweep"
    "$hpa" sweep "$dir/sweep.yaml" --out "$dir/sweep" --jobs "$(nproc)" > "$dir/sweep.log" 2>&1 \
      || { echo "sweep $name failed:"; tail -5 "$dir/sweep.log"; exit 1; }
    # paired: hpa_mpc (B) against nonhybrid_mpc (A; predict_retaut is hybrid-only)
    "$hpa" sweep-diff "$dir/sweep" "$dir/sweep" --a-where controller.type=nonhybrid_mpc \
      --b-where controller.type=hpa_mpc --out "$dir/diff" > "$dir/diff.log" 2>&1 \
      || { echo "sweep-diff $name failed:"; cat "$dir/diff.log"; exit 1; }
  done
  echo "$name done"
done

/usr/bin/python3 - "$out" <<'PY'
import json, os, statistics, sys
out = sys.argv[1]
arms = [("hpa_mpc", "hpa_mpc", "false"), ("hpa_mpc+predict_retaut", "hpa_mpc", "true"),
        ("nonhybrid_mpc", "nonhybrid_mpc", "false")]
lines = ["| push | controller | re-taut v_z min [m/s], median (min to max) | peak body rate [rad/s] "
         "| crashes | against the baseline (sweep-diff, B - A): v_z / body rate |",
         "|---|---|---|---|---|---|"]
def spread(v):
    v = [x for x in v if x is not None]
    return "-" if not v else f"{statistics.median(v):.2f} ({min(v):.2f} to {max(v):.2f})"
for case in ("line", "diagonal", "sideways", "gripper_lift"):
    for label, ctrl, predict in arms:
        d = os.path.join(out, case, "predict_" + predict)
        recs = [json.loads(l) for l in open(os.path.join(d, "sweep", "runs.jsonl"))]
        ms = [r["metrics"] for r in recs if r["controller"] == ctrl and r["metrics"]]
        ok = [m for m in ms if not m["crashed"]]
        vz = [m["retaut"]["quad_vz_min_mps"] for m in ok]
        rate = [m["retaut"]["peak_body_rate_radps"] for m in ok]
        verdict = ""
        if ctrl == "hpa_mpc":
            m = json.load(open(os.path.join(d, "diff", "diff.json")))["metrics"]
            verdict = " / ".join(
                f"{m[k]['verdict']} ({m[k]['difference']:+.2f}, p = {m[k]['p_value']:.2g})"
                for k in ("retaut_quad_vz_min_mps", "retaut_peak_body_rate_radps"))
        lines.append(f"| {case.replace('_', ' ')} | {label} | {spread(vz)} | {spread(rate)} | "
                     f"{len(ms) - len(ok)} of {len(ms)} | {verdict} |")
open(os.path.join(out, "retaut_pushes.md"), "w").write("\n".join(lines) + "\n")
print("\n".join(lines))
PY
