#!/usr/bin/env python3
"""Flight stacks that send what the simulator must refuse at the protocol's boundary, for
flight_boundary_test.sh: `hostile_boundary_stack.py MODE`. Until its mode acts, a stack hovers:
it answers every tick with the hover thrust, zero body rates and a level estimate.

MODE: ok (hovers to the end), hang (never answers a tick), split (its first reply's header
after 0.8 s, the body 0.8 s later), error_utf8 / ack_utf8 / finish_utf8 (an error message, a
hello_ack name, a finish_reply estimator name with bytes that are not UTF-8), truncate_ring
(cuts the frame ring to 0 bytes, then answers), frames_1000, frames_negative, counters_max,
solve_negative, cost_negative, quaternion_zero, quaternion_double (in tick replies),
no_estimate (answers every tick with neither estimate nor command), version_fraction,
version_wrap (in the hello_ack), finish_frames_huge, finish_frames_negative, health_variant (in
the finish_reply).

With HOSTILE_MARK set, the stack creates that file when its first tick arrives."""

import json
import os
import struct
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "python"))
from hpa_sim import lockstep  # noqa: E402

mode = sys.argv[1]
client = lockstep.FlightStackClient()
kind, body = client.receive()
hello = json.loads(body)
params = hello["config"]["params"]
hover_thrust_N = (params["quad_mass_kg"] + params["payload_mass_kg"]) * params["gravity_mps2"]

ack = {"protocol_version": lockstep.PROTOCOL_VERSION, "name": "boundary " + mode,
       "control_rate_hz": 1000}
if mode == "version_fraction":
    ack["protocol_version"] = 1.9
if mode == "version_wrap":
    ack["protocol_version"] = 4294967297
ack_body = json.dumps(ack).encode()
if mode == "ack_utf8":
    ack_body = b'{"protocol_version": 1, "name": "boundary \xff\xfe ack"}'
client.send(lockstep.HELLO_ACK, ack_body)


def reply(tick):
    """The tick's reply: hover command and level estimate, with the mode's one bad value."""
    solve_ms = -1e9 if mode == "solve_negative" else 0.1
    cost = -4e302 if mode == "cost_negative" else 1.0
    q = {"quaternion_zero": (0, 0, 0, 0), "quaternion_double": (2, 0, 0, 0)}.get(mode, (1, 0, 0, 0))
    estimate = command = mode != "no_estimate"
    out = struct.pack("<I", (1 if command else 0) | (2 if estimate else 0))
    if command:
        out += struct.pack("<4dIdd", 0, 0, 0, hover_thrust_N, 0, solve_ms, cost)
    if estimate:
        p_WQ_W = hello["config"]["initial_state"]["p_WQ_W"]
        out += struct.pack("<20dII", tick.time_s, *([0.0] * 6), *p_WQ_W, 0, 0, 0, *q, 0, 0, 0, 1, 2)
    counters = {"frames_1000": (0, 0, 1000), "frames_negative": (0, 0, -5),
                "counters_max": (2**32 - 1, 2**32 - 1, 0)}.get(mode, (0, 0, 0))
    out += struct.pack("<3I", *[c & 0xFFFFFFFF for c in counters])
    return out + struct.pack("<4i", 0, 0, 0, 0)


ticks = 0
while True:
    kind, body = client.receive()
    if kind == lockstep.FINISH:
        finish = {"estimator": "boundary", "estimator_health": [["rejected_updates", 0]],
                  "frames_detected": 0}
        if mode == "finish_frames_huge":
            finish["frames_detected"] = 1e300
        if mode == "finish_frames_negative":
            finish["frames_detected"] = -5
        if mode == "health_variant":
            finish["estimator_health"] = [["variant", 3]]
        finish_body = json.dumps(finish).encode()
        if mode == "finish_utf8":
            finish_body = b'{"estimator": "boundary \xc3\x28 finish"}'
        client.send(lockstep.FINISH_REPLY, finish_body)
        sys.exit(0)
    tick = lockstep.decode_tick(body)
    ticks += 1
    if ticks == 1 and os.environ.get("HOSTILE_MARK"):
        open(os.environ["HOSTILE_MARK"], "w").close()
    if mode == "hang":
        time.sleep(3600)
    if mode == "error_utf8":
        client.send(lockstep.ERROR, b"boundary: bad bytes \xff\xfe in my error")
        sys.exit(1)
    if mode == "truncate_ring" and ticks == 1:
        ring = "/dev/shm/" + hello["camera"]["ring"].lstrip("/")
        os.chmod(ring, 0o600)  # the simulator made it read-only: only on purpose
        os.truncate(ring, 0)
    body = reply(tick)
    if mode == "split" and ticks == 1:
        header = struct.pack("<III", lockstep.MAGIC, lockstep.TICK_REPLY, len(body))
        time.sleep(0.8)
        client.sock.sendall(header)
        time.sleep(0.8)
        client.sock.sendall(body)
        continue
    client.send(lockstep.TICK_REPLY, body)
