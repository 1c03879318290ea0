#!/usr/bin/env python3
"""Flight stacks that misbehave, for the lockstep interface's tests: `hostile_flight_stack.py
MODE` with MODE one of: hang (acks, then never answers a tick), version (acks with protocol
version 99), nan (answers with a NaN thrust), garbage (answers with bytes that are not a
message), die (exits after 50 ticks), batched_hang (declares batched ticks, then never answers),
batched_nocommand (declares batched ticks at 100 Hz, then answers its control ticks without a
command)."""

import json
import os
import socket
import struct
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "python"))
from hpa_sim import lockstep  # noqa: E402

mode = sys.argv[1]
client = lockstep.FlightStackClient()
kind, body = client.receive()
version = 99 if mode == "version" else lockstep.PROTOCOL_VERSION
ack = {"protocol_version": version, "name": "hostile " + mode, "control_rate_hz": 100}
if mode.startswith("batched"):
    ack["batched_ticks"] = True
client.send(lockstep.HELLO_ACK, json.dumps(ack).encode())
ticks = 0
while True:
    kind, body = client.receive()
    tick = lockstep.decode_tick(body)
    ticks += 1
    if mode in ("hang", "batched_hang"):
        time.sleep(3600)
    if tick.no_reply:
        continue
    if mode == "batched_nocommand":
        client.send(lockstep.TICK_REPLY, lockstep.encode_reply(None, {"time_s": tick.time_s}))
        continue
    if mode == "die" and ticks > 50:
        sys.exit(7)
    if mode == "garbage":
        client.sock.sendall(b"GET / HTTP/1.1\r\n\r\n")
        continue
    thrust = float("nan") if mode == "nan" else 8.0
    # a level vehicle at the origin as its estimate (the simulator refuses a command without one)
    client.send(lockstep.TICK_REPLY, lockstep.encode_reply(lockstep.Command([0, 0, 0], thrust),
                                                           {"time_s": tick.time_s}))
