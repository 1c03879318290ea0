#!/usr/bin/env bash
# Configures and builds hpa-sim in build/ (Release). Usage: ci/build.sh [extra cmake args]
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc)
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release "$@" > build.configure.log \
  || { cat build.configure.log; exit 1; }
cmake --build build -j "$jobs"
