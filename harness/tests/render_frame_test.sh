#!/usr/bin/env bash
# hpa render-frame's camera and size: the chase camera at a requested size is a PNG of that size
# (read back from its IHDR chunk); a size outside 16-4096 px and an unknown camera are bad input
# (exit 2, naming the option).
# usage: render_frame_test.sh HPA_BIN SCENARIOS_DIR OUT_DIR
set -uo pipefail
hpa=$1; scen=$2; out=$3
rm -rf "$out"; mkdir -p "$out"
# shellcheck source=cli_test_lib.sh
source "$(dirname "$0")/cli_test_lib.sh"

# png_size FILE: "WIDTHxHEIGHT" from the PNG's header (IHDR: width, height as 4-byte big endian)
png_size() {
  /usr/bin/python3 - "$1" <<'PY'
import struct, sys
data = open(sys.argv[1], "rb").read(24)
assert data[:8] == b"\x89PNG\r\n\x1a\n" and data[12:16] == b"IHDR", "not a PNG"
print("%dx%d" % struct.unpack(">II", data[16:24]))
PY
}

echo "== the chase camera at 320x240"
expect_exit 0 "wrote .*chase camera" render-frame "$scen/hover.yaml" --at 1.0 --camera chase \
  --size 320x240 --out "$out/chase.png"
[ "$(png_size "$out/chase.png")" = "320x240" ] \
  || fail "chase.png is $(png_size "$out/chase.png"), expected 320x240"

echo "== the payload camera at its own size by default, scaled when asked"
expect_exit 0 "wrote .*payload camera" render-frame "$scen/hover.yaml" --at 1.0 \
  --out "$out/payload.png"
[ "$(png_size "$out/payload.png")" = "1280x720" ] \
  || fail "payload.png is $(png_size "$out/payload.png"), expected 1280x720"
expect_exit 0 "wrote" render-frame "$scen/hover.yaml" --at 1.0 --size 64x48 \
  --out "$out/payload_small.png"
[ "$(png_size "$out/payload_small.png")" = "64x48" ] \
  || fail "payload_small.png is $(png_size "$out/payload_small.png"), expected 64x48"

echo "== bad sizes and cameras: exit 2 naming the option"
expect_exit 2 "--size" render-frame "$scen/hover.yaml" --at 1.0 --size 5x5 --out "$out/x.png"
expect_exit 2 "--size" render-frame "$scen/hover.yaml" --at 1.0 --size 5000x100 \
  --out "$out/x.png"
expect_exit 2 "--size" render-frame "$scen/hover.yaml" --at 1.0 --size 320 --out "$out/x.png"
expect_exit 2 "--camera" render-frame "$scen/hover.yaml" --at 1.0 --camera banana \
  --out "$out/x.png"
[ -e "$out/x.png" ] && fail "a rejected render-frame wrote x.png"

[ "$failures" -eq 0 ] || { echo "$failures check(s) failed"; exit 1; }
echo "render_frame: all checks passed"
