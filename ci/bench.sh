#!/usr/bin/env bash
# Speed figures of this tree, side by side with a reference commit built the same way and
# measured in the same run (each figure alternates between the two builds, REPS times, and the
# table gives medians and the ratio this / reference), because these machines are shared and
# noisy: only ratios measured together compare.
#
#   ci/bench.sh [--ref COMMIT] [--reps N] [--out DIR] [--build DIR]
#
# Figures: mpc_bench (RTI step, step Jacobians, condensing + QP), sim_bench (world step, payload
# camera render of the whole frame and of the region around the payload, the camera image model
# on such a region; a figure a build does not have shows as -), the closed loop's real-time
# factor with the analytic camera (scenarios/csv_reference.yaml) and the rendered one
# (scenarios/hover_gripper_pull.yaml), each in process and through hpa-flight with the ratio of
# the two (the lockstep boundary's price), and sweep throughput with the rendered camera
# (scenarios/sweeps/throughput_render.yaml, --jobs 2).
# Writes DIR/bench.md (default out/bench) and prints it. Without --ref, this tree alone. --build
# builds this tree into DIR instead of build/ (a build directory of one's own on a shared tree).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
ref="" reps=3 out=out/bench build_dir=""
while [ $# -gt 0 ]; do
  case $1 in
    --ref) ref=$2; shift 2 ;;
    --reps) reps=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --build) build_dir=$2; shift 2 ;;
    -h|--help) sed -n '2,18p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "ci/bench.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
mkdir -p "$out"
out=$(cd "$out" && pwd)
launcher=()
command -v ccache > /dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)

# the build directory of the tree at $1: $1/build, or --build's for this tree
build_of() {
  if [ "$1" = "$root" ] && [ -n "$build_dir" ]; then echo "$build_dir"; else echo "$1/build"; fi
}

# builds the benchmarks and hpa of the tree at $1 into its build directory
build_tree() {
  local b
  b=$(build_of "$1")
  cmake -S "$1" -B "$b" -G Ninja -DCMAKE_BUILD_TYPE=Release -DHPA_BUILD_BENCHMARKS=ON "${launcher[@]}" \
    > /dev/null
  cmake --build "$b" -j "$(nproc)" --target hpa hpa-flight mpc_bench sim_bench > /dev/null
}

sides=(this)
trees=("$root")
echo "== building this tree"
build_tree "$root"
if [ -n "$ref" ]; then
  ref_dir=$root/.bench-ref
  if [ ! -d "$ref_dir" ]; then git worktree add --detach -q "$ref_dir" "$ref"; fi
  git -C "$ref_dir" checkout -q --detach "$ref"
  echo "== building the reference $(git -C "$ref_dir" rev-parse --short HEAD)"
  build_tree "$ref_dir"
  sides+=(ref)
  trees+=("$ref_dir")
fi

# the binary $2 of tree $1 (the build layout may put it in bin/ or its folder)
binary() {
  local b
  b=$(find "$(build_of "$1")" -type f -name "$2" -perm -u+x | head -1)
  [ -n "$b" ] || { echo "ci/bench.sh: no $2 in $(build_of "$1")" >&2; exit 1; }
  echo "$b"
}

raw=$out/raw.jsonl
: > "$raw"
for ((rep = 1; rep <= reps; ++rep)); do
  for i in "${!sides[@]}"; do
    side=${sides[$i]} tree=${trees[$i]}
    echo "== rep $rep/$reps: $side"
    hpa=$(binary "$tree" hpa)
    "$(binary "$tree" mpc_bench)" --benchmark_filter='BM_HpaMpcRtiStep$|BM_StepJacobians|BM_CondenseAndQp' \
      --benchmark_min_time=0.5 --benchmark_format=json 2> /dev/null |
      python3 -c 'import json,sys; [print(json.dumps({"side":sys.argv[1],"figure":b["name"],"value":b["real_time"],"unit":b["time_unit"]})) for b in json.load(sys.stdin)["benchmarks"]]' "$side" >> "$raw"
    "$(binary "$tree" sim_bench)" --benchmark_filter='BM_WorldStep|BM_RenderPayloadCamera|BM_CameraImageModelRegion' \
      --benchmark_format=json 2> /dev/null |
      python3 -c 'import json,sys; [print(json.dumps({"side":sys.argv[1],"figure":b["name"],"value":b["real_time"],"unit":b["time_unit"]})) for b in json.load(sys.stdin)["benchmarks"]]' "$side" >> "$raw"
    # each scenario in process and through hpa-flight, one after the other (the boundary's
    # price is their ratio, measured side by side)
    for scenario in csv_reference hover_gripper_pull; do
      for how in "" "through hpa-flight"; do
        run_dir=$out/$side/$scenario${how:+_flight}
        stack=()
        [ -n "$how" ] && stack=(--flight-stack "$(binary "$tree" hpa-flight)")
        (cd "$tree" && "$hpa" run "scenarios/$scenario.yaml" --out "$run_dir" --quiet "${stack[@]}" > /dev/null) || true
        python3 -c 'import json,sys; m=json.load(open(sys.argv[2])); print(json.dumps({"side":sys.argv[1],"figure":"real-time factor, "+sys.argv[3],"value":m["sim_time_s"]/m["wall_time_s"],"unit":"x"}))' \
          "$side" "$run_dir/metrics.json" "$scenario${how:+ $how}" >> "$raw"
      done
    done
    sweep_dir=$out/$side/throughput_render
    rm -rf "$sweep_dir"
    start=$(date +%s.%N)
    # both builds fly this tree's sweep file (the same runs, however the reference's file reads)
    (cd "$tree" && "$hpa" sweep "$root/scenarios/sweeps/throughput_render.yaml" --out "$sweep_dir" --jobs 2 > /dev/null) || true
    end=$(date +%s.%N)
    runs=$(wc -l < "$sweep_dir/runs.jsonl")
    python3 -c 'import json,sys; print(json.dumps({"side":sys.argv[1],"figure":"rendered sweep, --jobs 2","value":float(sys.argv[2])*60/(float(sys.argv[4])-float(sys.argv[3])),"unit":"runs/min"}))' \
      "$side" "$runs" "$start" "$end" >> "$raw"
  done
done

python3 - "$raw" "$out/bench.md" "$(nproc)" "$(git rev-parse --short HEAD)" "${ref:-}" << 'PY'
import json, statistics, sys, platform
rows = [json.loads(l) for l in open(sys.argv[1])]
figures, units, values = [], {}, {}
for r in rows:
    if r["figure"] not in figures:
        figures.append(r["figure"])
    units[r["figure"]] = r["unit"]
    values.setdefault((r["figure"], r["side"]), []).append(r["value"])
has_ref = any(side == "ref" for _, side in values)
cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), "?")
lines = [f"Machine: {cpu}, {sys.argv[3]} cores; this tree {sys.argv[4]}"
         + (f", reference {sys.argv[5]}" if has_ref else "") + "; medians of "
         + str(max(len(v) for v in values.values())) + " (ci/bench.sh).", ""]
head = "| figure | unit | this tree |" + (" reference | this / reference |" if has_ref else "")
lines += [head, "|---|---|---|" + ("---|---|" if has_ref else "")]
def median(f, side):
    return statistics.median(values[(f, side)]) if (f, side) in values else None
def text(v):
    return "-" if v is None else f"{v:.4g}"
for f in figures:
    this = median(f, "this")
    row = f"| {f} | {units[f]} | {text(this)} |"
    if has_ref:
        ref = median(f, "ref")
        ratio = "-" if this is None or ref is None else f"{this / ref:.2f}"
        row += f" {text(ref)} | {ratio} |"
    lines.append(row)
# the boundary's price: each scenario's real-time factor through hpa-flight over in process
# (medians of the runs alternated with it; >= 0.5 is the goal)
boundary = []
for f in figures:
    if f.endswith(" through hpa-flight"):
        base = f[: -len(" through hpa-flight")]
        for side in ("this", "ref"):
            a, b = median(f, side), median(base, side)
            if a is not None and b:
                boundary.append(f"- {base.split(', ', 1)[1]} ({side}): through hpa-flight / in "
                                f"process = {a / b:.2f}")
if boundary:
    lines += ["", "The boundary's price (real-time factor through hpa-flight over in process):"]
    lines += boundary
open(sys.argv[2], "w").write("\n".join(lines) + "\n")
print("\n".join(lines))
PY
