#!/usr/bin/env bash
# The README's "your controller against hpa_mpc" commands, as written there: the block from its
# `P="python3 ...` line to its `hpa sweep-diff` line is taken from README.md and run from the
# source folder, with $B the build's bin folder, python3 the one with numpy, and out/ a fresh
# folder. Checks: every command succeeds, the comparison has both controllers labelled by what
# flew, both sweeps have their 20 runs, and the diff names hpa_mpc against the Python stack; and
# the basis: every run of the compare and of both sweeps flew on estimates with the analytic
# camera (metrics.json's camera), as the README says, and the diff names no difference in it,
# while the same sweep on the true state diffed against the stack's names it with a warning.
# usage: readme_your_controller_test.sh HPA_BIN SOURCE_DIR PYTHON OUT_DIR
set -uo pipefail
hpa=$1; src=$2; python=$3; out=$4
rm -rf "$out"; mkdir -p "$out"
# shellcheck source=cli_test_lib.sh
source "$(dirname "$0")/cli_test_lib.sh"

block=$(sed -n '/^P="python3 /,/hpa sweep-diff /p' "$src/README.md")
[ -n "$block" ] || { echo "FAIL: README.md has no block from P=\"python3 to hpa sweep-diff"; exit 1; }
[ "$(grep -c 'hpa ' <<< "$block")" -eq 4 ] || fail "expected 4 hpa commands in the block: $block"
script=$out/block.sh
{
  echo "set -euo pipefail"
  echo "B=$(dirname "$hpa")"
  sed -e "s|^P=\"python3 |P=\"$python |" -e "s| out/| $out/|g" <<< "$block"
} > "$script"
(cd "$src" && bash "$script") > "$out/block.log" 2>&1 || fail "the README block failed: $(tail -5 "$out/block.log")"

"$python" - "$out" <<'PY' || fail "the README block's outputs"
import json, sys
out = sys.argv[1]
labels = sorted(json.load(open(f"{out}/cmp/{name}/metrics.json"))["controller"]
                for name in ("hpa_mpc", "mine"))
assert labels == ["hpa_mpc", "python hover_controller"], labels
for name in ("wind_hpa_mpc", "wind_mine"):
    runs = [json.loads(line) for line in open(f"{out}/{name}/runs.jsonl")]
    assert len(runs) == 20 and all(r["status"] == "ok" for r in runs), (name, len(runs))
diff = open(f"{out}/wind_diff/diff.md").read()
assert "hpa_mpc" in diff and "python hover_controller" in diff, diff[:400]
# the basis: both sides on estimates, the same camera, in every run, and the diff agrees
cameras = {json.load(open(f"{out}/cmp/{name}/metrics.json"))["camera"] for name in ("hpa_mpc", "mine")}
for name in ("wind_hpa_mpc", "wind_mine"):
    cameras |= {json.loads(line)["metrics"]["camera"] for line in open(f"{out}/{name}/runs.jsonl")}
assert cameras == {"analytic"}, cameras
differs = json.load(open(f"{out}/wind_diff/diff.json"))["differs"]
assert not any(d.startswith("estimation basis") for d in differs), differs
print("README block: compare labels %s, 2 x 20 sweep runs, diff names both, all on estimates "
      "with the analytic camera" % labels)
PY
# the README's comparison before it was fair: hpa_mpc on hover_wind as the file says (on the true
# state) against the Python stack on estimates; sweep-diff names the difference with a warning
"$hpa" sweep "$src/scenarios/sweeps/hover_wind.yaml" --out "$out/wind_truth" > "$out/truth.log" 2>&1 ||
  fail "hover_wind on the truth: $(tail -3 "$out/truth.log")"
"$hpa" sweep-diff "$out/wind_truth" "$out/wind_mine" --out "$out/unfair_diff" > "$out/unfair.log" 2>&1 ||
  fail "sweep-diff of the unfair pairing: $(tail -3 "$out/unfair.log")"
grep -q "estimation basis: ground truth (A) vs estimate, analytic camera (B), in 20 of 20 pairs: WARNING" \
  "$out/unfair_diff/diff.md" || fail "the unfair pairing's diff.md does not name the basis: $(head -12 "$out/unfair_diff/diff.md")"
grep -q "estimation basis" "$out/unfair.log" || fail "the console does not name the basis"
[ "$failures" -eq 0 ] || { echo "$failures failure(s)"; exit 1; }
echo "the README's your-controller commands run as written"
