#!/usr/bin/env bash
# scripts/redraw_plots.py redraws hpa's plots with matplotlib from the CSV beside each: a run's
# tracking plot and a comparison's plot each become a non-empty PNG of their own.
# Usage: redraw_plots_test.sh HPA_BINARY SOURCE_DIR PYTHON
set -uo pipefail
hpa=$1
src=$2
python=$3
source "$src/scenarios/tests/cli_test_lib.sh"
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
"$hpa" compare "$src/scenarios/hover.yaml" --controllers geometric,nonhybrid_mpc --quiet \
  --set duration=2.5 --out "$out/cmp" > /dev/null 2>&1 || fail "compare failed"
"$hpa" run "$src/scenarios/hover.yaml" --quiet --plots --set duration=2.5 --out "$out/run" \
  > /dev/null 2>&1 || fail "run --plots failed"
for csv in "$out/cmp/comparison.csv" "$out/run/tracking.csv"; do
  png=${csv%.csv}_mpl.png
  "$python" "$src/scripts/redraw_plots.py" "$csv" -o "$png" > "$out/redraw.log" 2>&1 \
    || fail "redraw_plots.py $csv failed: $(tail -3 "$out/redraw.log")"
  [ -s "$png" ] && head -c 8 "$png" | grep -q PNG || fail "no PNG drawn from $csv"
done
echo "redraw_plots_test: $failures failure(s)"
[ "$failures" -eq 0 ]
