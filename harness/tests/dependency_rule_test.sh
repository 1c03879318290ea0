#!/usr/bin/env bash
# ctest build.dependency_rule: ci/dependency_rule.sh passes on the source tree, and fails, naming
# the file, on copies of it with one violation planted each (flight code including MuJoCo, GL,
# controller code including OpenCV, sim including flight code), so the check can fail.
#   dependency_rule_test.sh SOURCE_DIR WORK_DIR
set -euo pipefail
src=$1 work=$2
rule="$src/ci/dependency_rule.sh"
"$rule" "$src" || { echo "FAIL: the source tree breaks the dependency rule" >&2; exit 1; }
rm -rf "$work"
mkdir -p "$work"
# one planted include per case: FILE|LINE
cases=(
  "estimator/src/planted.cc|#include <mujoco/mujoco.h>"
  "flight/src/planted.h|#include <GL/gl.h>"
  "controller/src/planted.cc|#include <opencv2/core.hpp>"
  "models/src/planted.cc|#include <EGL/egl.h>"
  "sim/src/planted.cc|#include \"hpa/controller/hpa_mpc.h\""
  "sim/tests/planted_test.cc|#include \"hpa/estimator/estimator.h\""
)
for c in "${cases[@]}"; do
  file=${c%%|*} line=${c#*|}
  tree="$work/tree"
  rm -rf "$tree"
  mkdir -p "$tree"
  for d in models autopilot controller estimator flight sim; do cp -r "$src/$d" "$tree/"; done
  mkdir -p "$tree/$(dirname "$file")"
  echo "$line" > "$tree/$file"
  if out=$("$rule" "$tree" 2>&1); then
    echo "FAIL: '$line' in $file passed the rule" >&2
    exit 1
  fi
  grep -q "$file" <<<"$out" || { echo "FAIL: the rule's message does not name $file: $out" >&2; exit 1; }
done
# a test may include what its library may not (the rule is about flight code, not its tests)
tree="$work/tree"
rm -rf "$tree"
mkdir -p "$tree"
for d in models autopilot controller estimator flight sim; do cp -r "$src/$d" "$tree/"; done
echo "#include <mujoco/mujoco.h>" > "$tree/estimator/tests/planted_test.cc"
"$rule" "$tree" || { echo "FAIL: a flight-code test including MuJoCo was refused" >&2; exit 1; }
rm -rf "$work"
echo "dependency rule: holds on the tree; ${#cases[@]} planted violations each caught and named"
