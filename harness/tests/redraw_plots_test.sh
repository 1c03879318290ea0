#!/usr/bin/env bash
# scripts/redraw_plots.py redraws hpa's plots with matplotlib from the CSV beside each: a run's
# tracking and retaut plots, a comparison's plot and a two-factor sweep's crash_rate plot each
# become a non-empty PNG of their own. The redrawn figures keep what the hpa plots show: a run
# whose payload goes slack has its slack interval shaded in every time panel (a comparison: one
# shading per run), and each controller of the sweep keeps one colour in every panel.
# Usage: redraw_plots_test.sh HPA_BINARY SOURCE_DIR PYTHON
set -uo pipefail
source "$2/harness/tests/cli_test_lib.sh"
cli_test_start "$@"  # hpa, src, python; out: a folder removed at exit
"$hpa" compare "$src/scenarios/hover.yaml" --controllers geometric,nonhybrid_mpc --quiet \
  --set duration=2.5 --out "$out/cmp" > /dev/null 2>&1 || fail "compare failed"
"$hpa" run "$src/scenarios/hover.yaml" --quiet --plots --set duration=2.5 --out "$out/run" \
  > /dev/null 2>&1 || fail "run --plots failed"

# an upward payload impulse slackens the cable for a while (about 0.2 s here)
impulse_hover_base "$out/slack.yaml" redraw_slack 1.5 0.5
"$hpa" run "$out/slack.yaml" --quiet --plots --out "$out/slack" > /dev/null 2>&1 \
  || fail "run --plots of the slack scenario failed"
"$hpa" compare "$out/slack.yaml" --controllers geometric,nonhybrid_mpc --quiet \
  --out "$out/slack_cmp" > /dev/null 2>&1 || fail "compare of the slack scenario failed"
# two grid factors and two controllers: crash_rate.csv has one panel per grid cell
cat > "$out/grid.yaml" <<'YAML'
base: slack.yaml
runs: 2
seed: 3
vary:
  events.0.impulse.2: {uniform: [0.05, 0.3], label: "impulse z [N s]"}
  world.payload_mass: {grid: [0.08, 0.12]}
  events.0.at: {grid: [0.2, 0.4]}
  controller.type: {grid: [geometric, nonhybrid_mpc]}
YAML
"$hpa" sweep "$out/grid.yaml" --out "$out/grid" --jobs 2 > /dev/null 2>&1 \
  || fail "two-factor sweep failed"

for csv in "$out/cmp/comparison.csv" "$out/run/tracking.csv" "$out/slack/tracking.csv" \
           "$out/slack/retaut.csv" "$out/slack_cmp/comparison.csv" "$out/grid/crash_rate.csv"; do
  png=${csv%.csv}_mpl.png
  "$python" "$src/scripts/redraw_plots.py" "$csv" -o "$png" > "$out/redraw.log" 2>&1 \
    || fail "redraw_plots.py $csv failed: $(tail -3 "$out/redraw.log")"
  [ -s "$png" ] && head -c 8 "$png" | grep -q PNG || fail "no PNG drawn from $csv"
done

# what the redrawn figures hold, read from matplotlib's artists
"$python" - "$src/scripts" "$out" <<'PY' || fail "a redrawn figure lacks its shading or colours"
import csv, sys
sys.path.insert(0, sys.argv[1])
import redraw_plots
out = sys.argv[2]

def spans(ax):
    """the x extents of an axis' shaded spans, in data units"""
    inverse = ax.transData.inverted()
    found = []
    for patch in ax.patches:
        box = patch.get_window_extent().transformed(inverse)
        found.append((box.x0, box.x1, patch.get_facecolor()[:3]))
    return found

def first_slack_s(log):
    for row in csv.DictReader(open(log)):
        if float(row["true_mode"]) == 0.0:
            return float(row["time_s"])
    raise AssertionError(log + " has no slack row: the scenario no longer slackens the cable")

# a run's time panels each shade a span over its first slack row
t_slack = first_slack_s(out + "/slack/log.csv")
for name in ("tracking", "retaut"):
    fig = redraw_plots.draw(out + "/slack/%s.csv" % name)
    for ax in fig.axes:
        assert any(a <= t_slack <= b for a, b, _ in spans(ax)), \
            "%s panel '%s' shades no span over t = %.3f s" % (name, ax.get_title(), t_slack)
# the spans come from the plot's own NAME.shading.csv, not from the log: without log.csv the
# redraw shades the same spans, and a plot that shades nothing writes no shading file
import os, shutil, tempfile
bare = tempfile.mkdtemp()
for f in ("tracking.csv", "tracking.shading.csv"):
    shutil.copy(os.path.join(out, "slack", f), bare)
fig = redraw_plots.draw(os.path.join(bare, "tracking.csv"))
assert all(any(a <= t_slack <= b for a, b, _ in spans(ax)) for ax in fig.axes), \
    "the redraw needs log.csv for its shading"
assert not os.path.exists(out + "/grid/crash_rate.shading.csv"), "a shading file with no shade"
# a comparison shades each run's slack in its own colour
fig = redraw_plots.draw(out + "/slack_cmp/comparison.csv")
for ax in fig.axes:
    colours = {c for _, _, c in spans(ax)}
    assert len(colours) == 2, \
        "comparison panel '%s': shading colours %s" % (ax.get_title(), colours)

# a sweep's controllers: one colour each, the same in every panel
fig = redraw_plots.draw(out + "/grid/crash_rate.csv")
colour_of = {}
panels = 0
for ax in fig.axes:
    if not ax.get_visible():
        continue
    panels += 1
    for line in ax.get_lines():
        label = line.get_label()
        if label in ("geometric", "nonhybrid_mpc"):
            colour_of.setdefault(label, set()).add(tuple(line.get_color()))
assert panels == 4, "%d panels drawn, expected 4" % panels
assert set(colour_of) == {"geometric", "nonhybrid_mpc"}, colour_of
assert all(len(c) == 1 for c in colour_of.values()), "a controller changes colour: %s" % colour_of
assert colour_of["geometric"] != colour_of["nonhybrid_mpc"], colour_of
print("slack shaded at t = %.3f s; sweep colours %s" % (t_slack, colour_of))
PY
echo "redraw_plots_test: $failures failure(s)"
[ "$failures" -eq 0 ]
