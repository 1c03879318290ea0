#!/usr/bin/env bash
# Measures what golden's tolerance must absorb between compilers: builds hpa with clang in
# build-clang/ (Release, as CI's gcc build), flies every golden scenario with it, and compares
# with the gcc recording in scenarios/ci/golden.json, first as `hpa golden` does (default
# tolerance; the scenarios under tolerances.build_sensitive not compared), then every scenario
# with no tolerance: the largest relative difference of each, and its key. A developer tool
# (about 10 min on 2 cores).   ci/golden_compilers.sh
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build-clang -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER=clang++ \
  -DHPA_BUILD_TESTS=OFF -DHPA_BUILD_BENCHMARKS=OFF > build-clang.configure.log
cmake --build build-clang --target hpa hpa_media
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for f in scenarios/*.yaml scenarios/ci/*.yaml; do
  name=${f#scenarios/}; name=${name%.yaml}
  build-clang/bin/hpa run "$f" --quiet --out "$out/${name//\//_}" > /dev/null 2>&1 || true
done
echo "== as hpa golden compares (default tolerance, build-sensitive scenarios not compared)"
build-clang/bin/hpa golden --from "$out" || true
echo "== every scenario, no tolerance: the largest relative difference and where"
/usr/bin/python3 - "$out" <<'PY'
import json, sys
golden = json.load(open("scenarios/ci/golden.json"))
machine = {"build", "wall_time_s", "mpc_solve_ms", "render_ms", "detector_ms", "image_model_ms"}
def diffs(a, b, path, out):
    if isinstance(a, dict) and isinstance(b, dict):
        for k in a:
            if k in b and not (path == "" and k in machine):
                diffs(a[k], b[k], path + "." + k if path else k, out)
    elif isinstance(a, list) and isinstance(b, list):
        for i, (x, y) in enumerate(zip(a, b)):
            diffs(x, y, f"{path}.{i}", out)
    elif a != b:
        num = all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in (a, b))
        rel = abs(a - b) / max(abs(a), abs(b)) if num else float("inf")
        out.append((rel, path, a, b))
for name, recorded in sorted(golden["scenarios"].items()):
    now = json.load(open(f"{sys.argv[1]}/{name.replace('/', '_')}/metrics.json"))
    found = []
    diffs(recorded, now, "", found)
    worst = max(found, default=None)
    print(f"{name}: " + ("bit for bit" if worst is None else
          f"{len(found)} values differ, worst {worst[1]} {worst[2]} (gcc) vs {worst[3]} (clang), "
          f"relative {worst[0]:.3g}"))
PY
