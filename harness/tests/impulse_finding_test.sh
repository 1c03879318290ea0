#!/usr/bin/env bash
# The paper's section VI-B2 finding as a Monte Carlo regression: over the impulse sweep
# (scenarios/sweeps/impulse_crash_rate.yaml, flight profile, 40 paired draws of a vertical push
# of 0.1-2.5 N s), hpa_mpc's crash rate is not above the non-hybrid baseline's: its Wilson 95 %
# interval does not lie above the baseline's, and the paired comparison (hpa sweep-diff, exact
# McNemar) does not find it worse.
# Measured on this sweep: hpa_mpc 2 of 40 crashes, nonhybrid_mpc 1 of 40 (McNemar p = 1);
# hpa_mpc's are the payload striking the body at 15-23 m/s, which tumbles the vehicle within
# 0.12 s whichever controller flies. The paper's ordering (the baseline crashing more) does not
# show: with 100 draws (ci/paper_comparison.sh) 3 against 2. Crash counts this small are chaotic
# (a change moving no shipped scenario by 0.1 % once moved hpa_mpc between 2 and 4 of 40).
# Regression bounds: no bound on the crash count itself (chaotic, above); the crash rate's Wilson
# 95 % interval must reach below 10 % (measured 2 of 40: interval 0.014-0.165; 4 of 40 still
# passes, 8 of 40 fails), and the median quadrotor deviation, which is not chaotic, carries the
# tight bound: at most 1.3 x the measured 0.250 m.
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
controllers = json.load(open(sys.argv[1]))["controllers"]
diff = json.load(open(sys.argv[2]))
hpa, base = controllers["hpa_mpc"], controllers["nonhybrid_mpc"]
print("crashes:", {c: f"{v['crashes']} of {v['runs']}" for c, v in controllers.items()})
assert hpa["runs"] == base["runs"] == 40, (hpa["runs"], base["runs"])
# crash_rate_ci95: the sweep summary's Wilson 95 % interval
print(f"Wilson 95 %: hpa_mpc {hpa['crash_rate_ci95']}, nonhybrid_mpc {base['crash_rate_ci95']}")
assert hpa["crash_rate_ci95"][0] <= base["crash_rate_ci95"][1], \
    "hpa_mpc's crash rate interval lies above the baseline's"
assert diff["metrics"]["crash_rate"]["verdict"] != "worse", diff["metrics"]["crash_rate"]
assert hpa["crash_rate_ci95"][0] <= 0.10, \
    f"hpa_mpc crashed {hpa['crashes']} of 40 (measured 2): its rate is above 10 % at 95 %"
deviation = hpa["quad_deviation_max_m"]["median"]
print(f"hpa_mpc median quadrotor deviation {deviation:.3f} m (measured 0.250)")
assert deviation <= 1.3 * 0.250, deviation
PY
echo "impulse finding: holds"
