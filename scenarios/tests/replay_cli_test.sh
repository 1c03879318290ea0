#!/usr/bin/env bash
# hpa replay: renders a finished run's video from DIR/log.csv and DIR/run.json without changing
# the run's files; works on a sweep's kept logs; refuses a folder without run.json.
# Usage: replay_cli_test.sh HPA_BINARY SOURCE_DIR
set -uo pipefail
hpa=$1
src=$2
source "$src/scenarios/tests/cli_test_lib.sh"
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
expect_exit 2 "run.json.*cannot open it" replay "$out/nothing" --quiet
expect_exit 2 "expected a file name ending in .mp4" replay "$out/run" --quiet -o "$out/x.avi"

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

echo "replay_cli_test: $failures failure(s)"
[ "$failures" -eq 0 ]
