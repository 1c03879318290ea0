#!/usr/bin/python3
"""Checks the project's size limits on its C++ sources (docs/design.md, section 1): no source
file over 500 lines, and no function over 80 lines outside the tests (a test's table of cases may
run longer).

  source_sizes.py [SOURCE_DIR]     lists every file and function over its limit; exit 1 if any

A function is found as a line at namespace level that ends in `{` after a closing parenthesis
(a definition, not a namespace, class, struct or enum), and it ends where its braces close;
strings, characters and line comments are skipped when the braces are counted. The files are
those git tracks (*.cc, *.h) under SOURCE_DIR (default: this script's repository).
"""
import os
import re
import subprocess
import sys

MAX_FILE_LINES = 500
MAX_FUNCTION_LINES = 80

DEFINITION = re.compile(r"^[A-Za-z].*\)\s*(const)?\s*(override)?\s*(noexcept)?\s*\{\s*$")
NAMESPACE_OPEN = re.compile(r'^\s*(namespace|extern "C")[^{]*\{\s*$')
NAMESPACE_CLOSE = re.compile(r"^\s*}\s*//\s*namespace")


def code_of(line):
    """The line without its strings, characters and line comment."""
    line = re.sub(r'"([^"\\]|\\.)*"', '""', line)
    line = re.sub(r"'([^'\\]|\\.)*'", "''", line)
    return line.split("//")[0]


def long_functions(lines):
    """(first line number, length, signature) of every function over the limit."""
    found, depth, start = [], 0, None
    for number, raw in enumerate(lines, 1):
        if NAMESPACE_OPEN.match(raw) or NAMESPACE_CLOSE.match(raw):
            continue
        code = code_of(raw)
        if depth == 0 and start is None and DEFINITION.match(code) and not code.startswith(
                ("namespace", "struct", "class", "enum")):
            start = number
        depth += code.count("{") - code.count("}")
        if start is not None and depth == 0 and number > start:
            if number - start + 1 > MAX_FUNCTION_LINES:
                found.append((start, number - start + 1, lines[start - 1].strip()[:72]))
            start = None
    return found


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..")
    files = subprocess.run(["git", "-C", root, "ls-files", "*.cc", "*.h"], check=True,
                           capture_output=True, text=True).stdout.split()
    problems = []
    for name in files:
        with open(os.path.join(root, name), encoding="utf-8", errors="replace") as f:
            lines = f.read().split("\n")
        count = len(lines) - (lines[-1] == "")
        if count > MAX_FILE_LINES:
            problems.append(f"{name}: {count} lines (at most {MAX_FILE_LINES})")
        if "/tests/" in "/" + name:
            continue
        for start, length, signature in long_functions(lines):
            problems.append(f"{name}:{start}: a function of {length} lines (at most "
                            f"{MAX_FUNCTION_LINES}): {signature}")
    for p in problems:
        print(p)
    print(f"{len(files)} files: {len(problems)} over the limits")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
