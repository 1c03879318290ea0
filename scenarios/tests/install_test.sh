#!/usr/bin/env bash
# cmake --install puts hpa, hpa-flight, the libraries, headers, a CMake package and the data in a
# prefix; the installed binaries read the prefix's data from anywhere and write images and videos
# through the installed media module; a controller built out of tree against the installed
# package (find_package(hpa)) flies a scenario.
# Usage: install_test.sh BUILD_DIR SOURCE_DIR
set -uo pipefail
build=$1
src=$2
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }
prefix=$(mktemp -d)
elsewhere=$(mktemp -d)
trap 'rm -rf "$prefix" "$elsewhere"' EXIT

cmake --install "$build" --prefix "$prefix" > "$elsewhere/install.log" 2>&1 \
  || { cat "$elsewhere/install.log"; fail "cmake --install"; }
for f in bin/hpa bin/hpa-flight lib/cmake/hpa/hpaConfig.cmake lib/libhpa_runner.a \
         include/hpa/scenarios/runner.h include/hpa/flight/protocol.h \
         share/hpa/models/params.yaml share/hpa/models/scene.xml share/hpa/models/profiles/flight.yaml \
         share/hpa/scenarios/hover.yaml share/hpa/python/hpa_sim/lockstep.py \
         lib/hpa/libhpa_media.so; do
  [ -e "$prefix/$f" ] || fail "not installed: $f"
done

cd "$elsewhere" || exit 1
version=$("$prefix/bin/hpa" --version)
grep -q "data: $prefix/bin/../share/hpa" <<< "$version" || fail "the installed hpa reads: $version"
"$prefix/bin/hpa" run "$prefix/share/hpa/scenarios/hover.yaml" --quiet --out run \
  || fail "the installed hpa run"
"$prefix/bin/hpa" run "$prefix/share/hpa/scenarios/hover.yaml" --quiet --out run_flight \
  --flight-stack hpa-flight || fail "the installed hpa with the installed hpa-flight"
grep -q '"flight_stack": "hpa-flight' run_flight/metrics.json || fail "hpa-flight did not fly"

# images and videos go through lib/hpa/libhpa_media.so, which a run that writes neither never loads
"$prefix/bin/hpa" render-frame "$prefix/share/hpa/scenarios/hover.yaml" --at 0.1 --out frame.png \
  > /dev/null && [ -s frame.png ] || fail "the installed hpa writing a PNG"
"$prefix/bin/hpa" run "$prefix/share/hpa/scenarios/hover.yaml" --quiet --out run_video \
  --set duration=2.5 --video run_video.mp4 && [ -s run_video.mp4 ] \
  || fail "the installed hpa writing a video"
mv "$prefix/lib/hpa/libhpa_media.so" "$elsewhere/media.away"
"$prefix/bin/hpa" run "$prefix/share/hpa/scenarios/hover.yaml" --quiet --out run_nomedia \
  --set duration=2.5 || fail "a run that writes no image needs no media module"
text=$("$prefix/bin/hpa" render-frame "$prefix/share/hpa/scenarios/hover.yaml" --at 0.1 \
  --out nomedia.png 2>&1)
[ $? -ne 0 ] && grep -q "libhpa_media.so could not be loaded" <<< "$text" \
  || fail "without its media module: $text"
mv "$elsewhere/media.away" "$prefix/lib/hpa/libhpa_media.so"

# without its data an installed hpa names the places it looked in, never a source tree
mv "$prefix/share/hpa/models/params.yaml" "$elsewhere/params.yaml.away"
text=$("$prefix/bin/hpa" run "$prefix/share/hpa/scenarios/hover.yaml" --quiet --out nodata 2>&1)
[ $? -eq 2 ] && grep -q "data folder.*not found.*holds no models/params.yaml" <<< "$text" \
  || fail "the installed hpa without its data: $text"
mv "$elsewhere/params.yaml.away" "$prefix/share/hpa/models/params.yaml"
text=$(HPA_DATA_DIR=/nonexistent "$prefix/bin/hpa" run "$prefix/share/hpa/scenarios/hover.yaml" \
  --quiet --out baddata 2>&1)
[ $? -eq 2 ] && grep -q "HPA_DATA_DIR.*holds no models/params.yaml" <<< "$text" \
  || fail "a wrong HPA_DATA_DIR: $text"

cmake -S "$src/examples/out_of_tree_controller" -B oot -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$prefix" > oot.log 2>&1 && cmake --build oot >> oot.log 2>&1 \
  || { cat oot.log; fail "building the out-of-tree controller against the package"; }
flown=$(./oot/fly_pd_hover) || fail "the out-of-tree controller: $flown"
echo "$flown"
grep -q "data from $prefix/share/hpa" <<< "$flown" || fail "it read its data elsewhere: $flown"

echo "install_test: $failures failure(s)"
[ "$failures" -eq 0 ]
