#!/bin/sh
# `hpa` with the Python example controller flying every `hpa run` (other commands unchanged), so
# that scripts/scenario_bounds.py derives and checks the bounds of the example's own scenario:
#   scripts/scenario_bounds.py examples/python/hover_gripper_pull_example.yaml --seeds 1-30 \
#     --hpa examples/python/hpa_example_stack.sh --write
# HPA_BIN: the hpa to run (default: build/bin/hpa of the source tree this folder is in, else the
# hpa on PATH); PYTHON: a python3 with numpy (default python3).
here=$(cd "$(dirname "$0")" && pwd)
hpa=${HPA_BIN:-$here/../../build/bin/hpa}
[ -n "${HPA_BIN:-}" ] || [ -x "$hpa" ] || hpa=hpa
if [ "$1" = run ]; then
  exec "$hpa" "$@" --flight-stack "${PYTHON:-python3} $here/hover_controller.py"
fi
exec "$hpa" "$@"
