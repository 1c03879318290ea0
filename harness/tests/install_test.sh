#!/usr/bin/env bash
# cmake --install puts hpa, hpa-flight, the libraries, headers, a CMake package and the data in a
# prefix; the installed binaries read the prefix's data from anywhere and write images and videos
# through the installed media module; a controller built out of tree against the installed
# package (find_package(hpa)) flies a scenario, and my_hpa (hpa's command line with it
# registered) writes images from its build folder and, installed into the prefix, after the
# prefix is moved (the build is configured for another prefix, so nothing is found there).
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
         share/hpa/python/pyproject.toml \
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

# The media module a command loaded (the dynamic loader's own record) must be the one in `want`.
# Usage: media_from WANT_FOLDER LOG COMMAND...
media_from() {
  local want=$1 log=$2
  shift 2
  LD_DEBUG=files "$@" > "$log" 2>&1
  local code=$?
  local loaded
  loaded=$(grep -o 'file=[^ ]*libhpa_media.so' "$log" | tail -1 | sed 's/^file=//')
  [ -n "$loaded" ] && [ "$(realpath "$loaded")" = "$(realpath "$want")/libhpa_media.so" ] \
    || { echo "loaded '$loaded', expected $want/libhpa_media.so"; return 1; }
  return $code
}
hover_args=(--set duration=2.5 --camera analytic --quiet)

# my_hpa from its build folder: pd_hover beside hpa's controllers, the package's data
# (UsePackageDataDir) and the package's media module, found from the data folder's prefix
text=$(./oot/my_hpa --help)
grep -q "pd_hover .*built out of tree" <<< "$text" || fail "my_hpa --help lists no pd_hover: $text"
media_from "$prefix/lib/hpa" oot_run.log ./oot/my_hpa run "$prefix/share/hpa/scenarios/hover.yaml" \
  --controller pd_hover --out oot_run --plots "${hover_args[@]}" \
  && [ -s oot_run/tracking.png ] && grep -q '"controller": "pd_hover"' oot_run/metrics.json \
  || { tail -5 oot_run.log; fail "my_hpa run --plots from its build folder"; }

# my_hpa and fly_pd_hover installed into hpa's prefix, and the prefix moved
cmake --install oot --prefix "$prefix" >> oot.log 2>&1 || { cat oot.log; fail "installing my_hpa"; }
moved="$elsewhere/moved/prefix"
mkdir -p "$elsewhere/moved" && mv "$prefix" "$moved" || fail "moving the prefix"
version=$("$moved/bin/my_hpa" --version)
grep -q "data: $moved/bin/../share/hpa" <<< "$version" || fail "the moved my_hpa reads: $version"
media_from "$moved/lib/hpa" moved_compare.log "$moved/bin/my_hpa" compare \
  "$moved/share/hpa/scenarios/hover.yaml" --controllers pd_hover,geometric --out moved_compare \
  "${hover_args[@]}"
code=$?
{ [ $code -eq 0 ] || [ $code -eq 1 ]; } && [ -s moved_compare/comparison.png ] \
  && [ -s moved_compare/pd_hover/metrics.json ] \
  || { tail -5 moved_compare.log; fail "the moved my_hpa compare (exit $code)"; }
media_from "$moved/lib/hpa" moved_frame.log "$moved/bin/my_hpa" render-frame \
  "$moved/share/hpa/scenarios/hover.yaml" --at 0.1 --out moved_frame.png --controller pd_hover \
  && [ -s moved_frame.png ] || { tail -5 moved_frame.log; fail "the moved my_hpa render-frame"; }
media_from "$moved/lib/hpa" moved_hpa.log "$moved/bin/hpa" render-frame \
  "$moved/share/hpa/scenarios/hover.yaml" --at 0.1 --out moved_hpa_frame.png \
  && [ -s moved_hpa_frame.png ] || { tail -5 moved_hpa.log; fail "the moved hpa render-frame"; }
flown=$("$moved/bin/fly_pd_hover") || fail "the moved fly_pd_hover: $flown"
grep -q "data from $moved/bin/../share/hpa" <<< "$flown" \
  || fail "the moved fly_pd_hover read its data elsewhere: $flown"

# the build folder's my_hpa after the move: the package's data is gone, so it names the places it
# looked in; pointed at the moved data, it finds the moved media module from there
text=$(./oot/my_hpa run "$moved/share/hpa/scenarios/hover.yaml" --out stale "${hover_args[@]}" 2>&1)
[ $? -eq 2 ] && grep -q "data folder.*not found" <<< "$text" \
  || fail "my_hpa with its package moved away: $text"
HPA_DATA_DIR="$moved/share/hpa" media_from "$moved/lib/hpa" oot_moved.log ./oot/my_hpa \
  render-frame "$moved/share/hpa/scenarios/hover.yaml" --at 0.1 --out oot_moved.png \
  && [ -s oot_moved.png ] || { tail -5 oot_moved.log; fail "my_hpa with HPA_DATA_DIR moved"; }

echo "install_test: $failures failure(s)"
[ "$failures" -eq 0 ]
