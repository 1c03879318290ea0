#!/usr/bin/env bash
# Every shipped scenario's expect bounds on seeds they were not all fitted on: runs each scenario
# (scenarios/*.yaml, scenarios/ci/*.yaml) on seeds 1-40 (the bounds come from seeds 1-30,
# scripts/scenario_bounds.py) and lists every seed that fails; exit 1 if any does. A developer
# tool (about 15 min on 2 cores); ctest `cli.bounds_held_out` runs seeds 31-32 of every scenario.
#   ci/check_bounds.sh [SEEDS]     # SEEDS: first-last, default 1-40
set -euo pipefail
cd "$(dirname "$0")/.."
hpa=${HPA_BUILD_DIR:-build}/bin/hpa
exec /usr/bin/python3 scripts/scenario_bounds.py --check --hpa "$hpa" --seeds "${1:-1-40}" \
  scenarios/*.yaml scenarios/ci/*.yaml
