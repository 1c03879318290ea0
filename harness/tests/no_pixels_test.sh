#!/usr/bin/env bash
# A separate stack that declares uses_pixels: false in its hello_ack is sent no rendered frame and
# the run renders none: on the rendered camera it flies as fast as on the analytic one, with the
# same tracking as the same stack receiving every frame, and metrics.json says the camera was not
# flown (camera "none", its counts and timings null, a bound on them not measured). The analytic
# camera is unaffected; a stack that would detect at capture without pixels is refused.
# usage: no_pixels_test.sh HPA_BIN SOURCE_DIR PYTHON
source "$(dirname "$0")/cli_test_lib.sh"
cli_test_start "$@"

cat > "$out/pixels.yaml" <<'YAML'
name: no_pixels
duration: 1.0
estimation: {camera: render}
reference: {type: hover, payload_position: [0, 0, 0.7]}
expect:
  payload_in_fov_min: 0.5
YAML
# the Python example (VIO and the gyro, no pixels) declaring it, and counting the frames it got
cat > "$out/no_pixels.py" <<PY
import sys
sys.path.insert(0, "$src/python")
sys.path.insert(0, "$src/examples/python")
import hpa_sim
import hover_controller as hc

class Counting(hc.HoverController):
    def step(self, tick):
        assert len(tick.frames) == 0, "a frame reached a stack that uses no pixels"
        return super().step(tick)

sys.exit(hpa_sim.run(Counting, name="no pixels", control_rate_hz=hc.CONTROL_RATE_HZ,
                     uses_pixels=False))
PY
# a stack that says it detects at capture and reads no pixels
cat > "$out/contradiction.py" <<PY
import json, sys
sys.path.insert(0, "$src/python")
from hpa_sim import lockstep
client = lockstep.FlightStackClient()
client.receive()
client.send(lockstep.HELLO_ACK, json.dumps({"protocol_version": 1, "name": "x",
    "detects_at_capture": True, "uses_pixels": False}).encode())
client.receive()
PY

example="$python $src/examples/python/hover_controller.py"
"$hpa" run "$out/pixels.yaml" --quiet --out "$out/frames" --flight-stack "$example" ||
  fail "the example on every frame exited $?"
"$hpa" run "$out/pixels.yaml" --quiet --out "$out/none" --flight-stack "$python $out/no_pixels.py"
[ $? -eq 1 ] || fail "the run without pixels did not fail its camera bound (exit 1)"
"$hpa" run "$out/pixels.yaml" --quiet --out "$out/analytic" --camera analytic \
  --flight-stack "$python $out/no_pixels.py" || fail "the analytic camera without pixels exited $?"
"$python" - "$out" <<'PY' || fail "the metrics of a stack that uses no pixels"
import json, sys
frames, none, analytic = (json.load(open(sys.argv[1] + "/" + d + "/metrics.json"))
                          for d in ("frames", "none", "analytic"))
# not flown: said, and null where the camera would have counted
assert frames["camera"] == "render" and frames["camera_frames"] > 0, frames["camera"]
assert none["camera"] == "none", none["camera"]
for key in ("camera_frames", "detections", "payload_in_fov_fraction", "render_ms", "image_model_ms",
            "detector_ms", "camera_region_fraction"):
    assert none[key] is None, (key, none[key])
assert none["vehicles"][0]["camera_frames"] is None, none["vehicles"]
assert none["expect"]["failed"] == ["payload_in_fov_min: not measured in this run"], none["expect"]
# the same flight: the example reads no pixels either way
for key in ("payload_rmse_m", "quad_rmse_m", "slack_events", "mode_accuracy"):
    assert none[key] == frames[key], (key, none[key], frames[key])
# no frame rendered: far faster than rendering every frame (measured 2.7 s against 31.8 s on
# hover_gripper_pull, 12 s simulated; here 1 s)
assert none["wall_time_s"] < 0.5 * frames["wall_time_s"], (none["wall_time_s"],
                                                            frames["wall_time_s"])
# the analytic camera sends detections, not pixels: flown as before
assert analytic["camera"] == "analytic" and analytic["camera_frames"] > 0, analytic["camera"]
PY
expect_exit 3 "detects_at_capture is true and uses_pixels false" run "$out/pixels.yaml" --quiet \
  --out "$out/contradiction" --flight-stack "$python $out/contradiction.py"

[ "$failures" -eq 0 ] || { echo "$failures check(s) failed"; exit 1; }
echo "no pixels: all checks passed"
