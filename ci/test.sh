#!/usr/bin/env bash
# The README's second command (and what .ci/run calls): installs what is needed, proves the
# dependency rule, builds everything and runs the whole test suite (unit, model-vs-physics,
# closed-loop scenario regressions, sweep checks).
set -euo pipefail
cd "$(dirname "$0")/.."
./ci/setup.sh

echo "== dependency rule (ci/dependency_rule.sh; also ctest build.dependency_rule)"
./ci/dependency_rule.sh

echo "== flight-only build (HPA_FLIGHT_ONLY=ON: no MuJoCo, no GL, no sim target)"
cmake -S . -B build-flight -G Ninja -DCMAKE_BUILD_TYPE=Release -DHPA_FLIGHT_ONLY=ON \
  -DHPA_BUILD_TESTS=OFF -DHPA_BUILD_BENCHMARKS=OFF > /dev/null
cmake --build build-flight -j "$(nproc)"

echo "== full build"
./ci/build.sh

echo "== tests"
cd build
ctest --output-on-failure -j "$(nproc)" --timeout 900

echo "== sanitizers (ASan + UBSan) and fuzzing"
cd ..
./ci/sanitize.sh 60
