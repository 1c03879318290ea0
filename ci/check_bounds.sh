#!/usr/bin/env bash
# Every shipped scenario's expect bounds on seeds they were not fitted on: runs each scenario
# (scenarios/*.yaml, scenarios/ci/*.yaml) on the ten seeds after those its bounds were derived
# from (1-30 unless its comment says otherwise, scripts/scenario_bounds.py) and lists every seed
# that fails; exit 1 if any does. With SEEDS, those seeds instead (1-40: the derivation seeds
# too). A developer tool (several minutes on 2 cores); ctest `cli.bounds_held_out` runs the seed
# after each file's derivation seeds.
# With --unseen, each file on 100 seeds from 100001 on, which no derivation uses, and a file fails
# when fewer than 99 of them pass (the bounds rule's tail allowance); it prints how many held.
# --from N starts those 100 seeds at N instead (100101: a second, fresh set for a file whose
# bounds were re-derived after its failures on the first set were seen).
#   ci/check_bounds.sh [SEEDS]     # SEEDS: first-last
#   ci/check_bounds.sh --unseen [--from N] [FILE...]
set -euo pipefail
cd "$(dirname "$0")/.."
hpa=${HPA_BUILD_DIR:-build}/bin/hpa
if [ "${1:-}" = --unseen ]; then
  shift
  from=100001
  if [ "${1:-}" = --from ]; then
    [ $# -ge 2 ] || { echo "ci/check_bounds.sh: --from needs a seed" >&2; exit 2; }
    from=$2
    shift 2
  fi
  [ $# -gt 0 ] || set -- scenarios/*.yaml scenarios/ci/*.yaml
  exec /usr/bin/python3 scripts/scenario_bounds.py --check --hpa "$hpa" --unseen 100 \
    --unseen-from "$from" "$@"
fi
if [ $# -gt 0 ]; then
  exec /usr/bin/python3 scripts/scenario_bounds.py --check --hpa "$hpa" --seeds "$1" \
    scenarios/*.yaml scenarios/ci/*.yaml
fi
exec /usr/bin/python3 scripts/scenario_bounds.py --check --hpa "$hpa" --held-out 10 \
  scenarios/*.yaml scenarios/ci/*.yaml
