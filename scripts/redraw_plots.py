#!/usr/bin/env python3
"""Redraws an hpa plot with matplotlib from the CSV written beside it (every plot writes
NAME.csv: one row per point of every series, with its panel, series name and axis labels).

    python3 scripts/redraw_plots.py out/run/tracking.csv [-o tracking_mpl.pdf]

One subplot per panel, in the CSV's order; lines for plain series, error bars where low/high
are given, a colour-mapped scatter where value is given. A series keeps one colour in every
panel, and its qualified variants share it: `NAME (dotted)` (a reference, drawn dotted),
`NAME (expect-failure rate)` (drawn thin and dashed) and `NAME (95% CI)` (error bars) take
NAME's colour. Panels titled `a=1, b=2` (a sweep's crash_rate.csv with two or more grid
factors) are laid out as a grid: one column per value of the second name, wrapped past six,
with one y scale. One legend for the whole figure, below the panels. Panels against time
(`t [s]`) get the slack shading the hpa plot has, read from the run's log.csv beside the CSV
(DIR/log.csv, or DIR/NAME/log.csv for each series NAME of a comparison): the true slack
intervals, and in retaut.csv's panels each re-taut instant marked in red. Needs matplotlib
(Debian: python3-matplotlib); only the standard library otherwise.
"""

import argparse
import csv
import math
import os
import sys
from collections import OrderedDict

# qualifiers a series name may end with; the series takes the colour of the name before it
QUALIFIERS = (" (dotted)", " (expect-failure rate)", " (95% CI)")
# shorter true-mode flips are tendon chatter: the slack intervals of TrueSlackIntervals
# (scenarios/src/runner/metrics.cc, kMinSlackInterval_s), which the hpa plots shade
MIN_SLACK_INTERVAL_S = 0.03
# the hpa plots' shading colours (RGB): a run's slack, a comparison's other runs' slack, re-taut
SLACK_RGB = (1.0, 165 / 255, 0.0)
COMPARISON_FIRST_SLACK_RGB = (1.0, 200 / 255, 0.0)
COMPARISON_OTHER_SLACK_RGB = (150 / 255, 200 / 255, 1.0)
RETAUT_RGB = (220 / 255, 0.0, 0.0)
MAX_GRID_COLUMNS = 6


def read_panels(path):
    """{panel: {"x_label", "y_label", "series": {name: {"x", "y", "low", "high", "value"}}}}"""
    panels = OrderedDict()
    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        need = {"panel", "series", "x_label", "y_label", "x", "y", "low", "high", "value"}
        if reader.fieldnames is None or not need.issubset(reader.fieldnames):
            raise SystemExit("%s: not an hpa plot CSV (expected columns %s)" % (path, sorted(need)))
        for line, row in enumerate(reader, start=2):
            panel = panels.setdefault(row["panel"], {"x_label": row["x_label"],
                                                     "y_label": row["y_label"],
                                                     "series": OrderedDict()})
            s = panel["series"].setdefault(row["series"] or "series",
                                           {k: [] for k in ("x", "y", "low", "high", "value")})
            for k in s:
                try:
                    s[k].append(float(row[k]) if row[k] != "" else float("nan"))
                except ValueError:
                    raise SystemExit("%s line %d: %s '%s' is not a number" % (path, line, k, row[k]))
    return panels


def colour_key(name):
    """The name a series' colour belongs to: its name without a trailing qualifier."""
    for q in QUALIFIERS:
        if name.endswith(q):
            return colour_key(name[:-len(q)])
    return name


def facet_layout(titles):
    """(rows, columns) of a grid of panels titled `a=1, b=2, ...` with the same names in the
    same order (two or more), one column per value of the second name (wrapped past
    MAX_GRID_COLUMNS); None for any other titles (one panel per row)."""
    names = None
    second_values = []
    for title in titles:
        parts = [p.split("=", 1) for p in title.split(", ")]
        if len(parts) < 2 or any(len(p) != 2 for p in parts):
            return None
        if names is None:
            names = [p[0] for p in parts]
        elif names != [p[0] for p in parts]:
            return None
        if parts[1][1] not in second_values:
            second_values.append(parts[1][1])
    columns = min(len(second_values), MAX_GRID_COLUMNS, len(titles))
    return (len(titles) + columns - 1) // columns, columns


def slack_intervals(log_path):
    """The true slack intervals [start, end) of a run's log.csv (true_mode 0), as the hpa plots
    shade them, and the log's time span."""
    times, slack = [], []
    with open(log_path, newline="") as f:
        for row in csv.DictReader(f):
            times.append(float(row["time_s"]))
            slack.append(float(row["true_mode"]) == 0.0)
    intervals = []
    i = 0
    while i < len(times):
        if not slack[i]:
            i += 1
            continue
        j = i
        while j < len(times) and slack[j]:
            j += 1
        end = times[j] if j < len(times) else times[-1]
        if end - times[i] >= MIN_SLACK_INTERVAL_S:
            intervals.append((times[i], end))
        i = j
    span = (times[0], times[-1]) if times else (0.0, 0.0)
    return intervals, span


def slack_shading(csv_path, keys):
    """[(colour, intervals, span)] for the runs behind a plot: DIR/log.csv (a run's plot), else
    DIR/KEY/log.csv for each series KEY (a comparison: the first run's slack orange, the
    others' light blue, as hpa compare draws them)."""
    folder = os.path.dirname(os.path.abspath(csv_path))
    own = os.path.join(folder, "log.csv")
    if os.path.isfile(own):
        return [(SLACK_RGB,) + slack_intervals(own)]
    shading = []
    for key in keys:
        for name in (key, key[:-len(" (CRASHED)")] if key.endswith(" (CRASHED)") else None):
            log = name and os.path.join(folder, name, "log.csv")
            if log and os.path.isfile(log):
                colour = COMPARISON_FIRST_SLACK_RGB if not shading else COMPARISON_OTHER_SLACK_RGB
                shading.append((colour,) + slack_intervals(log))
                break
    return shading


def draw(csv_path):
    """The matplotlib figure of an hpa plot's CSV (its axes in the CSV's panel order)."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise SystemExit("redraw_plots.py needs matplotlib (Debian: apt-get install python3-matplotlib)")
    panels = read_panels(csv_path)
    if not panels:
        raise SystemExit("%s: no data rows" % csv_path)

    # one colour per series key over the whole figure, in order of first appearance
    keys = []
    for panel in panels.values():
        for name in panel["series"]:
            if colour_key(name) not in keys:
                keys.append(colour_key(name))
    palette = plt.get_cmap("tab10" if len(keys) <= 10 else "tab20").colors
    colour_of = {key: palette[i % len(palette)] for i, key in enumerate(keys)}

    layout = facet_layout(list(panels))
    if layout:
        rows, columns = layout
        fig, axes = plt.subplots(rows, columns, figsize=(3.6 * columns, 2.6 * rows),
                                 squeeze=False, sharex=True, sharey=True)
    else:
        rows, columns = len(panels), 1
        fig, axes = plt.subplots(rows, 1, figsize=(10, 2.6 * rows), squeeze=False)
    flat_axes = list(axes.flat)
    for ax in flat_axes[len(panels):]:
        ax.set_visible(False)

    shading = slack_shading(csv_path, keys)
    retaut = os.path.basename(csv_path) == "retaut.csv"
    handles = OrderedDict()  # legend label -> artist, over all panels
    for ax, (title, panel) in zip(flat_axes, panels.items()):
        if panel["x_label"] == "t [s]":
            for colour, intervals, span in shading:
                for a, b in intervals:
                    label = "slack (shaded)" if len(shading) == 1 else "slack (shaded per run)"
                    handles.setdefault(label, ax.axvspan(
                        a, b, color=colour, alpha=0.35, lw=0, zorder=0))
                    if retaut and b < span[1]:
                        mark = ax.axvspan(b, b + 0.004 * (span[1] - span[0]), color=RETAUT_RGB,
                                          alpha=0.35, lw=0, zorder=0)
                        handles.setdefault("re-taut", mark)
        for name, s in panel["series"].items():
            colour = colour_of[colour_key(name)]
            finite_value = any(v == v for v in s["value"])
            finite_err = any(v == v for v in s["low"])
            if finite_value:
                points = ax.scatter(s["x"], s["y"], c=s["value"], s=4, cmap="turbo", label=name)
                fig.colorbar(points, ax=ax)
                handles.setdefault(name, points)
            elif finite_err:
                # rounding can put an interval's end a hair past its point
                low = [max(0.0, y - lo) for y, lo in zip(s["y"], s["low"])]
                high = [max(0.0, hi - y) for y, hi in zip(s["y"], s["high"])]
                bars = ax.errorbar(s["x"], s["y"], yerr=[low, high], fmt="o", capsize=3,
                                   markersize=4, color=colour, label=name)
                handles.setdefault(name, bars)
            else:
                if name.endswith(" (dotted)"):
                    style, width = ":", 1.0
                elif colour_key(name) != name:
                    style, width = "--", 0.9
                else:
                    style, width = "-", 1.6
                line, = ax.plot(s["x"], s["y"], style, color=colour, linewidth=width, label=name)
                handles.setdefault(name, line)
        ax.set_title(title, fontsize=9)
        ax.set_xlabel(panel["x_label"])
        ax.set_ylabel(panel["y_label"])
        ax.grid(alpha=0.3)
    if layout:
        for ax in flat_axes:  # the shared axes are labelled once, at the left and the bottom
            ax.label_outer()
    # one legend below the panels, covering none of them
    columns_in_legend = max(1, min(len(handles), 4 if not layout else 2 * columns))
    legend_rows = math.ceil(len(handles) / columns_in_legend)
    legend_in = 0.25 * legend_rows + 0.2
    fig.set_figheight(fig.get_figheight() + legend_in)
    fig.legend(list(handles.values()), list(handles.keys()), loc="lower center",
               ncol=columns_in_legend, fontsize=7, frameon=False)
    fig.tight_layout(rect=(0, legend_in / fig.get_figheight(), 1, 1))
    return fig


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("csv", help="a plot's CSV written by hpa")
    parser.add_argument("-o", "--out", help="output file (.png, .svg, .pdf); default: CSV name + _mpl.pdf")
    args = parser.parse_args()
    fig = draw(args.csv)
    out = args.out or args.csv[:-4] + "_mpl.pdf"
    fig.savefig(out)
    print("wrote", out)


if __name__ == "__main__":
    sys.exit(main())
