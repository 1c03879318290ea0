#!/usr/bin/env bash
# `hpa golden --exact` asks for every value bit for bit: a golden copy recorded from this build's
# metrics passes it, and the same copy with one value moved by a relative 1e-9 passes the
# tolerant comparison but fails --exact, naming the value.
# usage: golden_exact_test.sh HPA_BIN FROM_DIR OUT_DIR
set -uo pipefail
hpa=$1; from=$2; out=$3
rm -rf "$out"; mkdir -p "$out"
# shellcheck source=cli_test_lib.sh
source "$(dirname "$0")/cli_test_lib.sh"
golden="$out/golden.json"
printf '{"tolerances": {"default": {"rel": 1e-3}}}' > "$golden"
"$hpa" golden --golden "$golden" --from "$from" --update --reason "this build" --quiet > /dev/null \
  || fail "recording a golden copy from $from failed"
expect_exit 0 "bit for bit" golden --golden "$golden" --from "$from" --exact --quiet
expect_exit 2 "--exact.*compares only" golden --golden "$golden" --from "$from" --exact --update \
  --reason x
python3 - "$golden" <<'PY' || fail "could not nudge a value"
import json, sys
g = json.load(open(sys.argv[1]))
g["scenarios"]["hover"]["quad_position_deviation_max_m"] *= 1.0 + 1e-9
json.dump(g, open(sys.argv[1], "w"))
PY
expect_exit 0 "within tolerance" golden --golden "$golden" --from "$from" --quiet
expect_exit 1 "hover: quad_position_deviation_max_m" golden --golden "$golden" --from "$from" --exact --quiet
[ "$failures" -eq 0 ] || { echo "$failures check(s) failed"; exit 1; }
echo "golden --exact: all checks passed"
