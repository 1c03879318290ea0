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
with one y scale. One legend for the whole figure, below the panels. Each panel gets the
shading the hpa plot has (the true slack intervals, a comparison's per run, and retaut.csv's
re-taut marks), read from NAME.shading.csv, which the plot writes beside NAME.csv with every
span it shades: the redraw does not derive them again. Needs matplotlib
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


def read_shading(csv_path):
    """{panel: [(label, x0, x1, rgb)]} from NAME.shading.csv, written beside the plot's CSV with
    every span the hpa plot shades (slack intervals, re-taut marks); {} when it shades none."""
    path = csv_path[:-len(".csv")] + ".shading.csv" if csv_path.endswith(".csv") else None
    shading = OrderedDict()
    if not path or not os.path.isfile(path):
        return shading
    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        need = {"panel", "label", "x0", "x1", "r", "g", "b"}
        if reader.fieldnames is None or not need.issubset(reader.fieldnames):
            raise SystemExit("%s: not an hpa shading CSV (expected columns %s)"
                             % (path, sorted(need)))
        for line, row in enumerate(reader, start=2):
            try:
                span = (float(row["x0"]), float(row["x1"]))
                rgb = tuple(float(row[c]) / 255.0 for c in "rgb")
            except ValueError:
                raise SystemExit("%s line %d: a span or colour that is not a number" % (path, line))
            shading.setdefault(row["panel"], []).append((row["label"], span[0], span[1], rgb))
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

    shading = read_shading(csv_path)
    handles = OrderedDict()  # legend label -> artist, over all panels
    for ax, (title, panel) in zip(flat_axes, panels.items()):
        for label, a, b, rgb in shading.get(title, []):
            span = ax.axvspan(a, b, color=rgb, alpha=0.35, lw=0, zorder=0)
            if label:
                handles.setdefault(label + " (shaded)", span)
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
