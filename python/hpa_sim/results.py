"""Loaders of what hpa writes: metrics.json (a dict), log.csv (numpy arrays by column, or a
pandas DataFrame when pandas is installed and asked for) and a sweep's runs.jsonl (a list of
dicts, or a DataFrame). Every refusal is an InputError whose message starts with the file, the
line and, where it helps, the column: "PATH:LINE:COLUMN: what was wrong, what was expected"."""

import csv
import io
import json
import math
import os
import stat
import warnings

import numpy as np

_BOM = b"\xef\xbb\xbf"  # a UTF-8 byte-order mark, as some editors save a CSV
_TEXT_COLUMNS = ("status",)  # log.csv's columns of names; every other column is a number
_JSON_TYPE = {dict: "an object", list: "an array", str: "a string", bool: "a boolean",
              int: "a number", float: "a number", type(None): "null"}


class InputError(ValueError):
    """A file (or message) hpa_sim cannot read; the message names where and what was expected."""


def _where(source, line=None, column=None):
    # "PATH", "PATH:LINE" or "PATH:LINE:COLUMN", the form compilers and editors jump to
    return ":".join([str(source)] + [str(n) for n in (line, column) if n is not None])


def _line_column(text, index, first_line=1):
    # 1-based line and column of text[index] (bytes or str), counting from first_line
    newline = b"\n" if isinstance(text, bytes) else "\n"
    line = first_line + text.count(newline, 0, index)
    return line, index - (text.rfind(newline, 0, index) + 1) + 1


def _read_bytes(path):
    # the whole file; a missing or unreadable file is an InputError naming it, and so is a
    # device, a pipe or a folder (reading /dev/zero or a FIFO would never end): opened without
    # blocking, then checked, so a FIFO cannot hang the open
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)
    except OSError as e:
        raise InputError("%s: cannot read it (%s)" % (path, e.strerror or e)) from e
    if not stat.S_ISREG(os.fstat(fd).st_mode):
        os.close(fd)
        raise InputError("%s: not a regular file (a device, a pipe or a folder), expected a "
                         "file" % path)
    with os.fdopen(fd, "rb") as f:
        try:
            return f.read()
        except OSError as e:
            raise InputError("%s: cannot read it (%s)" % (path, e.strerror or e)) from e


def _decode_utf8(data, source, first_line=1, error=InputError):
    # strict UTF-8: a bad byte is refused with its line and (byte) column, never replaced
    try:
        return bytes(data).decode("utf-8")
    except UnicodeDecodeError as e:
        line, column = _line_column(bytes(data), e.start, first_line)
        raise error("%s: byte 0x%02x is not UTF-8 (%s), expected UTF-8 text"
                    % (_where(source, line, column), data[e.start], e.reason)) from e


def _read_text(path):
    # the file as text: UTF-8, a leading byte-order mark dropped
    data = _read_bytes(path)
    return _decode_utf8(data[len(_BOM):] if data.startswith(_BOM) else data, path)


class _NonFinite(Exception):
    # raised inside the JSON parser on NaN, Infinity or a number too large for a double
    pass


def _refuse_constant(token):
    raise _NonFinite(token)


def _finite_float(token):
    value = float(token)
    if not math.isfinite(value):
        raise _NonFinite(token)
    return value


def _non_finite_index(text):
    # where the first NaN, Infinity or overflowing number outside a string starts (the JSON
    # parser says what it refused, not where)
    i, in_string, escaped = 0, False, False
    while i < len(text):
        ch = text[i]
        if in_string:
            if escaped:
                escaped = False
            elif ch == "\\":
                escaped = True
            elif ch == '"':
                in_string = False
        elif ch == '"':
            in_string = True
        elif ch in "NI":
            return i
        elif ch in "-0123456789":
            j = i + 1
            while j < len(text) and text[j] in "+-.0123456789eE":
                j += 1
            token = text[i:j]
            # "-" starts -Infinity; an integer (no point, no exponent) is exact at any size
            if token == "-" or (any(c in token for c in ".eE") and not _is_finite_number(token)):
                return i
            i = j
            continue
        i += 1
    return 0


def _parse_json(text, source, first_line=1, error=InputError):
    # one JSON value; malformed JSON and non-finite numbers refused with line and column
    try:
        return json.loads(text, parse_constant=_refuse_constant, parse_float=_finite_float)
    except _NonFinite as e:
        line, column = _line_column(text, _non_finite_index(text), first_line)
        raise error("%s: %s is not a finite number, expected a finite number or null"
                    % (_where(source, line, column), e)) from None
    except json.JSONDecodeError as e:
        raise error("%s: not valid JSON (%s)"
                    % (_where(source, first_line + e.lineno - 1, e.colno), e.msg)) from None
    except RecursionError:
        raise error("%s: JSON nested too deeply" % _where(source, first_line)) from None


def _require_object(value, text, source, first_line, expected, error=InputError):
    # a JSON value that must be an object, refused with where it starts
    if isinstance(value, dict):
        return value
    start = len(text) - len(text.lstrip())
    line, column = _line_column(text, start, first_line)
    raise error("%s: %s, expected an object (%s)"
                % (_where(source, line, column), _JSON_TYPE.get(type(value), "a value"), expected))


def load_metrics(path):
    """metrics.json as a dict (docs/design.md section 8); InputError naming file and line."""
    text = _read_text(path)
    return _require_object(_parse_json(text, path), text, path, 1, "one run's metrics")


def _column_values(cells, rows_lines, path, name, column):
    # one log column: (its finite floats, None), or (None, (line, message)) for its first bad
    # cell
    try:
        values = np.array(cells, dtype=np.float64)
        bad = np.flatnonzero(~np.isfinite(values))
        first = int(bad[0]) if len(bad) else None
    except ValueError:
        values = None
        first = next(i for i, c in enumerate(cells) if not _is_finite_number(c))
    if first is None:
        return values, None
    return None, (rows_lines[first], "%s: column '%s' holds '%s', expected a finite number"
                  % (_where(path, rows_lines[first], column), name, cells[first]))


def _is_finite_number(cell):
    try:
        return math.isfinite(float(cell))
    except ValueError:
        return False


def load_log(path, pandas=False):
    """log.csv as {column: numpy array}, numbers as float and status as str (docs/design.md
    section 8); with pandas=True a pandas.DataFrame. InputError naming file, line and column."""
    reader = csv.reader(io.StringIO(_read_text(path), newline=""))
    try:
        header = next(reader, None)
        if header is None:
            raise InputError("%s: empty, expected a header line and one row per control step"
                             % _where(path, 1))
        body, rows_lines = [], []
        for row in reader:
            if len(row) != len(header):
                raise InputError("%s: %d field%s, expected %d as in the header (a truncated "
                                 "log?)" % (_where(path, reader.line_num), len(row),
                                            "" if len(row) == 1 else "s", len(header)))
            body.append(row)
            rows_lines.append(reader.line_num)
    except csv.Error as e:
        raise InputError("%s: not CSV (%s)" % (_where(path, reader.line_num), e)) from None
    # the header: unique names, none empty
    seen = {}
    for j, name in enumerate(header):
        if not name:
            raise InputError("%s: column %d has no name, expected a name in every column"
                             % (_where(path, 1, j + 1), j + 1))
        if name in seen:
            raise InputError("%s: column '%s' appears twice (columns %d and %d), expected "
                             "unique names" % (_where(path, 1, j + 1), name, seen[name] + 1, j + 1))
        seen[name] = j
    if not body:
        raise InputError("%s: a header and no rows, expected one row per control step"
                         % _where(path, 2))
    # the columns; of several bad cells the one on the earliest line is reported
    columns, first_bad = {}, None
    for j, name in enumerate(header):
        cells = [row[j] for row in body]
        if name in _TEXT_COLUMNS:
            columns[name] = np.array(cells)
            continue
        values, bad = _column_values(cells, rows_lines, path, name, j + 1)
        if bad is not None and (first_bad is None or bad[0] < first_bad[0]):
            first_bad = bad
        columns[name] = values
    if first_bad is not None:
        raise InputError(first_bad[1])
    if pandas:
        import pandas as pd  # optional: not part of the project's dependencies
        return pd.DataFrame(columns)
    return columns


def load_runs(path, pandas=False):
    """A sweep's runs.jsonl: one dict per run (its index, drawn values and metrics). A torn last
    line (no newline and not JSON: a killed sweep) is skipped with a warning, as `hpa sweep
    --resume` does; any other bad line is an InputError naming file and line."""
    data = _read_bytes(path)
    if data.startswith(_BOM):
        data = data[len(_BOM):]
    lines = data.split(b"\n")  # only "\n" ends a record: U+2028 may sit inside a JSON string
    runs = []
    for number, raw in enumerate(lines, start=1):
        if not raw.strip():
            continue
        torn = number == len(lines)  # the last piece has no newline after it
        try:
            text = _decode_utf8(raw, path, number)
            value = _parse_json(text, path, number)
        except InputError as e:
            if not torn:
                raise
            warnings.warn("%s (the torn last line of a killed sweep: no newline at its end; "
                          "skipped, hpa sweep --resume runs it again)" % e, stacklevel=2)
            continue
        runs.append(_require_object(value, text, path, number, "one run per line"))
    if pandas:
        import pandas as pd
        return pd.json_normalize(runs)
    return runs
