#!/usr/bin/env bash
# hpa run with a csv reference (reference: {type: csv, file: ...}): a file that is not a regular
# file (/dev/zero, a FIFO, a folder) is refused at once; rows closer than the minimum step,
# positions beyond the hover reference's range, speeds beyond the physical bound and a
# quadrotor reference that is not finite are refused with exit 2 naming the file and line,
# before anything is flown; a UTF-8 byte order mark before the header is accepted.
# Usage: csv_reference_cli_test.sh HPA_BINARY SOURCE_DIR
set -uo pipefail
hpa=$1
src=$2
source "$src/harness/tests/cli_test_lib.sh"
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
base="$src/scenarios/csv_reference.yaml"

# run_csv CODE PATTERN FILE: hpa run of the csv scenario flying FILE exits CODE, its output
# matching PATTERN, within a few seconds (no file is read for long, none blocks)
run_csv() {
  local code=$1 pattern=$2 file=$3
  local start took
  start=$(date +%s)
  expect_exit "$code" "$pattern" run "$base" --quiet --out "$out/run" --set duration=0.5 \
    --set "reference.file=$file"
  took=$(($(date +%s) - start))
  [ "$took" -le 10 ] || fail "reference.file=$file took $took s"
}

echo "== not a regular file: refused at once (/dev/zero was read for 20 s, a FIFO blocked)"
run_csv 2 "/dev/zero.*not a regular file" /dev/zero
mkfifo "$out/fifo.csv"
run_csv 2 "fifo.csv.*not a regular file" "$out/fifo.csv"
run_csv 2 "$out.*not a regular file" "$out"

echo "== rows 1e-300 s apart (ref_pQ_x was -nan, 30 MPC fallbacks): exit 2 naming the line"
printf 't_s,x_m,y_m,z_m\n0,0,0,0.8\n1e-300,1,0,0.8\n0.2,1,0,0.8\n' > "$out/close.csv"
run_csv 2 "close.csv: key 'line 3 column 1'.*at least 0.0001 s apart" "$out/close.csv"

echo "== positions beyond the hover reference's range, speeds beyond the physical bound"
printf 't_s,x_m,y_m,z_m\n0,0,0,0.8\n1,1e300,0,0.8\n' > "$out/far.csv"
run_csv 2 "far.csv: key 'line 3 column 2'.*outside the reference positions' range \[-1000, 1000\]" \
  "$out/far.csv"
printf 't_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps\n0,0,0,0.8,1e9,0,0\n1,1,0,0.8,0,0,0\n' \
  > "$out/fast.csv"
run_csv 2 "fast.csv: key 'line 2'.*above 40 m/s" "$out/fast.csv"
printf 't_s,x_m,y_m,z_m\n0,0,0,0.8\n0.1,9,0,0.8\n' > "$out/jump.csv"
run_csv 2 "jump.csv: key 'line 2'.*90 m/s.*differenced between lines 2 and 3" "$out/jump.csv"

echo "== a quadrotor reference that is not defined (the payload in free fall): exit 2 by line"
printf 't_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps,ax_mps2,ay_mps2,az_mps2\n%s\n%s\n' \
  0,0,0,0.8,0,0,0,0,0,0 1,0,0,0.8,0,0,0,0,0,-20 > "$out/fall.csv"
run_csv 2 "fall.csv: key 'line 3'.*free fall" "$out/fall.csv"

echo "== a UTF-8 byte order mark before the header is accepted (was: unknown column 't_s')"
printf '\xef\xbb\xbf' > "$out/bom.csv"
cat "$src/scenarios/references/figure_eight_path.csv" >> "$out/bom.csv"
text=$(timeout 120 "$hpa" run "$base" --quiet --out "$out/bom" --set duration=0.5 \
  --set "reference.file=$out/bom.csv" 2>&1); status=$?
# 0, or 1 where the file's expect bounds (for its whole 10 s) do not hold over 0.5 s
[ "$status" -le 1 ] || fail "a BOM CSV: exit $status: $text"
[ -s "$out/bom/metrics.json" ] || fail "a BOM CSV: no metrics.json: $text"

echo "csv_reference_cli_test: $failures failure(s)"
[ "$failures" -eq 0 ]
