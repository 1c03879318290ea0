#!/usr/bin/env bash
# The README's "your controller against hpa_mpc" commands, as written there: the block from its
# `P="python3 ...` line to its `hpa sweep-diff` line is taken from README.md and run from the
# source folder, with $B the build's bin folder, python3 the one with numpy, and out/ a fresh
# folder. Checks: every command succeeds, the comparison has both controllers labelled by what
# flew, both sweeps have their 20 runs, and the diff names hpa_mpc against the Python stack.
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
print("README block: compare labels %s, 2 x 20 sweep runs, diff names both" % labels)
PY
[ "$failures" -eq 0 ] || { echo "$failures failure(s)"; exit 1; }
echo "the README's your-controller commands run as written"
