#!/usr/bin/env bash
# Runs every shipped scenario (scenarios/*.yaml, scenarios/ci/*.yaml) with its own controller
# and with nonhybrid_mpc, and compares each metrics.json, timing fields aside, with the copy
# recorded in ci/metrics_recorded/. A refactor that must not change behaviour passes this.
#   ci/same_metrics.sh            compare (exit 1 on any difference, printing it)
#   ci/same_metrics.sh --record   overwrite the recorded copies
# HPA_RUN_ARGS adds arguments to every run (e.g. HPA_RUN_ARGS="--set world.profile=ideal").
set -euo pipefail
cd "$(dirname "$0")/.."
hpa=${HPA_BUILD_DIR:-build}/bin/hpa
recorded=ci/metrics_recorded
record=false
[ "${1:-}" = "--record" ] && record=true
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
jobs=()
for f in scenarios/*.yaml scenarios/ci/*.yaml; do
  name=$(echo "$f" | sed 's|scenarios/||; s|/|_|g; s|\.yaml$||')
  jobs+=("$f $name default")
  jobs+=("$f ${name}__nonhybrid_mpc nonhybrid_mpc")
done
run_one() {
  set -- $1
  local extra=()
  [ "$3" != default ] && extra=(--controller "$3")
  # shellcheck disable=SC2086
  "$hpa" run "$1" --out "$out/$2" --quiet "${extra[@]}" ${HPA_RUN_ARGS:-} > "$out/$2.log" 2>&1 \
    || true
  [ -f "$out/$2/metrics.json" ] || { echo "no metrics for $2:"; cat "$out/$2.log"; }
}
export -f run_one; export hpa out HPA_RUN_ARGS
printf '%s\n' "${jobs[@]}" | xargs -P "$(nproc)" -I{} bash -c 'run_one "{}"'
mkdir -p "$recorded"
args=()
for j in "${jobs[@]}"; do set -- $j; args+=("$2"); done
# Timing fields measure the machine, not the behaviour; numbers are compared to 1e-7 relative
# (metrics.json writes 9 significant digits); keys added since the recording are listed, not
# failed (extend, never rename).
python3 - "$out" "$recorded" "$record" "${args[@]}" <<'PY'
import json, math, sys
out, recorded, record, names = sys.argv[1], sys.argv[2], sys.argv[3] == "true", sys.argv[4:]
timing = {"wall_time_s", "mpc_solve_ms", "render_ms", "detector_ms", "image_model_ms"}
def load(path):
    m = json.load(open(path))
    return {k: v for k, v in m.items() if k not in timing}
def diff(a, b, path, errs, added):
    if isinstance(a, dict) and isinstance(b, dict):
        for k in b:
            if k not in a: errs.append(f"{path}{k}: missing (recorded {b[k]!r})")
            else: diff(a[k], b[k], f"{path}{k}.", errs, added)
        for k in a:
            if k not in b: added.append(f"{path}{k}")
    elif isinstance(a, list) and isinstance(b, list) and len(a) == len(b):
        for i, (x, y) in enumerate(zip(a, b)): diff(x, y, f"{path}{i}.", errs, added)
    elif isinstance(a, (int, float)) and isinstance(b, (int, float)) and not isinstance(a, bool):
        if not (a == b or abs(a - b) <= 1e-7 * max(abs(a), abs(b)) + 1e-12):
            errs.append(f"{path[:-1]}: {a!r} (recorded {b!r})")
    elif a != b:
        errs.append(f"{path[:-1]}: {a!r} (recorded {b!r})")
status = 0
added_all = set()
for n in names:
    try:
        got = load(f"{out}/{n}/metrics.json")
    except Exception as e:
        print(f"{n}: no metrics ({e})"); status = 1; continue
    if record:
        json.dump(got, open(f"{recorded}/{n}.json", "w"), indent=1, sort_keys=True); continue
    errs, added = [], []
    diff(got, load(f"{recorded}/{n}.json"), "", errs, added)
    added_all.update(added)
    if errs:
        status = 1
        print(f"CHANGED {n}:"); [print("   ", e) for e in errs]
if record: print(f"recorded {len(names)} metrics files in {recorded}")
elif status == 0: print(f"all {len(names)} runs give the recorded metrics")
if added_all: print("keys added since the recording:", ", ".join(sorted(added_all)))
sys.exit(status)
PY
