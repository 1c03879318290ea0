#!/usr/bin/env bash
# The paper's section VI-B2 finding as a Monte Carlo regression: over the impulse sweep
# (scenarios/sweeps/impulse_crash_rate.yaml, flight profile, 40 paired draws of a vertical push
# of 0.1-2.5 N s), hpa_mpc crashes less often than the non-hybrid baseline, and the paired
# comparison never finds hpa_mpc worse. Measured: hpa_mpc 3 of 40, nonhybrid_mpc 7 of 40 (McNemar
# p = 0.125: the ordering holds, not yet significant at 40 pairs). Bound: hpa_mpc at most 4 crashes
# (one more than measured) and fewer than the baseline.
set -u
hpa="$1"; scen="$2"; out="$3"
rm -rf "$out"; mkdir -p "$out"
fail() { echo "FAIL: $*"; exit 1; }

"$hpa" sweep "$scen/sweeps/impulse_crash_rate.yaml" --out "$out/sweep" --jobs 2 \
  > "$out/sweep.log" 2>&1 || fail "sweep failed: $(tail -5 "$out/sweep.log")"
"$hpa" sweep-diff "$out/sweep" "$out/sweep" --a-where controller.type=nonhybrid_mpc \
  --b-where controller.type=hpa_mpc --out "$out/diff" > "$out/diff.log" 2>&1 \
  || fail "sweep-diff failed: $(cat "$out/diff.log")"
cat "$out/diff.log"
python3 - "$out/sweep/summary.json" "$out/diff/diff.json" <<'PY' || fail "impulse finding does not hold"
import json, sys
summary = json.load(open(sys.argv[1]))
diff = json.load(open(sys.argv[2]))
crashes = {c: sum(b["crashes"] for b in v["bins"]) for c, v in summary["controllers"].items()}
runs = {c: sum(b["runs"] for b in v["bins"]) for c, v in summary["controllers"].items()}
print("crashes:", {c: f"{crashes[c]} of {runs[c]}" for c in crashes})
assert runs["hpa_mpc"] == runs["nonhybrid_mpc"] == 40, runs
assert crashes["hpa_mpc"] <= 4, f"hpa_mpc crashed {crashes['hpa_mpc']} times (measured 3)"
assert crashes["hpa_mpc"] < crashes["nonhybrid_mpc"], crashes
assert diff["metrics"]["crash_rate"]["verdict"] != "worse", diff["metrics"]["crash_rate"]
PY
echo "impulse finding: holds"
