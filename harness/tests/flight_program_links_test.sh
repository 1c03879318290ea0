#!/usr/bin/env bash
# The flight program links no MuJoCo and no GL: hpa-flight (the flight code as its own process,
# flight/app) holds no symbol of MuJoCo (mj_, mjr_, mjv_), OSMesa, EGL or OpenGL, defined or
# undefined, and names no such shared library among those it needs itself (readelf's NEEDED: a
# library OpenCV loads for its own use is OpenCV's, not the flight code's). hpa (which simulates) must hold them, so the check
# is shown able to fail. With ci/dependency_rule.sh (no such include in flight code) this proves
# the dependency rule of docs/design.md section 1 on the built programs.
# usage: flight_program_links_test.sh HPA_FLIGHT_BIN HPA_BIN
set -uo pipefail
flight_bin=$1 hpa_bin=$2
symbols='^(mj_|mjr_|mjv_|mju_|OSMesa|egl[A-Z]|gl[A-Z])'
libraries='libmujoco|libOSMesa|libEGL|libGL'

# sim_symbols BIN: the MuJoCo and GL symbols BIN defines or needs, one per line
sim_symbols() { nm -C "$1" 2>/dev/null | awk '{print $NF}' | grep -E "$symbols" | sort -u; }
# sim_libraries BIN: the MuJoCo and GL shared libraries BIN itself needs
sim_libraries() { readelf -d "$1" 2>/dev/null | grep NEEDED | grep -oE "$libraries" | sort -u; }

failures=0
found=$(sim_symbols "$flight_bin")
if [ -n "$found" ]; then
  echo "FAIL: $flight_bin holds MuJoCo or GL symbols:"; echo "$found" | head -20 | sed 's/^/  /'
  failures=$((failures + 1))
fi
found=$(sim_libraries "$flight_bin")
if [ -n "$found" ]; then
  echo "FAIL: $flight_bin needs MuJoCo or GL libraries: $found"; failures=$((failures + 1))
fi
# the same checks find MuJoCo in the simulator: they can fail
[ -n "$(sim_symbols "$hpa_bin")" ] || { echo "FAIL: no MuJoCo symbol found in $hpa_bin"; failures=$((failures + 1)); }
[ -n "$(sim_libraries "$hpa_bin")" ] || { echo "FAIL: no MuJoCo library found for $hpa_bin"; failures=$((failures + 1)); }
[ "$failures" -eq 0 ] || exit 1
echo "flight program: no MuJoCo or GL symbol or library in $(basename "$flight_bin")"
