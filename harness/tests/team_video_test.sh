#!/usr/bin/env bash
# A team run's video (docs/cooperative.md): `hpa run` of a team scenario with --video writes an MP4
# of 960x540 frames, one per video tick of the run (RateTable::video), and with
# --video-slack-events only the frames around its cable's slack event; neither changes the run
# (metrics.json equal to the plain run's but for the timings).
#   team_video_test.sh HPA_BIN SOURCE_DIR PYTHON
set -uo pipefail
here=$(cd "$(dirname "$0")" && pwd)
source "$here/cli_test_lib.sh"
cli_test_start "$@"

scenario="$src/scenarios/ci/team2_cable_slack.yaml"
duration_s=8.0  # the scenario's duration
rate_hz=30      # RateTable::video

# mp4_frames FILE: "FRAMES WIDTH HEIGHT" of the MP4's video track (its sample table's count, its
# sample entry's size), or a line starting "bad:" naming what is wrong with the file
mp4_frames() {
  "$python" - "$1" <<'PY'
import struct, sys

data = open(sys.argv[1], "rb").read()

def boxes(start, end):
    """(type, payload start, payload end) of the boxes in data[start:end]."""
    at = start
    while at + 8 <= end:
        size, kind = struct.unpack(">I4s", data[at:at + 8])
        head = 8
        if size == 1:
            size = struct.unpack(">Q", data[at + 8:at + 16])[0]
            head = 16
        elif size == 0:
            size = end - at
        if size < head or at + size > end:
            raise ValueError(f"box {kind!r} overruns the file")
        yield kind.decode("latin-1"), at + head, at + size
        at += size

def find(start, end, path):
    """The payload span of the first box along path (types), or None."""
    for kind, a, b in boxes(start, end):
        if kind == path[0]:
            return (a, b) if len(path) == 1 else find(a, b, path[1:])
    return None

try:
    top = [k for k, _, _ in boxes(0, len(data))]
    if not top or top[0] != "ftyp" or "moov" not in top or "mdat" not in top:
        print("bad: not an MP4 (top-level boxes %s)" % top)
        sys.exit(0)
    moov = find(0, len(data), ["moov"])
    for kind, a, b in boxes(*moov):
        if kind != "trak":
            continue
        hdlr = find(a, b, ["mdia", "hdlr"])
        if hdlr is None or data[hdlr[0] + 8:hdlr[0] + 12] != b"vide":
            continue
        stbl = find(a, b, ["mdia", "minf", "stbl"])
        stsz = find(*stbl, ["stsz"])
        frames = struct.unpack(">I", data[stsz[0] + 8:stsz[0] + 12])[0]
        stsd = find(*stbl, ["stsd"])
        entry = stsd[0] + 8  # version, flags, entry count; then the first sample entry
        width, height = struct.unpack(">HH", data[entry + 8 + 24:entry + 8 + 28])
        print(frames, width, height)
        sys.exit(0)
    print("bad: no video track")
except (ValueError, struct.error, TypeError) as e:
    print("bad: %s" % e)
PY
}

"$hpa" run "$scenario" --out "$out/plain" --quiet || fail "the plain run failed"
"$hpa" run "$scenario" --out "$out/video" --quiet --video "$out/video/team.mp4" \
  || fail "the run with --video failed"
"$hpa" run "$scenario" --out "$out/slack" --quiet --video-slack-events \
  || fail "the run with --video-slack-events failed"

echo "== --video: one 960x540 frame per video tick"
# video ticks at k / rate_hz from t = 0 to the end inclusive (the scenario does not crash)
expected=$("$python" -c "print(round($duration_s * $rate_hz) + 1)")
if [ -s "$out/video/team.mp4" ]; then
  read -r frames width height <<< "$(mp4_frames "$out/video/team.mp4")"
  [ "$frames" = "$expected" ] || fail "team.mp4 has $frames frames, expected $expected"
  [ "$width x $height" = "960 x 540" ] || fail "team.mp4 is $width x $height, expected 960 x 540"
  echo "team.mp4: $frames frames, $width x $height"
else
  fail "no team.mp4"
fi

echo "== --video-slack-events: the slack event with a second either side, not the whole run"
if [ -s "$out/slack/slack_events.mp4" ]; then
  read -r frames width height <<< "$(mp4_frames "$out/slack/slack_events.mp4")"
  # at least the second before and the second after the event (VideoRecorder::kSlackWindow_s)
  if ! [[ "$frames" =~ ^[0-9]+$ ]] || [ "$frames" -le $((2 * rate_hz)) ] ||
    [ "$frames" -ge "$expected" ]; then
    fail "slack_events.mp4 has $frames frames, expected more than $((2 * rate_hz)) and fewer than $expected"
  fi
  echo "slack_events.mp4: $frames frames, $width x $height"
else
  fail "no slack_events.mp4 (the scenario's push slackens vehicle 1's cable)"
fi

echo "== observing never changes the run"
same_run "$out/plain" "$out/video" "--video"
same_run "$out/plain" "$out/slack" "--video-slack-events"

[ "$failures" -eq 0 ] && echo "all team video checks passed"
exit $((failures > 0))
