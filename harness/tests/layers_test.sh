#!/usr/bin/env bash
# The harness layers (runner <- reports (hpa_output) <- sweeps and cli (hpa_tools)) as the build
# enforces them: compiled with a library's own include directories, a header of a layer above it
# is not found, and its own and those below are. Each check is an #if on __has_include, so nothing
# else is compiled.
# usage: layers_test.sh CXX RUNNER_INCLUDES OUTPUT_INCLUDES TOOLS_INCLUDES (;-separated lists)
set -uo pipefail
cxx=$1
declare -A includes=([runner]=$2 [output]=$3 [tools]=$4)
failures=0

# check LAYER EXPECT HEADER: compiling with LAYER's include directories, __has_include(HEADER)
# is EXPECT (true or false)
check() {
  local layer=$1 expect=$2 header=$3 flags=() dir
  IFS=';' read -r -a dirs <<< "${includes[$layer]}"
  for dir in "${dirs[@]}"; do [ -n "$dir" ] && flags+=("-I$dir"); done
  local op=""; [ "$expect" = false ] && op="!"
  if ! printf '#if %s__has_include("%s")\n#else\n#error\n#endif\n' "$op" "$header" |
      "$cxx" -std=c++17 -fsyntax-only "${flags[@]}" -x c++ - 2> /dev/null; then
    echo "FAIL: $layer: __has_include(\"$header\") is not $expect"
    failures=$((failures + 1))
  fi
}

# the runner sees its own headers, public and private, and neither output's nor tools'
check runner true hpa/scenarios/scenario.h
check runner true harness/runner/src/run_loop.h
check runner false hpa/scenarios/plots.h
check runner false hpa/scenarios/video_recorder.h
check runner false hpa/scenarios/cli.h
check runner false hpa/scenarios/sweep.h
check runner false harness/reports/src/media.h
check runner false harness/cli/src/cli_parse.h
check runner false harness/sweeps/src/sweep_internal.h
# output sees the runner's public headers and its own, not tools'
check output true hpa/scenarios/plots.h
check output true hpa/scenarios/runner.h
check output true harness/reports/src/media.h
check output false hpa/scenarios/cli.h
check output false hpa/scenarios/golden.h
check output false harness/cli/src/cli_parse.h
check output false harness/runner/src/run_loop.h
check output false harness/sweeps/src/sweep_internal.h
# tools sees every layer
check tools true hpa/scenarios/cli.h
check tools true hpa/scenarios/plots.h
check tools true harness/runner/src/flight_process.h
check tools true harness/sweeps/src/sweep_internal.h
check tools true harness/cli/src/cli_parse.h
check tools true hpa/scenarios/sweep.h
[ "$failures" -eq 0 ] || { echo "$failures layer check(s) failed"; exit 1; }
echo "the harness layers hold: runner <- reports <- sweeps and cli, enforced by each library's includes"
