"""Loaders of what hpa writes: metrics.json (a dict), log.csv (numpy arrays by column, or a
pandas DataFrame when pandas is installed and asked for) and a sweep's runs.jsonl (a list of
dicts, or a DataFrame)."""

import csv
import json

import numpy as np


def load_metrics(path):
    """metrics.json as a dict (docs/design.md section 8)."""
    with open(path) as f:
        return json.load(f)


def load_log(path, pandas=False):
    """log.csv as {column: numpy array}; numeric columns as float, the rest as str. With
    pandas=True, a pandas.DataFrame (ImportError naming pandas if it is not installed)."""
    if pandas:
        import pandas as pd  # optional: not part of the project's dependencies
        return pd.read_csv(path)
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    if not rows:
        raise ValueError("%s: empty (no header)" % path)
    header, body = rows[0], rows[1:]
    for i, row in enumerate(body, start=2):
        if len(row) != len(header):
            raise ValueError("%s line %d: %d fields, the header has %d" % (path, i, len(row), len(header)))
    columns = {}
    for j, name in enumerate(header):
        values = [row[j] for row in body]
        try:
            columns[name] = np.array([float(v) for v in values])
        except ValueError:
            columns[name] = np.array(values)
    return columns


def load_runs(path, pandas=False):
    """A sweep's runs.jsonl: one dict per run (its index, drawn values and metrics)."""
    with open(path) as f:
        runs = [json.loads(line) for line in f if line.strip()]
    if pandas:
        import pandas as pd
        return pd.json_normalize(runs)
    return runs
