#!/usr/bin/env bash
# What a failed or cut-short output leaves is never mistaken for a result:
# a. a file-size limit (ulimit -f) is a full disk: hpa is not killed by SIGXFSZ but exits 4
#    naming the file and the limit, with no partial file, no metrics.json, and a sweep's
#    runs.jsonl ending in its last whole record (a resume without the limit finishes it);
# b. hpa golden (--quiet or not) names every scenario it cannot compare (missing from the
#    golden file) instead of counting it as changed;
# c. sweep-diff reads a runs.jsonl with a torn last line as --resume repairs it: the line left
#    out with a note naming the same byte count, the folder unchanged;
# d. after --resume --allow-changed-inputs, inputs.json keeps the first inputs and adds the
#    changed ones under `resumed`.
# usage: output_leftovers_test.sh HPA_BIN SOURCE_DIR PYTHON
source "$(dirname "$0")/cli_test_lib.sh"
cli_test_start "$@"
hover=$src/scenarios/hover.yaml

# no_partials DIR LABEL: no file under DIR has a partial name
no_partials() {
  local left; left=$(find "$1" -name '*.partial*')
  [ -z "$left" ] || fail "$2: partial files left: $left"
}

# a. the file-size limit: run.json (2 KiB), then log.csv (20 KiB), then a sweep's runs.jsonl
(ulimit -f 1; "$hpa" run "$hover" --set duration=1 --set events.0.at=0.5 --out "$out/fsz1" --quiet) > "$out/fsz1.log" 2>&1
status=$?
[ "$status" -eq 4 ] || fail "ulimit -f 1: hpa run exited $status, expected 4: $(cat "$out/fsz1.log")"
grep -q "run.json: File too large: the file-size limit (ulimit -f)" "$out/fsz1.log" \
  || fail "ulimit -f 1: message: $(cat "$out/fsz1.log")"
(ulimit -f 20; "$hpa" run "$hover" --set duration=1 --set events.0.at=0.5 --out "$out/fsz20" --quiet) > "$out/fsz20.log" 2>&1
status=$?
[ "$status" -eq 4 ] || fail "ulimit -f 20: hpa run exited $status, expected 4: $(cat "$out/fsz20.log")"
grep -q "cannot write .*log.csv.*the file-size limit (ulimit -f)" "$out/fsz20.log" || fail "ulimit -f 20: $(cat "$out/fsz20.log")"
for d in fsz1 fsz20; do
  no_partials "$out/$d" "$d"
  [ -e "$out/$d/metrics.json" ] && fail "$d: a metrics.json after a failed write"
done
cat > "$out/fsz.yaml" <<YAML
base: $hover
runs: 12
seed: 3
vary:
  events.0.force.0: {uniform: [0.1, 0.3]}
YAML
sets=(--set duration=0.3 --set events.0.at=0.1)
(ulimit -f 12; "$hpa" sweep "$out/fsz.yaml" --out "$out/S" --jobs 2 "${sets[@]}") \
  > "$out/fszs.log" 2>&1
status=$?
[ "$status" -eq 4 ] || fail "ulimit -f 12: hpa sweep exited $status, expected 4: $(tail -3 "$out/fszs.log")"
grep -q "runs.jsonl: cannot append a run's record: .*the file-size limit" "$out/fszs.log" \
  || fail "the sweep's message: $(tail -2 "$out/fszs.log")"
[ "$(tail -c 1 "$out/S/runs.jsonl" | od -An -c | tr -d ' ')" = '\n' ] \
  || fail "runs.jsonl does not end with a whole record"
no_partials "$out/S" "the sweep"
"$hpa" sweep "$out/fsz.yaml" --out "$out/S" --jobs 2 "${sets[@]}" --resume > "$out/res.log" 2>&1 \
  || fail "the resume without the limit: $(tail -3 "$out/res.log")"
[ "$(grep -c . "$out/S/runs.jsonl")" -eq 12 ] || fail "the resumed sweep has not 12 records"

# c. a torn last line: B is A's records and the first 200 bytes of one more
cp -r "$out/S" "$out/B"
head -c 200 "$out/S/runs.jsonl" >> "$out/B/runs.jsonl"
cp "$out/B/runs.jsonl" "$out/B.before"
expect_exit 0 "12 paired runs" sweep-diff "$out/S" "$out/B" --out "$out/D"
text=$("$hpa" sweep-diff "$out/S" "$out/B" --out "$out/D" 2>&1 >/dev/null)
grep -q "B/runs.jsonl (B) ends in an unterminated line.*its last 200 bytes are left out" <<< "$text" \
  || fail "sweep-diff's note on the torn line: $text"
cmp -s "$out/B/runs.jsonl" "$out/B.before" || fail "sweep-diff changed B's runs.jsonl"
expect_exit 0 "dropped 200 bytes" sweep "$out/fsz.yaml" --out "$out/B" --resume "${sets[@]}"

# d. a resume with changed inputs: both parts' inputs in inputs.json
head -n 6 "$out/S/runs.jsonl" > "$out/part" && mv "$out/part" "$out/S/runs.jsonl"
"$hpa" sweep "$out/fsz.yaml" --out "$out/S" --jobs 2 --set duration=0.4 --set events.0.at=0.1 \
  --resume --allow-changed-inputs > "$out/changed.log" 2>&1 \
  || fail "--allow-changed-inputs: $(tail -3 "$out/changed.log")"
"$python" - "$out/S" <<'PY' || fail "inputs.json after --resume --allow-changed-inputs"
import json, sys
d = sys.argv[1]
records = [json.loads(line) for line in open(d + "/runs.jsonl")]
inputs = json.load(open(d + "/inputs.json"))
ids = {r.get("inputs_id") for r in records if "inputs_id" in r}
assert len(records) == 12 and len(ids) == 1, (len(records), ids)
assert inputs["sweep_id"] == records[0]["sweep_id"]
assert inputs["sets"] == [["duration", "0.3"], ["events.0.at", "0.1"]], inputs.get("sets")
[part] = inputs["resumed"]
assert part["inputs_id"] == ids.pop(), part["inputs_id"]
assert part["sets"] == [["duration", "0.4"], ["events.0.at", "0.1"]], part["sets"]
assert {f["role"] for f in part["files"]} >= {"sweep", "base", "params"}, part["files"]
PY

# b. golden: a golden file recorded from stand-in metrics, one scenario then removed from it
for f in "$src"/scenarios/*.yaml "$src"/scenarios/ci/*.yaml; do
  rel=${f#"$src"/scenarios/}; rel=${rel%.yaml}
  mkdir -p "$out/from/${rel//\//_}"
  echo '{"run_error": null, "expect": {"passed": true}, "crashed": false}' \
    > "$out/from/${rel//\//_}/metrics.json"
done
golden=$out/golden.json
echo '{"tolerances": {"default": {"rel": 1e-3}}}' > "$golden"
"$hpa" golden --golden "$golden" --from "$out/from" --update --reason test --quiet > /dev/null \
  || fail "recording the stand-in golden file"
"$python" - "$golden" <<'PY'
import json, sys
g = json.load(open(sys.argv[1]))
del g["scenarios"]["hover"], g["scenarios"]["ci/team2_line"]
json.dump(g, open(sys.argv[1], "w"))
PY
for quiet in --quiet ""; do
  expect_exit 1 "not in the golden file, not compared: ci/team2_line, hover" golden \
    --golden "$golden" --from "$out/from" $quiet
  expect_exit 1 "^hover: not in the golden file" golden --golden "$golden" --from "$out/from" $quiet
done

[ "$failures" -eq 0 ] && echo "output_leftovers: all checks passed"
exit $((failures > 0))
