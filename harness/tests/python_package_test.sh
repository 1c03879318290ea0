#!/usr/bin/env bash
# The Python client as a package: `pip install ./python` into a fresh venv, offline (Debian's
# python3, setuptools and wheel; numpy from python3-numpy through --system-site-packages); the
# example stack flies from that venv with PYTHONPATH unset, importing the installed hpa_sim; a
# stack that raises ends its run with a run error naming the raising file:line and the exception.
# Usage: python_package_test.sh HPA_BIN SOURCE_DIR PYTHON3 VERSION (hpa's, CMakeLists.txt)
set -uo pipefail
hpa=$1
src=$2
python=$3
version=$4
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
unset PYTHONPATH PYTHONHOME PIP_INDEX_URL PIP_EXTRA_INDEX_URL
export PYTHONDONTWRITEBYTECODE=1

# setuptools builds in the folder it installs from (build/, *.egg-info): a copy, so the source tree
# is never written to
mkdir "$work/pkg" && cp -r "$src/python/pyproject.toml" "$src/python/hpa_sim" "$work/pkg/" \
  || fail "copying python/"
"$python" -m venv --system-site-packages "$work/venv" > "$work/venv.log" 2>&1 \
  || { cat "$work/venv.log"; fail "python3 -m venv --system-site-packages"; }
venv_python=$work/venv/bin/python
(cd "$work/pkg" && "$venv_python" -m pip install --no-index --no-build-isolation \
  --disable-pip-version-check . > "$work/pip.log" 2>&1) \
  || { cat "$work/pip.log"; fail "pip install --no-index --no-build-isolation ./python"; }

# the installed package is what a script in examples/python imports, at hpa's version
(cd "$src/examples/python" && "$venv_python" - "$work/venv" "$version") <<'PY' \
  || fail "the installed package"
import importlib.metadata
import os
import sys
import hpa_sim
venv, version = sys.argv[1], sys.argv[2]
where = os.path.realpath(hpa_sim.__file__)
assert where.startswith(os.path.realpath(venv) + os.sep), "hpa_sim imported from " + where
assert importlib.metadata.version("hpa-sim") == version, (importlib.metadata.version("hpa-sim"),
                                                          version)
import numpy  # noqa: F401  (Debian's, through --system-site-packages)
print("hpa_sim %s from %s" % (version, os.path.dirname(where)))
PY

# the example stack flown from the venv
cd "$src" || exit 1
"$hpa" run scenarios/hover.yaml --quiet --out "$work/run" \
  --flight-stack "$venv_python examples/python/hover_controller.py" > "$work/run.log" 2>&1
code=$?
"$venv_python" - "$work/run/metrics.json" "$code" <<'PY' \
  || { tail -20 "$work/run.log"; fail "the example stack's run"; }
import sys
from hpa_sim import load_metrics
m = load_metrics(sys.argv[1])
assert m["run_error"] is None, m["run_error"]
assert m["flight_stack"] == "python hover_controller", m["flight_stack"]
assert not m["crashed"], m["crash_reason"]
assert m["sim_time_s"] == 8.0, m["sim_time_s"]
print("example stack from the venv: exit %s, quad deviation %.3f m, expect %s"
      % (sys.argv[2], m["quad_position_deviation_max_m"],
         "passed" if m["expect"]["passed"] else "failed: %s" % m["expect"]["failed"]))
PY

# a stack that raises two calls below its step: the run error names the raising line
cat > "$work/raising_stack.py" <<'PY'
from hpa_sim import run


class Raises:
    def __init__(self, hello):
        self.gain = 2.0

    def step(self, tick):
        return self.command(tick) if tick.time_s >= 0.05 else None

    def command(self, tick):
        raise ValueError("boom at t = %.3f s" % tick.time_s)


raise SystemExit(run(Raises, name="raising"))
PY
line=$(grep -n "raise ValueError" "$work/raising_stack.py" | cut -d: -f1)
"$hpa" run scenarios/hover.yaml --quiet --out "$work/raising" \
  --flight-stack "$venv_python $work/raising_stack.py" > "$work/raising.log" 2>&1
code=$?
[ $code -eq 3 ] || fail "a raising stack's run exits $code, expected 3"
"$venv_python" - "$work/raising/metrics.json" "$work/raising_stack.py:$line in command" <<'PY' \
  || { tail -20 "$work/raising.log"; fail "the raising stack's run error"; }
import sys
from hpa_sim import load_metrics
error = load_metrics(sys.argv[1])["run_error"]
assert error is not None, "no run error"
for fragment in ("Traceback (last 3 frames", "in step; ", sys.argv[2] + "; ",
                 "ValueError: boom at t = 0.05"):
    assert fragment in error, "%r not in the run error: %s" % (fragment, error)
print("run error: " + error)
PY

echo "python_package_test: $failures failure(s)"
[ "$failures" -eq 0 ]
