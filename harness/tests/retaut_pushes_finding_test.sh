#!/usr/bin/env bash
# The re-taut claim of the paper (section VI-B2) on four pushes, paired over 12 draws each
# (ci/retaut_pushes.sh: analytic camera, flight profile; hpa sweep-diff's paired Wilcoxon).
# Findings at 20 draws (docs/results.md, "Re-taut on more than one push"):
# - line push: hpa_mpc with the re-taut predicted in its horizon meets it with a smaller |v_z|
#   and a smaller peak body rate than the baseline ("better" on both);
# - gripper lift: with the prediction, |v_z| is smaller ("better", +0.10 m/s) and the peak body
#   rate 0.07 rad/s lower, within the 0.2 rad/s that matters ("no difference shown");
# - diagonal and sideways pushes: hpa_mpc's peak body rate is lower ("better") but its |v_z| is
#   larger ("worse"): the baseline follows the swinging payload and the cable re-tightens
#   with less speed along it; hpa_mpc holds its position and the cable jerks it down.
# Regression bounds on hpa_mpc + predict_retaut's medians: the 20-draw measurement times 1.3
# (line: -0.20 m/s and 0.19 rad/s, bounds v_z >= -0.26 m/s, body rate <= 0.25 rad/s; lift:
# -0.15 m/s and 0.23 rad/s, bounds v_z >= -0.20 m/s, body rate <= 0.30 rad/s), so a 50 %
# regression fails.
set -u
hpa="$1"; root="$2"; out="$3"
rm -rf "$out"; mkdir -p "$out"
fail() { echo "FAIL: $*"; exit 1; }
HPA_BUILD_DIR="$(cd "$(dirname "$hpa")/.." && pwd)" "$root/ci/retaut_pushes.sh" "$out" 12 \
  > "$out/run.log" 2>&1 || fail "ci/retaut_pushes.sh failed: $(tail -5 "$out/run.log")"
cat "$out/retaut_pushes.md"
python3 - "$out" <<'PY' || fail "re-taut findings do not hold"
import json, statistics, sys
out = sys.argv[1]
def verdicts(case, predict):
    m = json.load(open(f"{out}/{case}/predict_{predict}/diff/diff.json"))["metrics"]
    return m["retaut_quad_vz_min_mps"]["verdict"], m["retaut_peak_body_rate_radps"]["verdict"]
def medians(case):
    recs = [json.loads(l) for l in open(f"{out}/{case}/predict_true/sweep/runs.jsonl")]
    ms = [r["metrics"] for r in recs if r["controller"] == "hpa_mpc" and not r["metrics"]["crashed"]]
    return (statistics.median(m["retaut"]["quad_vz_min_mps"] for m in ms),
            statistics.median(m["retaut"]["peak_body_rate_radps"] for m in ms))
assert verdicts("line", "true") == ("better", "better"), verdicts("line", "true")
vz_verdict, rate_verdict = verdicts("gripper_lift", "true")
assert vz_verdict == "better" and rate_verdict in ("better", "no difference shown"), \
    verdicts("gripper_lift", "true")
for case, vz_min, rate_max in (("line", -0.26, 0.25), ("gripper_lift", -0.20, 0.30)):
    vz, rate = medians(case)
    assert vz >= vz_min and rate <= rate_max, (case, vz, rate)
for case in ("diagonal", "sideways"):
    assert verdicts(case, "false") == ("worse", "better"), (case, verdicts(case, "false"))
PY
echo "re-taut findings on four pushes: hold"
