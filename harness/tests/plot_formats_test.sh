#!/usr/bin/env bash
# Plots a paper can use: --plot-format png | svg | pdf writes each plot in that format with the
# CSV of what it draws (a header naming panel, series, axis labels with units; one row per
# drawn point); SVG is well-formed XML, PDF a PDF; an unknown format is refused before the run;
# plots never change the metrics. Usage: plot_formats_test.sh HPA_BINARY SOURCE_DIR PYTHON
set -uo pipefail
source "$2/harness/tests/cli_test_lib.sh"
cli_test_start "$@"  # hpa, src, python; out: a folder removed at exit
scenario="$src/scenarios/hover.yaml"

"$hpa" run "$scenario" --quiet --out "$out/none" || fail "run without plots"
for format in png svg pdf; do
  "$hpa" run "$scenario" --quiet --out "$out/$format" --plots --plot-format "$format" \
    || fail "run with $format plots"
  for plot in tracking xy_path retaut; do
    [ -s "$out/$format/$plot.$format" ] || fail "$format: no $plot.$format"
    [ -s "$out/$format/$plot.csv" ] || fail "$format: no $plot.csv"
  done
done
head -c 4 "$out/pdf/tracking.pdf" | grep -q '%PDF' || fail "tracking.pdf is not a PDF"
"$python" - "$out" <<'PY' || fail "plot files"
import csv, json, sys, xml.etree.ElementTree as ET
out = sys.argv[1]
root = ET.parse(out + "/svg/tracking.svg").getroot()
assert root.tag.endswith("svg"), root.tag
assert len(list(root.iter("{http://www.w3.org/2000/svg}path"))) > 100, "an SVG without its lines"
rows = list(csv.DictReader(open(out + "/svg/tracking.csv")))
log_rows = sum(1 for _ in open(out + "/none/log.csv")) - 1
series = {}
for r in rows:
    series.setdefault((r["panel"], r["series"]), []).append(r)
# three panels of reference, true and estimate, one point per control step each
assert len(series) == 9, sorted(series)
assert all(len(v) == log_rows for v in series.values()), {k: len(v) for k, v in series.items()}
assert {r["x_label"] for r in rows} == {"t [s]"}, {r["x_label"] for r in rows}
assert "reference (dotted)" in {k[1] for k in series}, sorted(series)
# the PNG's and the SVG's CSV hold the same numbers
assert open(out + "/png/tracking.csv").read() == open(out + "/svg/tracking.csv").read()
skip = {"wall_time_s", "mpc_solve_ms", "render_ms", "image_model_ms", "detector_ms"}
base = json.load(open(out + "/none/metrics.json"))
for fmt in ("png", "svg", "pdf"):
    m = json.load(open("%s/%s/metrics.json" % (out, fmt)))
    bad = [k for k in base if k not in skip and base[k] != m[k]]
    assert not bad, "%s plots changed %s" % (fmt, bad)
print("plots: %d series of %d points; metrics unchanged by png, svg and pdf" % (len(series), log_rows))
PY
expect_exit 2 "unknown plot format 'eps', expected png \| svg \| pdf" run "$scenario" --quiet \
  --out "$out/eps" --plots --plot-format eps
[ ! -e "$out/eps/metrics.json" ] || fail "a refused format still ran"

echo "plot_formats_test: $failures failure(s)"
[ "$failures" -eq 0 ]
