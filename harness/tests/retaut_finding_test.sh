#!/usr/bin/env bash
# The paper's section VI-B2 finding on the re-taut, paired: `hpa compare` flies line_impulse
# (flight profile, rendered camera, seed 1) with hpa_mpc predicting the re-taut in its horizon
# (controller.predict_retaut; the setting is hybrid-only, so nonhybrid_mpc flies as the paper's
# baseline) and with nonhybrid_mpc. hpa_mpc must meet the re-taut with a smaller |v_z| and a
# smaller peak body rate than the baseline.
# Measured (ci/paper_comparison.sh, seeds 1/2/3): hpa_mpc + predict_retaut v_z -0.23 / -0.23 /
# -0.21 m/s, peak body rate 0.16 / 0.23 / 0.16 rad/s; nonhybrid_mpc -0.51 / -0.75 / -0.32 m/s,
# 0.61 / 2.10 / 0.89 rad/s. Regression bounds on hpa_mpc's own figures: the seed-1 measurement
# times 1.3 (v_z >= -0.30 m/s, body rate <= 0.21 rad/s), so a 50 % regression fails.
# Without the prediction (the paper's form) hpa_mpc's figures are -0.46 m/s and 0.60 rad/s at
# seed 1: v_z below the baseline's on two seeds of three, the body rate on none clearly; the
# README reports it.
set -u
hpa="$1"; scen="$2"; out="$3"
rm -rf "$out"; mkdir -p "$out"
fail() { echo "FAIL: $*"; exit 1; }

"$hpa" compare "$scen/line_impulse.yaml" --seed 1 --set controller.predict_retaut=true \
  --controllers hpa_mpc,nonhybrid_mpc --out "$out" --quiet > "$out/compare.log" 2>&1
[ -f "$out/hpa_mpc/metrics.json" ] && [ -f "$out/nonhybrid_mpc/metrics.json" ] \
  || fail "compare wrote no metrics: $(tail -5 "$out/compare.log")"
cat "$out/comparison.md" 2>/dev/null
python3 - "$out/hpa_mpc/metrics.json" "$out/nonhybrid_mpc/metrics.json" <<'PY' \
  || fail "re-taut finding does not hold"
import json, sys
hpa, base = (json.load(open(p)) for p in sys.argv[1:3])
for name, m in (("hpa_mpc", hpa), ("nonhybrid_mpc", base)):
    assert not m["crashed"], f"{name} crashed: {m['crash_reason']}"
    assert m["retaut"]["count"] >= 1, f"{name}: no re-taut"
h, b = hpa["retaut"], base["retaut"]
print(f"re-taut v_z min: hpa_mpc {h['quad_vz_min_mps']:.3f}, nonhybrid_mpc {b['quad_vz_min_mps']:.3f} m/s")
print(f"re-taut peak body rate: hpa_mpc {h['peak_body_rate_radps']:.3f}, "
      f"nonhybrid_mpc {b['peak_body_rate_radps']:.3f} rad/s")
assert abs(h["quad_vz_min_mps"]) < abs(b["quad_vz_min_mps"]), "|v_z| not below the baseline's"
assert h["peak_body_rate_radps"] < b["peak_body_rate_radps"], "body rate not below the baseline's"
assert h["quad_vz_min_mps"] >= -0.30, f"hpa_mpc v_z {h['quad_vz_min_mps']} (measured -0.23)"
assert h["peak_body_rate_radps"] <= 0.21, f"hpa_mpc rate {h['peak_body_rate_radps']} (measured 0.16)"
PY
echo "re-taut finding: holds"
