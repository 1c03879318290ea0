#!/usr/bin/env bash
# The README's second command (and what .ci/run calls): installs what is needed, proves the
# dependency rule, builds everything and runs the whole test suite (unit, model-vs-physics,
# closed-loop scenario regressions, sweep checks).
set -euo pipefail
cd "$(dirname "$0")/.."
./ci/setup.sh

echo "== dependency rule: flight code (models, autopilot, estimator, controller, flight) never includes MuJoCo or GL"
if grep -rIl -e '#include *<mujoco' -e '#include *<GL/' -e 'OSMesa' \
     models autopilot controller estimator flight --include='*.h' --include='*.cc' | grep -v '/tests/'; then
  echo "dependency rule broken by the files above" >&2
  exit 1
fi
if grep -rIl '#include *<opencv' autopilot controller --include='*.h' --include='*.cc' | grep -v '/tests/'; then
  echo "autopilot/ and controller/ must not depend on OpenCV" >&2
  exit 1
fi

echo "== sim/ depends on models only (no flight code)"
if grep -rIl -e '#include "hpa/estimator' -e '#include "hpa/controller' -e '#include "hpa/autopilot' \
     sim/src sim/include sim/tests; then
  echo "sim/ depends on models only: the files above include flight code" >&2
  exit 1
fi

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
