"""Compares two runs of one scenario (each an `hpa run --out` folder): their metrics.json equal
but for the wall-clock timings and what flew (flight_stack), and, with --rows, their log.csv row
for row but for the solve times. Exit 1 naming what differs. Used by cli_test_lib.sh's same_run.

usage: same_run.py A B [--rows MIN_ROWS] [--skip KEY]... [--stack-b PREFIX] [--nonempty KEY]...
"""
import argparse
import csv
import json
import sys

# metrics that measure the machine, not the run (at any depth: a team's vehicles have their own
# solve_ms); and what flew
TIMING_KEYS = {"wall_time_s", "mpc_solve_ms", "render_ms", "image_model_ms", "detector_ms",
               "solve_ms"}
NOT_COMPARED = TIMING_KEYS | {"flight_stack"}


def without_timings(value):
    """A metric with every timing key inside it removed."""
    if isinstance(value, dict):
        return {k: without_timings(v) for k, v in value.items() if k not in TIMING_KEYS}
    if isinstance(value, list):
        return [without_timings(v) for v in value]
    return value


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("a")
    parser.add_argument("b")
    parser.add_argument("--rows", type=int, help="compare log.csv too; at least this many rows")
    parser.add_argument("--skip", action="append", default=[], help="a metric not compared")
    parser.add_argument("--stack-b", help="B flew a stack whose name starts so")
    parser.add_argument("--nonempty", action="append", default=[], help="a metric A must have")
    args = parser.parse_args()
    a, b = (json.load(open(p + "/metrics.json")) for p in (args.a, args.b))
    for name, m in (("A", a), ("B", b)):
        assert m["run_error"] is None, "%s ended with a run error: %s" % (name, m["run_error"])
    if args.stack_b:
        assert b["flight_stack"].startswith(args.stack_b), b["flight_stack"]
    for key in args.nonempty:
        assert a.get(key), "A has no %s" % key
    skip = NOT_COMPARED | set(args.skip)
    bad = [k for k in a if k not in skip and without_timings(a[k]) != without_timings(b.get(k))]
    assert not bad, "metrics differ: %s" % ", ".join("%s %r != %r" % (k, a[k], b.get(k))
                                                     for k in bad)
    rows = 0
    if args.rows is not None:
        la, lb = (list(csv.reader(open(p + "/log.csv"))) for p in (args.a, args.b))
        assert len(la) == len(lb) > args.rows, "log rows: %d and %d" % (len(la), len(lb))
        # every solve-time column (a team's log has one per vehicle: vi_solve_ms)
        cols = {i for i, name in enumerate(la[0]) if name.endswith("solve_ms")}
        assert cols, "log has no solve_ms column"
        strip = lambda row: [x for i, x in enumerate(row) if i not in cols]
        bad = [i for i, (x, y) in enumerate(zip(la, lb)) if strip(x) != strip(y)]
        assert not bad, "log rows differ from row %d" % bad[0]
        rows = len(la) - 1
    print("%s = %s: %d metrics, %d log rows" % (args.a, args.b, len(a) - len(skip), rows))


if __name__ == "__main__":
    try:
        main()
    except AssertionError as e:
        print("same_run: %s" % e, file=sys.stderr)
        sys.exit(1)
