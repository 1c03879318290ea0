#!/usr/bin/env bash
# The size limits on the C++ sources (scripts/source_sizes.py): the tree holds them, and a copy
# with a file of 501 lines and a function of 81 lines planted fails naming both (so the check can
# fail), while the same function in a test file is allowed.
# usage: source_sizes_test.sh SOURCE_DIR WORK_DIR
set -uo pipefail
src=$1; work=$2
check=(/usr/bin/python3 "$src/scripts/source_sizes.py")
"${check[@]}" "$src" || { echo "FAIL: the tree breaks the size limits"; exit 1; }

rm -rf "$work"; mkdir -p "$work/lib/src" "$work/lib/tests"
{
  echo "namespace hpa {"
  echo "int Long() {"
  for i in $(seq 1 78); do echo "  int x$i = $i;"; done
  echo "  return 0;"
  echo "}"
  echo "}  // namespace hpa"
} > "$work/lib/src/long_function.cc"
cp "$work/lib/src/long_function.cc" "$work/lib/tests/long_function_test.cc"
for i in $(seq 1 501); do echo "// line $i"; done > "$work/lib/src/long_file.h"
git -C "$work" init -q && git -C "$work" add -A
out=$("${check[@]}" "$work"); rc=$?
echo "$out"
[ "$rc" -eq 1 ] || { echo "FAIL: planted violations not found (exit $rc)"; exit 1; }
grep -q "lib/src/long_file.h: 501 lines" <<< "$out" || { echo "FAIL: the long file not named"; exit 1; }
grep -q "lib/src/long_function.cc:2: a function of 81 lines" <<< "$out" \
  || { echo "FAIL: the long function not named"; exit 1; }
grep -q "long_function_test.cc" <<< "$out" && { echo "FAIL: a test's function counted"; exit 1; }
echo "source sizes: the tree holds the limits, and planted violations are found"
