#!/usr/bin/env bash
# Installs every Debian 12 package hpa-sim needs. Idempotent; run as root.
# Why each package is here is in README.md ("Dependencies").
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config git
  libmujoco-dev            # physics (MuJoCo 2.2.2) and its renderer
  libosmesa6-dev           # headless OpenGL context for off-screen camera rendering
  libegl-dev libegl-mesa0  # --gl egl: EGL headers (libEGL is dlopen'ed) and Mesa's EGL driver
  libeigen3-dev            # linear algebra in models, estimator, controller
  libopencv-core-dev libopencv-imgproc-dev libopencv-imgcodecs-dev libopencv-videoio-dev
                           # payload detector, PNG frames and plots, MP4 video
  libcairo2-dev            # SVG and PDF plots (OpenCV writes raster images only)
  libnlopt-cxx-dev         # fully converged NMPC solve (checks the RTI solver)
  libyaml-cpp-dev          # params.yaml, scenario and sweep files
  nlohmann-json3-dev       # every JSON file written and read (metrics, runs.jsonl, summaries)
  libcli11-dev             # command-line parsing of hpa golden and hpa sweep-diff
  libgtest-dev libgmock-dev  # unit and integration tests
  libbenchmark-dev         # mpc_bench and other benchmarks
  python3-numpy            # the Python flight-stack client and result loaders (python/hpa_sim)
  python3-venv python3-pip # hpa_sim pip-installed offline into a venv (ctest python.package)
  python3-matplotlib       # scripts/redraw_plots.py redraws plots from their CSV (cli.redraw_plots)
  parallel                 # shard sweeps across processes/machines (CI runs two shards)
  slurm-wlm munge          # a single-node Slurm cluster: the job-array sweep test
  clang-14 libclang-rt-14-dev  # ASan + UBSan build and libFuzzer (ci/sanitize.sh)
)

if [ "$(id -u)" -ne 0 ]; then
  echo "ci/setup.sh: must run as root (apt-get install)" >&2
  exit 1
fi

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "ci/setup.sh: all ${#packages[@]} packages already installed"
  exit 0
fi
echo "ci/setup.sh: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
apt-get install -y -qq --no-install-recommends "${missing[@]}"
echo "ci/setup.sh: done"
