#!/usr/bin/env bash
# The team controllers side by side (docs/cooperative.md): RotorTM's cooperative controller and
# the per-vehicle hpa_mpc baseline on every team scenario (scenarios/ci/team*.yaml), seeds 1-SEEDS
# each, motion capture as shipped. Writes DIR/team_comparison.md: crashes, the payload's RMSE
# (norm of the per-axis RMSE) range, and the medians of the vehicles' largest tilt, the payload's
# tilt, the slackest cable's slack time, the largest cable tension and the update time.
# A developer tool (under a minute with SEEDS=10 on 2 cores), not a CI step:
#   ci/team_comparison.sh DIR [SEEDS]
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:?usage: ci/team_comparison.sh DIR [SEEDS]}
seeds=${2:-10}
hpa=${HPA_BUILD_DIR:-build}/bin/hpa
mkdir -p "$out"
# every team scenario once (team3_lift_hpa_mpc is team3_lift with the baseline already flown here)
scenarios=$(ls scenarios/ci/team*.yaml | grep -v '_hpa_mpc\.yaml$')
for file in $scenarios; do
  name=$(basename "$file" .yaml)
  for controller in cooperative hpa_mpc; do
    for seed in $(seq 1 "$seeds"); do
      "$hpa" run "$file" --controller "$controller" --seed "$seed" \
        --out "$out/$name/$controller/seed$seed" --quiet > /dev/null || true
    done
  done
done
/usr/bin/python3 - "$out" "$seeds" $scenarios << 'PY'
import json, statistics, sys, os
out, seeds, files = sys.argv[1], int(sys.argv[2]), sys.argv[3:]
lines = ["| scenario | controller | crashes | payload RMSE [m] | vehicle tilt max [deg] | "
         "payload tilt max [deg] | slack [s] | tension max [N] | update [ms] |",
         "|---|---|---|---|---|---|---|---|---|"]
for f in files:
    name = os.path.basename(f)[:-5]
    for c in ("cooperative", "hpa_mpc"):
        ms = [json.load(open(f"{out}/{name}/{c}/seed{s}/metrics.json")) for s in range(1, seeds + 1)]
        ok = [m for m in ms if not m["crashed"] and m["payload_rmse_m"]]
        rmse = [sum(x * x for x in m["payload_rmse_m"]) ** 0.5 for m in ok]
        med = lambda f: statistics.median(f(m) for m in ok) if ok else float("nan")
        worst = lambda m, k: max(v[k] for v in m["team"]["vehicles"])
        lines.append(
            f"| {name} | {c} | {sum(m['crashed'] for m in ms)}/{len(ms)} | "
            f"{min(rmse):.4f}-{max(rmse):.4f} | {med(lambda m: worst(m, 'tilt_max_deg')):.1f} | "
            f"{med(lambda m: m['team']['payload_tilt_max_deg']):.2f} | "
            f"{med(lambda m: worst(m, 'slack_time_s')):.2f} | "
            f"{med(lambda m: worst(m, 'cable_tension_max_N')):.2f} | "
            f"{med(lambda m: m['mpc_solve_ms']['median']):.4f} |")
text = "\n".join(lines) + "\n"
open(f"{out}/team_comparison.md", "w").write(text)
print(text, end="")
PY
