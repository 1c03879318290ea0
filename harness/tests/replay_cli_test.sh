#!/usr/bin/env bash
# hpa replay: renders a finished run's video from DIR/log.csv and DIR/run.json without changing
# the run's files; works on a sweep's kept runs, on an hpa compare output (a video per
# controller) and on a csv-reference run whose CSV is gone,
# from another working directory; refuses bad input with exit 2 naming the file and key (a
# folder without run.json, an edited log, run.json values, FIFOs, --rate); exit 4 for a folder
# it cannot write; a stop by SIGINT / SIGTERM exits 130 / 143 within a frame, and a stopped or
# killed replay keeps the previous replay.mp4 whole.
# Usage: replay_cli_test.sh HPA_BINARY SOURCE_DIR
set -uo pipefail
hpa=$1
src=$2
source "$src/harness/tests/cli_test_lib.sh"
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

# (exit 1 allowed: the file's expect bounds are for its whole 8 s)
"$hpa" run "$src/scenarios/hover.yaml" --quiet --out "$out/run" --set duration=2.5 \
  --set events.0.at=1.0
[ -s "$out/run/metrics.json" ] && [ -s "$out/run/run.json" ] || fail "run"
before=$(md5sum "$out/run/metrics.json" "$out/run/log.csv")
expect_exit 0 "replay.mp4 \(76 frames" replay "$out/run"
[ -s "$out/run/replay.mp4" ] || fail "no replay.mp4"
[ "$before" = "$(md5sum "$out/run/metrics.json" "$out/run/log.csv")" ] \
  || fail "replay changed the run's files"
expect_exit 0 "other.mp4 \(38 frames" replay "$out/run" -o "$out/other.mp4" --rate 15
expect_exit 2 "run.json.*cannot read" replay "$out/nothing" --quiet
expect_exit 2 "expected a file name ending in .mp4" replay "$out/run" --quiet -o "$out/x.avi"

echo "== --rate: a number of frames per second in [1, 1000], NaN included (was exit 4)"
expect_exit 2 "--rate" replay "$out/run" --quiet --rate nan -o "$out/nan.mp4"
expect_exit 2 "--rate" replay "$out/run" --quiet --rate 0.5 -o "$out/slow.mp4"
[ -e "$out/nan.mp4" ] && fail "--rate nan wrote a file"

echo "== a folder that cannot be written is exit 4 (cannot write), not 2"
mkdir -p "$out/readonly"
chmod 755 "$out" "$out/run"
chmod 555 "$out/readonly"
if [ "$(id -u)" -eq 0 ]; then
  # root writes anywhere: check as an unprivileged user
  text=$(timeout 60 setpriv --reuid=65534 --regid=65534 --clear-groups "$hpa" replay "$out/run" \
    --quiet -o "$out/readonly/r.mp4" 2>&1); status=$?
else
  text=$(timeout 60 "$hpa" replay "$out/run" --quiet -o "$out/readonly/r.mp4" 2>&1); status=$?
fi
[ "$status" -eq 4 ] || fail "read-only folder: exit $status, expected 4: $text"
grep -q "not writable" <<< "$text" || fail "read-only folder: the message lacks 'not writable': $text"

echo "== a replay stopped by SIGINT / SIGTERM: 130 / 143 within a frame, the previous video kept"
previous=$(md5sum < "$out/run/replay.mp4")
for sig in INT TERM; do
  # 2.5 s at 1000 Hz: 2501 frames, far longer than the wait for the signal
  "$hpa" replay "$out/run" --quiet --rate 1000 > "$out/sig.log" 2>&1 &
  pid=$!
  for _ in $(seq 1 600); do
    [ -e "$out/run/replay.partial.mp4" ] && break
    sleep 0.1
  done
  [ -e "$out/run/replay.partial.mp4" ] || fail "SIG$sig: the replay never started writing"
  sleep 0.5
  kill -s "$sig" "$pid"
  sent=$(date +%s.%N)
  # the stop is polled before each frame: a few frames' time at most, 20 s on a loaded machine
  for _ in $(seq 1 200); do
    kill -0 "$pid" 2>/dev/null || break
    sleep 0.1
  done
  if kill -0 "$pid" 2>/dev/null; then
    fail "SIG$sig: the replay still runs 20 s after the signal"
    kill -KILL "$pid"
  fi
  wait "$pid"; status=$?
  took=$(echo "$(date +%s.%N) - $sent" | bc)
  echo "SIG$sig: exit $status after ${took} s"
  want=$([ "$sig" = INT ] && echo 130 || echo 143)
  [ "$status" -eq "$want" ] || fail "SIG$sig: exit $status, expected $want: $(cat "$out/sig.log")"
  grep -q "stopped by signal" "$out/sig.log" || fail "SIG$sig: no message: $(cat "$out/sig.log")"
  [ "$previous" = "$(md5sum < "$out/run/replay.mp4")" ] || fail "SIG$sig changed replay.mp4"
  [ -e "$out/run/replay.partial.mp4" ] && fail "SIG$sig left replay.partial.mp4"
done

echo "== a replay killed midway (SIGKILL) leaves the previous replay.mp4 whole"
"$hpa" replay "$out/run" --quiet --rate 1000 > /dev/null 2>&1 &
pid=$!
for _ in $(seq 1 600); do
  [ -e "$out/run/replay.partial.mp4" ] && break
  sleep 0.1
done
sleep 0.5
kill -KILL "$pid"
wait "$pid" 2>/dev/null
[ "$previous" = "$(md5sum < "$out/run/replay.mp4")" ] || fail "SIGKILL destroyed replay.mp4"
rm -f "$out/run/replay.partial.mp4"

echo "== a log whose times the run could not have written is refused before any frame"
cp "$out/run/log.csv" "$out/log.good"
# the last row's time set to 1e9 s (was 3e10 frames) and 1e300 s (was a 0-frame video, exit 0)
last=$(wc -l < "$out/log.good")
for t in 1e9 1e300; do
  awk -F, -v OFS=, -v last="$last" -v t="$t" 'NR == last { $1 = t } { print }' "$out/log.good" \
    > "$out/run/log.csv"
  expect_exit 2 "log.csv: key 'line $last column time_s'.*past the run's duration, 2.5 s" \
    replay "$out/run" --quiet -o "$out/edited.mp4"
done
# every time negative
awk -F, -v OFS=, 'NR > 1 { $1 = -$1 - 1 } { print }' "$out/log.good" > "$out/run/log.csv"
expect_exit 2 "log.csv: key 'line 2 column time_s'.*negative" replay "$out/run" --quiet \
  -o "$out/edited.mp4"
[ -e "$out/edited.mp4" ] && fail "a refused log wrote a video"
cp "$out/log.good" "$out/run/log.csv"

echo "== FIFOs and folders in place of run.json or log.csv: 'not a regular file', no wait"
mkdir -p "$out/fifo"
cp "$out/run/run.json" "$out/fifo/"
mkfifo "$out/fifo/log.csv"
expect_exit 2 "log.csv.*not a regular file" replay "$out/fifo" --quiet
rm "$out/fifo/log.csv"
mkdir "$out/fifo/log.csv"
expect_exit 2 "log.csv.*not a regular file" replay "$out/fifo" --quiet
rmdir "$out/fifo/log.csv"
cp "$out/run/log.csv" "$out/fifo/"
rm "$out/fifo/run.json"
mkfifo "$out/fifo/run.json"
expect_exit 2 "run.json.*not a regular file" replay "$out/fifo" --quiet

echo "== run.json's values are checked, naming run.json and the key"
mkdir -p "$out/edit"
cp "$out/run/log.csv" "$out/edit/"
edit() {  # edit KEY JSON_VALUE: run.json with KEY set to the value
  python3 - "$out/run/run.json" "$out/edit/run.json" "$1" "$2" <<'PY'
import json, sys
record = json.load(open(sys.argv[1]))
record[sys.argv[3]] = json.loads(sys.argv[4])
json.dump(record, open(sys.argv[2], "w"))
PY
}
for case in 'seed|-1' 'seed|1.5' 'camera|"banana"' 'controller|"banana"' \
  'scenario_text|"name: [oops"'; do
  key=${case%%|*}
  edit "$key" "${case#*|}"
  expect_exit 2 "run.json: key '$key'" replay "$out/edit" --quiet
done
edit scenario_text '"name: [oops"'
expect_exit 2 "run.json: key 'scenario_text': malformed YAML" replay "$out/edit" --quiet

echo "== a csv-reference run replays from elsewhere after its CSV is gone (run.json keeps it)"
mkdir -p "$out/scen/references"
cp "$src/scenarios/csv_reference.yaml" "$out/scen/"
cp "$src/scenarios/references/figure_eight_path.csv" "$out/scen/references/"
(cd "$out" && "$hpa" run scen/csv_reference.yaml --quiet --out csvrun --set duration=1.0 \
  > /dev/null 2>&1)
[ -s "$out/csvrun/run.json" ] || fail "the csv run wrote no run.json"
python3 - "$out/csvrun/run.json" "$out/scen/references/figure_eight_path.csv" <<'PY' \
  || fail "run.json lacks the absolute scenario_file or the CSV's text"
import json, sys
record = json.load(open(sys.argv[1]))
assert record["scenario_file"].startswith("/"), record["scenario_file"]
assert record["reference_csv_text"] == open(sys.argv[2]).read()
PY
rm "$out/scen/references/figure_eight_path.csv"
(cd / && expect_exit 0 "replay.mp4 \(31 frames" replay "$out/csvrun" --rate 30)

# a sweep's worst run, kept and replayed
cat > "$out/sweep.yaml" <<YAML
base: $src/scenarios/hover.yaml
runs: 2
seed: 5
vary:
  duration: {list: [2.0]}
  events.0.at: {list: [1.0]}
  events.0.force.0: {uniform: [0.1, 0.5]}
YAML
"$hpa" sweep "$out/sweep.yaml" --out "$out/sweep" --jobs 1 --keep-logs worst:1 > /dev/null 2>&1 \
  || fail "sweep with --keep-logs"
kept=$(ls -d "$out"/sweep/logs/run_* 2>/dev/null | head -1)
[ -n "$kept" ] && [ -s "$kept/run.json" ] || fail "the kept run has no run.json"
expect_exit 0 "replay.mp4 \(61 frames" replay "$kept"

echo "== an hpa compare output: one video per controller, each from its own run.json"
"$hpa" compare "$src/scenarios/hover.yaml" --controllers geometric,nonhybrid_mpc --quiet \
  --out "$out/cmp" --set duration=2.5 > /dev/null 2>&1 || fail "compare failed"
for c in geometric nonhybrid_mpc; do
  [ -s "$out/cmp/$c/run.json" ] || fail "compare wrote no run.json for $c"
done
expect_exit 0 "cmp/nonhybrid_mpc/replay.mp4" replay "$out/cmp"
[ -s "$out/cmp/geometric/replay.mp4" ] || fail "no video for the geometric run of the comparison"
expect_exit 2 "one video per run of a comparison" replay "$out/cmp" --out "$out/x.mp4"

echo "replay_cli_test: $failures failure(s)"
[ "$failures" -eq 0 ]
