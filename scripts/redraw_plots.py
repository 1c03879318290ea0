#!/usr/bin/env python3
"""Redraws an hpa plot with matplotlib from the CSV written beside it (every plot writes
NAME.csv: one row per point of every series, with its panel, series name and axis labels).

    python3 scripts/redraw_plots.py out/run/tracking.csv [-o tracking_mpl.pdf]

One subplot per panel, in the CSV's order; lines for plain series, error bars where low/high
are given, a colour-mapped scatter where value is given. Needs matplotlib (Debian:
python3-matplotlib); only the standard library otherwise.
"""

import argparse
import csv
import sys
from collections import OrderedDict


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


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("csv", help="a plot's CSV written by hpa")
    parser.add_argument("-o", "--out", help="output file (.png, .svg, .pdf); default: CSV name + _mpl.pdf")
    args = parser.parse_args()
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise SystemExit("redraw_plots.py needs matplotlib (Debian: apt-get install python3-matplotlib)")
    panels = read_panels(args.csv)
    if not panels:
        raise SystemExit("%s: no data rows" % args.csv)
    fig, axes = plt.subplots(len(panels), 1, figsize=(10, 2.6 * len(panels)), squeeze=False)
    styles = ["-", "--", ":", "-."]
    for ax, (title, panel) in zip(axes[:, 0], panels.items()):
        for k, (name, s) in enumerate(panel["series"].items()):
            finite_value = any(v == v for v in s["value"])
            finite_err = any(v == v for v in s["low"])
            if finite_value:
                points = ax.scatter(s["x"], s["y"], c=s["value"], s=4, cmap="turbo", label=name)
                fig.colorbar(points, ax=ax)
            elif finite_err:
                low = [y - lo for y, lo in zip(s["y"], s["low"])]
                high = [hi - y for y, hi in zip(s["y"], s["high"])]
                ax.errorbar(s["x"], s["y"], yerr=[low, high], fmt="o", capsize=3, label=name)
            else:
                style = ":" if name.endswith("(dotted)") else styles[k % len(styles)]
                ax.plot(s["x"], s["y"], style, linewidth=1.2, label=name)
        ax.set_title(title, fontsize=9)
        ax.set_xlabel(panel["x_label"])
        ax.set_ylabel(panel["y_label"])
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="best")
    fig.tight_layout()
    out = args.out or args.csv[:-4] + "_mpl.pdf"
    fig.savefig(out)
    print("wrote", out)


if __name__ == "__main__":
    sys.exit(main())
