#!/usr/bin/env bash
# The dependency rule (docs/design.md section 1), checked on a source tree: flight code (models,
# autopilot, estimator, controller, flight) never includes MuJoCo or GL, autopilot and controller
# never OpenCV (their tests may), and sim, its tests too, depends on models only (no flight code).
#   ci/dependency_rule.sh [SOURCE_DIR]     exit 1 naming each file that breaks the rule
set -uo pipefail
cd "${1:-$(dirname "$0")/..}" || exit 2
broken=0
# $1: what is wrong; $2: "tests" to hold the tests to it too; the rest: grep arguments; names
# every file that matches
check() {
  local what=$1 tests=$2
  shift 2
  local hits
  hits=$(grep -rIl "$@" --include='*.h' --include='*.hpp' --include='*.cc' --include='*.cpp' \
           2>/dev/null | { if [ "$tests" = tests ]; then cat; else grep -v '/tests/'; fi; })
  if [ -n "$hits" ]; then
    echo "dependency rule: $what:" >&2
    echo "$hits" | sed 's/^/  /' >&2
    broken=1
  fi
}
check "flight code includes MuJoCo or GL" no-tests -e '#include *<mujoco' -e '#include *<GL/' \
  -e 'OSMesa' -e '#include *<EGL/' models autopilot controller estimator flight
check "autopilot/ and controller/ depend on OpenCV" no-tests -e '#include *<opencv' autopilot controller
check "sim/ includes flight code (it depends on models only)" tests -e '#include "hpa/estimator' \
  -e '#include "hpa/controller' -e '#include "hpa/autopilot' -e '#include "hpa/flight' sim
exit $broken
