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

echo "== flight-only configuration (HPA_FLIGHT_ONLY=ON: no MuJoCo, no GL, no sim target)"
# Configured only: that the flight code needs no MuJoCo or GL is proved on what is built, by
# ctest build.dependency_rule (no include of them under controller/, estimator/, flight/) and
# build.flight_program_links (hpa-flight holds no MuJoCo or GL symbol and needs no such
# library), so a second build of the flight code would only repeat them.
cmake -S . -B build-flight -G Ninja -DHPA_FLIGHT_ONLY=ON -DHPA_BUILD_TESTS=OFF \
  -DHPA_BUILD_BENCHMARKS=OFF > build-flight.configure.log \
  || { cat build-flight.configure.log; exit 1; }
stage_done "dependency rule and flight-only configuration"

echo "== full build"
./ci/build.sh
stage_done "full build"

echo "== tests"
(cd build && ctest --output-on-failure -j "$(nproc)" --timeout 900)
stage_done "tests"

echo "== sanitizers (ASan + UBSan) and fuzzing"
./ci/sanitize.sh 60
stage_done "sanitizers and fuzzing"
