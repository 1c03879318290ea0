#!/usr/bin/env bash
# The README's second command (and what .ci/run calls): installs what is needed, proves the
# dependency rule, builds everything and runs the whole test suite (unit, model-vs-physics,
# closed-loop scenario regressions, sweep checks). Each stage prints its wall time, so a slow
# CI run says where its minutes went.
set -euo pipefail
cd "$(dirname "$0")/.."
stage_start_s=$SECONDS
ci_start_s=$SECONDS
# stage_done NAME: prints the wall time of the stage that just ended and starts the next one
stage_done() {
  echo "== $1 took $((SECONDS - stage_start_s)) s (CI so far $((SECONDS - ci_start_s)) s)"
  stage_start_s=$SECONDS
}

./ci/setup.sh
stage_done "setup"

echo "== dependency rule (ci/dependency_rule.sh; also ctest build.dependency_rule)"
./ci/dependency_rule.sh

echo "== flight-only build (HPA_FLIGHT_ONLY=ON: no MuJoCo, no GL, no sim target)"
# Unoptimised (build type None: no -O flags): this build only proves that the flight code
# compiles and links without MuJoCo or GL; nothing runs from it.
cmake -S . -B build-flight -G Ninja -DCMAKE_BUILD_TYPE=None -DHPA_FLIGHT_ONLY=ON \
  -DHPA_BUILD_TESTS=OFF -DHPA_BUILD_BENCHMARKS=OFF > /dev/null
cmake --build build-flight -j "$(nproc)"
stage_done "dependency rule and flight-only build"

echo "== full build"
./ci/build.sh
stage_done "full build"

echo "== tests"
(cd build && ctest --output-on-failure -j "$(nproc)" --timeout 900)
stage_done "tests"

echo "== sanitizers (ASan + UBSan) and fuzzing"
./ci/sanitize.sh 60
stage_done "sanitizers and fuzzing"
