#!/usr/bin/env bash
# The paper's section VI-C finding, on the shipped path and moved 1.5 times as fast: with L_cam
# (perception weight 1) hpa_mpc keeps the held payload in view at least 0.99 of the time on
# seeds 1-3 (rendered camera), and without it (weight 0) clearly less.
# Bounds: 0.99 is the finding's own threshold. "Clearly less": without L_cam at least 0.18 below
# with it on the same seed, half the smallest difference measured on seeds 1-3 and 44-46
# (0.36: docs/results.md, "Person moves the payload"), so a term that lost half its effect
# fails. Seeds 4-30 are the scenario files' bounds (scripts/scenario_bounds.py).
set -u
hpa="$1"; scen="$2"; out="$3"
rm -rf "$out"; mkdir -p "$out"
fail() { echo "FAIL: $*"; exit 1; }

# each seed's pair of runs side by side (2 cores)
for file in person_moves_payload ci/person_moves_payload_fast; do
  for seed in 1 2 3; do
    for weight in 1 0; do
      name="$(basename "$file")_${seed}_${weight}"
      "$hpa" run "$scen/$file.yaml" --seed "$seed" --set controller.perception_weight="$weight" \
        --out "$out/$name" --quiet > "$out/$name.log" 2>&1 &
    done
    wait
  done
done
python3 - "$out" <<'PY' || fail "the perception finding does not hold"
import json, os, sys
out = sys.argv[1]
bad = []
for name in ("person_moves_payload", "person_moves_payload_fast"):
    for seed in (1, 2, 3):
        fov = {}
        for weight in (1, 0):
            path = os.path.join(out, f"{name}_{seed}_{weight}", "metrics.json")
            if not os.path.exists(path):
                bad.append(f"{name} seed {seed} weight {weight}: no metrics.json")
                continue
            m = json.load(open(path))
            if m["crashed"]:
                bad.append(f"{name} seed {seed} weight {weight} crashed: {m['crash_reason']}")
            fov[weight] = m["payload_in_fov_fraction"]
        if len(fov) < 2:
            continue
        print(f"{name} seed {seed}: in view {fov[1]:.3f} with L_cam, {fov[0]:.3f} without")
        if not fov[1] >= 0.99:
            bad.append(f"{name} seed {seed}: in view {fov[1]:.3f} with L_cam, below 0.99")
        if not fov[0] <= fov[1] - 0.18:
            bad.append(f"{name} seed {seed}: in view {fov[0]:.3f} without L_cam, not 0.18 below "
                       f"{fov[1]:.3f} with it")
assert not bad, "\n".join(bad)
PY
echo "perception finding holds"
