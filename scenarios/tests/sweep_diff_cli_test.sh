#!/usr/bin/env bash
# hpa sweep-diff end to end: a deliberate regression (perception weight 1.0 -> 0.3 on
# person_moves_payload) is found worse on payload_in_fov_fraction; a sweep compared with itself
# shows no difference on any metric; sweeps that do not pair are refused with exit 2.
# usage: sweep_diff_cli_test.sh HPA_BIN SCENARIOS_DIR OUT_DIR
set -uo pipefail
hpa=$1; scen=$2; out=$3
rm -rf "$out"; mkdir -p "$out"
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }
verdict() { python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['metrics'][sys.argv[2]]['verdict'])" "$@"; }

"$hpa" sweep "$scen/sweeps/perception_weight_regression.yaml" --out "$out/pw" --jobs 2 \
  > "$out/pw.log" 2>&1 || fail "sweep failed: $(tail -3 "$out/pw.log")"

echo "== the deliberate regression is detected"
"$hpa" sweep-diff "$out/pw" "$out/pw" --a-where controller.perception_weight=1.0 \
  --b-where controller.perception_weight=0.3 --out "$out/regression" > "$out/regression.log" 2>&1 \
  || fail "sweep-diff failed: $(cat "$out/regression.log")"
[ "$(verdict "$out/regression/diff.json" payload_in_fov_fraction)" = worse ] \
  || fail "lower perception weight not found worse on payload_in_fov_fraction: $(cat "$out/regression.log")"
grep -q "controller.perception_weight: 1.0 (A) vs 0.3 (B)" "$out/regression.log" \
  || fail "sweep-diff does not name the setting that differs"
python3 -c "import json,sys; d=json.load(open(sys.argv[1])); assert d['runs_paired'] == 20, d['runs_paired']" \
  "$out/regression/diff.json" || fail "expected 20 pairs"
for f in diff.md diff.json diff.png; do [ -s "$out/regression/$f" ] || fail "no $f written"; done

echo "== a sweep against itself: no difference anywhere"
"$hpa" sweep-diff "$out/pw" "$out/pw" --out "$out/same" > "$out/same.log" 2>&1 || fail "self diff failed"
python3 - "$out/same/diff.json" <<'PY' || fail "self comparison is not 'same' everywhere"
import json, sys
d = json.load(open(sys.argv[1]))
assert d["runs_paired"] == 40, d["runs_paired"]
bad = {k: m["verdict"] for k, m in d["metrics"].items() if m["verdict"] != "same" or m["difference"] not in (0, None)}
assert not bad, bad
assert "crash_rate" in d["metrics"]
PY

echo "== sweeps that do not pair are refused"
"$hpa" sweep-diff "$out/pw" "$out/pw" --a-where controller.perception_weight=1.0 --out "$out/unpaired" \
  > "$out/unpaired.log" 2>&1
[ $? -eq 2 ] || fail "20 runs against 40 did not exit 2"
grep -q "no partner\|do not pair\|same draw, seed" "$out/unpaired.log" || fail "no pairing message: $(cat "$out/unpaired.log")"

[ $failures -eq 0 ] && echo "sweep-diff: all checks passed"
exit $((failures > 0))
