"""A flight stack in Python over hpa-sim's lockstep protocol (docs/protocol.md).

`hpa run --flight-stack "python3 my_stack.py" SCENARIO` starts the script with
HPA_FLIGHT_SOCKET set. The script connects, receives the hello (the vehicle's parameters, the
reference, the rates), then answers one tick at a time: each tick carries the sensor messages
that reached the flight computer since the last one, and the reply carries the state estimate
and, when the controller runs, a body-rate + collective-thrust command. Simulated time waits for
each reply (lockstep), so a slow controller slows the run, never the simulated vehicle.

    from hpa_sim import run, Command
    class Hover:
        def __init__(self, hello): ...
        def step(self, tick):           # -> Command or None (keep the last command)
            ...
    run(Hover)
"""

import json
import mmap
import os
import socket
import struct
import sys
import traceback

import numpy as np

from .results import _decode_utf8, _parse_json, _require_object

PROTOCOL_VERSION = 1
MAGIC = 0x46415048  # "HPAF"
HELLO, HELLO_ACK, TICK, TICK_REPLY, FINISH, FINISH_REPLY, ERROR = range(1, 8)
MESSAGE_TYPES = {HELLO: "hello", HELLO_ACK: "hello_ack", TICK: "tick", TICK_REPLY: "tick_reply",
                 FINISH: "finish", FINISH_REPLY: "finish_reply", ERROR: "error"}
MAX_MESSAGE_BYTES = 64 << 20  # the simulator's own limit on a message body
ERROR_FRAMES = 3  # the innermost stack frames an error message names
# An error message's length: a run error is read by a person in metrics.json and on stderr, so a
# page of text, far inside MAX_MESSAGE_BYTES (the whole traceback goes to the stack's stderr)
ERROR_MAX_BYTES = 4096

_HAS_ALLOCATION, _SATURATED, _HAS_TRUTH, _NEED_ESTIMATE, _GRIPPER = 1, 2, 4, 8, 16
_TICK_FLAGS = "1 allocation, 2 mixer saturated, 4 truth, 8 estimate needed, 16 gripper"
_STATE_FLAGS = "1 payload visible, 2 payload lost, 4 payload supported"
_HAS_COMMAND, _HAS_ESTIMATE = 1, 2
STATUS = ["success", "max_iterations", "qp_failure", "non_finite", "fallback", "recovery"]
MODES = ["slack", "taut"]  # a state's cable mode by its wire value (0 slack, 1 taut)


class ProtocolError(RuntimeError):
    """A malformed or unexpected message; the text names the message and what was wrong."""


class Command:
    """Body rates (rad/s, body frame) and collective thrust (N) for the simulator's rate loop."""

    def __init__(self, w_B_radps, thrust_N, status="success", solve_time_ms=0.0, cost=0.0):
        self.w_B_radps = [float(v) for v in w_B_radps]
        self.thrust_N = float(thrust_N)
        self.status = status
        self.solve_time_ms = float(solve_time_ms)
        self.cost = float(cost)


class Tick:
    """One tick's inputs. imu: (n, 7) array [t_s, gyro_B (3) rad/s, accel_B (3) m/s^2];
    vio: (n, 11) array [t_s, p_WB_W (3) m, q_WB (w, x, y, z), v_WB_W (3) m/s] stamped with
    their capture time; detections: dicts (time_s, found, reason, p_CL_C, centre_px, radius_px);
    frames: dicts (capture_time_s, image: the whole (h, w, 3) uint8 BGR frame, a view valid
    during the tick); allocation: (thrust_allocated_N, saturated) or None; truth: a state dict (only with
    the scenario's ground-truth switch) or None; reference: dict p_WL_W, v_WL_W, a_WL_W."""

    __slots__ = ("time_s", "allocation", "imu", "vio", "detections", "frames", "truth",
                 "need_estimate", "gripper_active", "reference")


class _Reader:
    # reads one binary message; every refusal names the message ("malformed tick message: ...")
    def __init__(self, data, what):
        self.data, self.pos, self.what = data, 0, what

    def fail(self, why):
        raise ProtocolError("malformed %s message: %s" % (self.what, why))

    def take(self, fmt):
        size = struct.calcsize(fmt)
        if self.pos + size > len(self.data):
            self.fail("it ends early (byte %d of %d, %d more needed)"
                      % (self.pos, len(self.data), size))
        values = struct.unpack_from(fmt, self.data, self.pos)
        self.pos += size
        return values

    def f64s(self, n):
        return np.array(self.take("<%dd" % n))

    def u32(self):
        return self.take("<I")[0]

    def text(self, name):
        length = self.u32()
        if length > len(self.data) - self.pos:
            self.fail("%s of %d bytes, longer than the rest of the message" % (name, length))
        raw = bytes(self.data[self.pos:self.pos + length])
        self.pos += length
        try:
            return raw.decode("utf-8")
        except UnicodeDecodeError as e:
            bad = e
        self.fail("%s is not UTF-8 (byte %d of it, 0x%02x: %s)"
                  % (name, bad.start, raw[bad.start], bad.reason))

    def state(self, name):
        v = self.take("<20d")
        mode, flags = self.take("<II")
        if mode >= len(MODES):
            self.fail("%s cable mode %d, expected 0 slack or 1 taut" % (name, mode))
        if flags & ~7:
            self.fail("%s flags 0x%x with unknown bits, expected %s" % (name, flags, _STATE_FLAGS))
        return {"time_s": v[0], "p_WL_W": np.array(v[1:4]), "v_WL_W": np.array(v[4:7]),
                "p_WQ_W": np.array(v[7:10]), "v_WQ_W": np.array(v[10:13]),
                "q_WB": np.array(v[13:17]), "w_B": np.array(v[17:20]), "mode": MODES[mode],
                "payload_visible": bool(flags & 1), "payload_lost": bool(flags & 2),
                "payload_supported": bool(flags & 4)}


def _pack_state(s):
    def vec(key, n, default=0.0):
        v = s.get(key)
        return [default] * n if v is None else [float(x) for x in v]
    q = s.get("q_WB")
    q = [1.0, 0.0, 0.0, 0.0] if q is None else [float(x) for x in q]
    values = ([float(s.get("time_s", 0.0))] + vec("p_WL_W", 3) + vec("v_WL_W", 3) +
              vec("p_WQ_W", 3) + vec("v_WQ_W", 3) + q + vec("w_B", 3))
    flags = ((1 if s.get("payload_visible", False) else 0) | (2 if s.get("payload_lost", True) else 0)
             | (4 if s.get("payload_supported", False) else 0))
    mode = s.get("mode", "taut")
    if mode not in MODES:
        raise ValueError("estimate mode %r, expected one of %s" % (mode, ", ".join(MODES)))
    return struct.pack("<20dII", *values, MODES.index(mode), flags)


def decode_tick(data, what="tick"):
    """Decodes a tick (or finish: what="finish") message body into a Tick (frames without
    images); ProtocolError naming the message on a malformed one or an unknown flag or mode."""
    r = _Reader(data, what)
    t = Tick()
    t.time_s, flags = r.take("<dI")
    if flags & ~(_HAS_ALLOCATION | _SATURATED | _HAS_TRUTH | _NEED_ESTIMATE | _GRIPPER):
        r.fail("flags 0x%x with unknown bits, expected %s" % (flags, _TICK_FLAGS))
    if flags & _SATURATED and not flags & _HAS_ALLOCATION:
        r.fail("flags 0x%x: mixer saturated without an allocation" % flags)
    t.allocation = None
    if flags & _HAS_ALLOCATION:
        t.allocation = (r.take("<d")[0], bool(flags & _SATURATED))
    t.need_estimate = bool(flags & _NEED_ESTIMATE)
    t.gripper_active = bool(flags & _GRIPPER)
    ref = r.f64s(9)
    t.reference = {"p_WL_W": ref[0:3], "v_WL_W": ref[3:6], "a_WL_W": ref[6:9]}
    n = r.u32()
    t.imu = r.f64s(7 * n).reshape(n, 7)
    n = r.u32()
    t.vio = r.f64s(11 * n).reshape(n, 11)
    t.detections = []
    for i in range(r.u32()):
        time_s, found = r.take("<dI")
        if found > 1:
            r.fail("detection %d found %d, expected 0 or 1" % (i, found))
        v = r.f64s(6)
        reason = r.text("detection %d's reason" % i)
        t.detections.append({"time_s": time_s, "found": bool(found), "p_CL_C": v[0:3],
                             "centre_px": v[3:5], "radius_px": v[5], "reason": reason})
    t.frames = []
    for _ in range(r.u32()):
        capture_time_s, x, y, w, h, region_slot, whole_slot = r.take("<d4iII")
        t.frames.append({"capture_time_s": capture_time_s, "region": (x, y, w, h),
                         "region_slot": region_slot, "whole_slot": whole_slot, "image": None})
    t.truth = r.state("truth") if flags & _HAS_TRUTH else None
    if r.pos != len(data):
        r.fail("%d bytes after its end" % (len(data) - r.pos))
    return t


def decode_header(header):
    """(type, body length) of a 12-byte message header; ProtocolError on a bad magic, an unknown
    type or a body past MAX_MESSAGE_BYTES."""
    magic, kind, length = struct.unpack("<III", header)
    if magic != MAGIC:
        raise ProtocolError("not an hpa lockstep message (magic 0x%08x, expected 0x%08x)"
                            % (magic, MAGIC))
    if kind not in MESSAGE_TYPES:
        raise ProtocolError("message type %d, expected one of %s" % (kind, ", ".join(
            "%d %s" % item for item in MESSAGE_TYPES.items())))
    if length > MAX_MESSAGE_BYTES:
        raise ProtocolError("%s message of %d bytes, expected at most %d"
                            % (MESSAGE_TYPES[kind], length, MAX_MESSAGE_BYTES))
    return kind, length


def _field(obj, key, where, types):
    # a JSON field that must be there with one of the given types
    if key not in obj:
        raise ProtocolError("%s: no '%s'" % (where, key))
    if not isinstance(obj[key], types) or isinstance(obj[key], bool):
        raise ProtocolError("%s: '%s' is %r, expected %s"
                            % (where, key, obj[key], " or ".join(t.__name__ for t in types)))
    return obj[key]


def decode_hello(body):
    """The hello message's JSON object as a dict; ProtocolError naming the hello and, for bad
    UTF-8 or JSON, the line and column."""
    where = "hello message"
    text = _decode_utf8(body, where, error=ProtocolError)
    hello = _require_object(_parse_json(text, where, error=ProtocolError), text, where, 1,
                            "the run's parameters", error=ProtocolError)
    # another version's layout is unknown: the caller refuses it by its version
    if _field(hello, "protocol_version", where, (int,)) != PROTOCOL_VERSION:
        return hello
    camera = hello.get("camera")
    if camera is not None:
        where += "'s camera"
        if not isinstance(camera, dict):
            raise ProtocolError("%s: %r, expected an object" % (where, camera))
        _field(camera, "ring", where, (str,))
        for key in ("slots", "width_px", "height_px", "slot_bytes"):
            if _field(camera, key, where, (int,)) < 0:
                raise ProtocolError("%s: '%s' is %d, expected 0 or more"
                                    % (where, key, camera[key]))
        if camera["slot_bytes"] < 3 * camera["width_px"] * camera["height_px"]:
            raise ProtocolError("%s: 'slot_bytes' %d, expected at least 3 x width x height = %d"
                                % (where, camera["slot_bytes"],
                                   3 * camera["width_px"] * camera["height_px"]))
    return hello


def encode_reply(command, estimate, rejected=0, resets=0, frames_detected=0, camera_roi=(0, 0, 0, 0)):
    """Encodes a tick reply: a Command or None, a state dict or None, health counters and the
    region of interest (x, y, width, height pixels) the camera should read out next besides
    the whole frame (zero size: none)."""
    flags = (_HAS_COMMAND if command is not None else 0) | (_HAS_ESTIMATE if estimate is not None else 0)
    out = struct.pack("<I", flags)
    if command is not None:
        if command.status not in STATUS:
            raise ValueError("command status %r, expected one of %s"
                             % (command.status, ", ".join(STATUS)))
        out += struct.pack("<4dIdd", *command.w_B_radps, command.thrust_N,
                           STATUS.index(command.status), command.solve_time_ms, command.cost)
    if estimate is not None:
        out += _pack_state(estimate)
    return out + struct.pack("<III4i", rejected, resets, frames_detected, *camera_roi)


def describe_exception(exc, frames=ERROR_FRAMES, max_bytes=ERROR_MAX_BYTES):
    """The text an error message carries for an exception: its innermost `frames` stack frames
    as FILE:LINE in FUNCTION, then TYPE: MESSAGE, in at most max_bytes of UTF-8 (cut at the
    end, so a long exception text goes first), e.g. "Traceback (last 3 frames): a.py:10 in run;
    b.py:20 in step; b.py:7 in gains; ValueError: boom"."""
    stack = traceback.extract_tb(exc.__traceback__)
    shown = list(stack)[-frames:] if frames > 0 else []
    head = ""
    if shown:
        left_out = len(stack) - len(shown)
        head = "Traceback (last %d frame%s%s): %s; " % (
            len(shown), "" if len(shown) == 1 else "s",
            ", %d before them left out" % left_out if left_out else "",
            "; ".join("%s:%s in %s" % (f.filename, f.lineno, f.name) for f in shown))
    try:
        text = str(exc)
    except Exception:  # an exception whose __str__ fails still has a type
        text = "(its text could not be formatted)"
    data = (head + type(exc).__name__ + (": " + text if text else "")).encode("utf-8", "replace")
    if len(data) <= max_bytes:
        return data.decode("utf-8")
    # cut at a character boundary; the note's count has no more digits than len(data)
    note = " ... (%d bytes cut)" % len(data)
    kept = data[:max(0, max_bytes - len(note))].decode("utf-8", "ignore")
    return kept + " ... (%d bytes cut)" % (len(data) - len(kept.encode("utf-8")))


class FlightStackClient:
    """One connection to the simulator: messages in and out, and the frame ring."""

    def __init__(self, path=None):
        path = path or os.environ.get("HPA_FLIGHT_SOCKET")
        if not path:
            raise SystemExit("no HPA_FLIGHT_SOCKET: start this with hpa run --flight-stack")
        self.sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        self.sock.connect(path)
        self.ring = None

    def receive(self):
        """(type, body bytes) of the next message; ProtocolError on a bad header or an error."""
        kind, length = decode_header(self._read(12, "a message header"))
        body = self._read(length, "a %s message's body" % MESSAGE_TYPES[kind])
        if kind == ERROR:
            # the simulator's own report, shown even where its bytes are not UTF-8
            raise ProtocolError("the simulator reported: " + body.decode("utf-8", "replace"))
        return kind, body

    def send(self, kind, body):
        """Sends one message."""
        self.sock.sendall(struct.pack("<III", MAGIC, kind, len(body)) + body)

    def hello(self, name, control_rate_hz):
        """Receives the hello (a dict), maps the frame ring, answers with the ack."""
        kind, body = self.receive()
        if kind != HELLO:
            raise ProtocolError("expected a hello, got a %s message" % MESSAGE_TYPES[kind])
        hello = decode_hello(body)
        if hello["protocol_version"] != PROTOCOL_VERSION:
            self.send(ERROR, ("this client speaks protocol version %d" % PROTOCOL_VERSION).encode())
            raise ProtocolError("the simulator speaks protocol version %d" % hello["protocol_version"])
        camera = hello.get("camera")
        if camera:
            name_ = camera["ring"]
            fd = os.open("/dev/shm/" + name_.lstrip("/"), os.O_RDONLY)
            try:
                self.ring = mmap.mmap(fd, camera["slot_bytes"] * camera["slots"], prot=mmap.PROT_READ)
            finally:
                os.close(fd)
            self.camera = camera
        self.send(HELLO_ACK, json.dumps({"protocol_version": PROTOCOL_VERSION, "name": name,
                                         "control_rate_hz": control_rate_hz}).encode())
        return hello

    def attach_frames(self, tick):
        """Points each frame's "image" at its whole frame in the ring (a read-only numpy view)."""
        for f in tick.frames:
            if self.ring is None:
                raise ProtocolError("a tick at t = %g s carries a frame, but the hello had no "
                                    "camera" % tick.time_s)
            c = self.camera
            if not 0 <= f["whole_slot"] < c["slots"]:
                raise ProtocolError("a tick at t = %g s names ring slot %d, expected 0 to %d"
                                    % (tick.time_s, f["whole_slot"], c["slots"] - 1))
            offset = f["whole_slot"] * c["slot_bytes"]
            f["image"] = np.frombuffer(self.ring, dtype=np.uint8, count=c["width_px"] * c["height_px"] * 3,
                                       offset=offset).reshape(c["height_px"], c["width_px"], 3)

    def _read(self, n, what):
        chunks = []
        while n > 0:
            chunk = self.sock.recv(n)
            if not chunk:
                raise EOFError("the simulator closed the connection while this read %s" % what)
            chunks.append(chunk)
            n -= len(chunk)
        return b"".join(chunks)


def run(controller_class, name=None, control_rate_hz=0.0):
    """Serves one run: builds controller_class(hello) and calls its step(tick) every tick.
    step returns a Command (a new command), or None (the rate loop keeps the last one); the
    controller may set `estimate` (a state dict) for the simulator's log and rate loop, else the
    latest VIO pose and IMU rate are sent (before the first VIO sample, the hello's initial
    state)."""
    client = FlightStackClient()
    try:
        hello = client.hello(name or controller_class.__name__, control_rate_hz)
        controller = controller_class(hello)
        last_vio, last_gyro = None, np.zeros(3)
        # before the first VIO sample, the state the run starts from (the simulator refuses a
        # reply without the estimate a tick asks for)
        start = hello.get("config", {}).get("initial_state") or {}
        start = dict(start, q_WB=start.get("q_WB_wxyz", [1.0, 0.0, 0.0, 0.0]))
        while True:
            kind, body = client.receive()
            if kind not in (TICK, FINISH):
                raise ProtocolError("expected a tick or finish, got a %s message"
                                    % MESSAGE_TYPES[kind])
            tick = decode_tick(body, MESSAGE_TYPES[kind])
            if kind == FINISH:
                client.send(FINISH_REPLY, json.dumps({"estimator": "", "estimator_health": [],
                                                      "frames_detected": 0}).encode())
                return 0
            client.attach_frames(tick)
            if len(tick.vio):
                last_vio = tick.vio[-1]
            if len(tick.imu):
                last_gyro = tick.imu[-1, 1:4]
            command = controller.step(tick)
            estimate = getattr(controller, "estimate", None)
            if estimate is None and tick.truth is not None:
                estimate = tick.truth
            if estimate is None and last_vio is not None:
                estimate = {"p_WQ_W": last_vio[1:4], "q_WB": last_vio[4:8], "v_WQ_W": last_vio[8:11],
                            "w_B": last_gyro}
            if estimate is None:
                estimate = start
            estimate = dict(estimate, time_s=tick.time_s)
            client.send(TICK_REPLY, encode_reply(command, estimate))
    except EOFError:
        return 0
    except Exception as e:  # tell the simulator why and where (its run error), then fail
        try:
            client.send(ERROR, describe_exception(e).encode("utf-8", "replace"))
        except OSError:
            pass
        print("flight stack: %s: %s" % (type(e).__name__, e), file=sys.stderr)
        traceback.print_exc(file=sys.stderr)
        return 1
