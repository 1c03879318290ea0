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

A stack that runs the vehicle's rate loop itself passes owns_rate_loop=True and gives its class a
rate_loop(rate_tick) method returning a RotorCommand (rotor speeds in rad/s): the simulator then
runs no autopilot of its own (docs/protocol.md, rate_tick and rate_reply).

A team scenario's stack (docs/protocol.md, Teams) is served by run_team: it receives the
team_hello, builds one controller per vehicle it flies, and at each of the team's control steps
calls each vehicle's step(view) with a TeamView, which returns that vehicle's Command:

    from hpa_sim import run_team, Command
    class Hold:
        def __init__(self, hello, vehicle): ...
        def step(self, view):           # -> Command
            ...
    run_team(Hold, control_rate_hz=100.0)
"""

import json
import math
import mmap
import os
import socket
import struct
import sys
import time
import traceback

import numpy as np

from .results import _decode_utf8, _parse_json, _require_object


def _load_table():
    # the message table beside this file (installed with the package): the one declaration of
    # every message, which the C++ side compiles in
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "messages.json")
    with open(path, encoding="utf-8") as f:
        return json.load(f)


TABLE = _load_table()  # the message table (messages.json): framing, message types, structs
PROTOCOL_VERSION = TABLE["protocol_version"]
MAGIC = TABLE["magic"]  # "HPAF"
MESSAGE_TYPES = {t["id"]: t["name"] for t in TABLE["message_types"]}
_TYPE_IDS = {name: kind for kind, name in MESSAGE_TYPES.items()}
HELLO, HELLO_ACK, TICK, TICK_REPLY, FINISH, FINISH_REPLY, ERROR, RATE_TICK, RATE_REPLY = (
    _TYPE_IDS[name] for name in ("hello", "hello_ack", "tick", "tick_reply", "finish",
                                 "finish_reply", "error", "rate_tick", "rate_reply"))
TEAM_HELLO, TEAM_HELLO_ACK, TEAM_TICK, TEAM_TICK_REPLY = (
    _TYPE_IDS[name] for name in ("team_hello", "team_hello_ack", "team_tick", "team_tick_reply"))
# a team's control loop: the rates a team_hello_ack may declare (Hz), (0, this]
MAX_TEAM_CONTROL_RATE_HZ = 1000.0
MAX_MESSAGE_BYTES = TABLE["max_message_bytes"]  # the simulator's own limit on a message body
# the JSON messages' keys, by message name: the table's declarations (name, type, required, doc)
JSON_KEYS = {t["name"]: t["keys"] for t in TABLE["message_types"] if t["encoding"] == "json"}
_JSON_TYPES = {"integer": (int,), "number": (int, float), "string": (str,), "bool": (bool,),
               "object": (dict,), "array": (list,)}
ERROR_FRAMES = 3  # the innermost stack frames an error message names
# An error message's length: a run error is read by a person in metrics.json and on stderr, so a
# page of text, far inside MAX_MESSAGE_BYTES (the whole traceback goes to the stack's stderr)
ERROR_MAX_BYTES = 4096


class ProtocolError(RuntimeError):
    """A malformed or unexpected message; the text names the message and what was wrong."""


def _format(text, **values):
    # an error template of the table with each {name} replaced (as the C++ side fills them)
    for name, value in values.items():
        text = text.replace("{" + name + "}", str(value))
    return text


def _error(key, **values):
    return _format(TABLE["errors"][key], **values)


def _shown_value(v):
    return "%.17g" % v  # every digit that tells a number apart


def _shown_limit(v):
    return "%.15g" % v  # a declared limit as it was written


def _in(at):
    return at + " " if at else ""


def _of(at):
    return at + "'s " if at else ""


class _Field:
    """One field of a struct of the table, resolved: its base kind, size and checks."""

    def __init__(self, spec, structs):
        self.name = spec["name"]
        self.label = spec.get("label", self.name)
        kind = spec["type"]
        checks = dict(spec)
        named = TABLE["types"].get(kind, {})
        if "base" in named:  # a named type refines its base type with checks
            checks = dict(named, **spec)
            kind = named["base"]
        base = ("f64", "u32", "i32", "bool", "enum", "flags", "text")
        self.kind = kind if kind in base else "struct"
        self.type = structs(kind) if self.kind == "struct" else None
        self.count = spec.get("count", 1)
        self.list = spec.get("list", False)
        self.item = spec.get("item", self.name)
        self.values = spec.get("values", [])
        self.bits = spec.get("bits", [])
        self.present_if = spec.get("present_if")
        self.gate = 0
        self.finite = checks.get("finite", False)
        self.min = checks.get("min")
        self.max = checks.get("max")
        self.refused = checks.get("refused", "")
        self.checked = self.finite or self.min is not None or self.max is not None
        self.unit_quaternion = spec.get("unit_quaternion")
        self.fmt = "<%d%s" % (self.count, {"f64": "d", "u32": "I", "i32": "i"}.get(self.kind, "I"))
        self.default = spec.get("default")
        if self.default is None:
            zeros = {"f64": 0.0, "u32": 0, "i32": 0, "bool": False, "text": ""}
            self.default = zeros.get(self.kind)
            if self.kind in ("f64", "u32", "i32") and self.count > 1:
                self.default = [self.default] * self.count
            if self.kind == "enum":
                self.default = self.values[0]
        if self.list or self.kind == "text":
            self.min_bytes = 4
        elif self.kind == "struct":
            self.min_bytes = self.type.min_bytes
        else:
            self.min_bytes = self.count * (8 if self.kind == "f64" else 4)


class _Struct:
    """A struct of the table: its fields in wire order. One of f64 fields alone, unchecked and
    always there, is a row: a list of them decodes to an (n, width) float array."""

    def __init__(self, name, structs):
        self.name = name
        self.fields, bits, self.gates = [], {}, {}
        for spec in TABLE["structs"][name]["fields"]:
            f = _Field(spec, structs)
            if f.present_if is not None:
                f.gate = bits[f.present_if]
                self.gates[f.gate] = f.name
            for b in f.bits:
                bits[b["name"]] = b["value"]
            self.fields.append(f)
        self.min_bytes = sum(f.min_bytes for f in self.fields if not f.gate)
        self.rows = all(f.kind == "f64" and not f.gate and not f.checked for f in self.fields)
        self.width = sum(f.count for f in self.fields)


def _structs():
    # every struct of the table, resolved (a struct's fields resolve the structs they hold)
    resolved = {}

    def find(name):
        if name not in resolved:
            if name not in TABLE["structs"]:
                raise ValueError("messages.json: unknown type %r" % name)
            resolved[name] = _Struct(name, find)
        return resolved[name]

    for name in TABLE["structs"]:
        find(name)
    return resolved


STRUCTS = _structs()  # the table's structs by name, resolved
_LAYOUTS = {t["name"]: t["layout"] for t in TABLE["message_types"] if "layout" in t}


def _field_of(struct, name):
    return next(f for f in STRUCTS[struct].fields if f.name == name)


STATUS = _field_of("control_output", "status").values  # a command's status by its wire value
MODES = _field_of("state", "mode").values  # a state's cable mode by its wire value
# What an estimate that says nothing of the payload tells the simulator: not seen, lost
_ESTIMATE_DEFAULTS = {"payload_visible": False, "payload_lost": True, "payload_supported": False}


class Command:
    """Body rates (rad/s, body frame) and collective thrust (N) for the simulator's rate loop."""

    def __init__(self, w_B_radps, thrust_N, status="success", solve_time_ms=0.0, cost=0.0):
        self.w_B_radps = [float(v) for v in w_B_radps]
        self.thrust_N = float(thrust_N)
        self.status = status
        self.solve_time_ms = float(solve_time_ms)
        self.cost = float(cost)


class RotorCommand:
    """A rate-loop step's output, from a stack that owns the rate loop: rotor speed commands
    (4, rad/s, inside the motors' range), the collective thrust they make (N) and whether the
    allocation fell short of the command."""

    def __init__(self, w_cmd_radps, thrust_allocated_N, saturated=False):
        self.w_cmd_radps = [float(v) for v in w_cmd_radps]
        self.thrust_allocated_N = float(thrust_allocated_N)
        self.saturated = bool(saturated)


class Tick:
    """One tick's inputs, an attribute per field of the table's tick (messages.json). imu: (n, 7)
    array [t_s, gyro_B (3) rad/s, accel_B (3) m/s^2]; vio: (n, 11) array [t_s, p_WB_W (3) m,
    q_WB (w, x, y, z), v_WB_W (3) m/s] stamped with their capture time; detections: dicts
    (time_s, found, reason, p_CL_C, centre_px, radius_px); frames: dicts (capture_time_s,
    region, region_slot, whole_slot, image: the whole (h, w, 3) uint8 BGR frame, a view valid
    during the tick); allocation: (thrust_allocated_N, saturated) or None; truth: a state dict
    (only with the scenario's ground-truth switch) or None; reference: dict p_WL_W, v_WL_W,
    a_WL_W; need_estimate, gripper_active, no_reply: the tick's flags; control_due: whether a
    loop at the stack's declared control_rate_hz fires at this tick (False without one)."""


class TeamView:
    """What one vehicle of a team knows at a control step (a team_tick's view, the C++ TeamView;
    docs/cooperative.md): time_s (s), vehicle (its index in the team), then, as motion capture
    measured them (or the truth with the scenario's ground-truth switch), numpy arrays: its own
    p_WQ_W (m), v_WQ_W (m/s), q_WB (w, x, y, z) and w_B (rad/s, body frame: its rate gyro's
    sample), and the payload's p_WL_W, v_WL_W, q_WP (w, x, y, z) and w_P (rad/s, payload
    frame). Readings come as sent, unchecked: all_finite() says whether every number is finite
    (a controller that gets a non-finite one should level out, as the C++ controllers do)."""

    FIELDS = tuple(f.name for f in STRUCTS["team_view"].fields)  # the arrays, in wire order

    def __init__(self, time_s, vehicle, **fields):
        self.time_s = float(time_s)
        self.vehicle = int(vehicle)
        for name in self.FIELDS:
            setattr(self, name, np.array(fields[name], dtype=float))

    def all_finite(self):
        """Whether time_s and every number of the view is finite."""
        return math.isfinite(self.time_s) and all(
            bool(np.all(np.isfinite(getattr(self, name)))) for name in self.FIELDS)

    def __repr__(self):
        return "TeamView(time_s=%g, vehicle=%d, %s)" % (self.time_s, self.vehicle, ", ".join(
            "%s=%s" % (name, np.array2string(getattr(self, name), precision=4))
            for name in self.FIELDS))


class _Reader:
    # reads one binary message; every refusal names the message ("malformed tick message: ...")
    def __init__(self, data, what):
        self.data, self.pos, self.what = data, 0, what

    def fail(self, why):
        raise ProtocolError(_error("malformed", message=self.what, what=why))

    def take(self, fmt):
        size = struct.calcsize(fmt)
        if self.pos + size > len(self.data):
            self.fail(_error("ends_early", pos=self.pos, size=len(self.data), need=size))
        values = struct.unpack_from(fmt, self.data, self.pos)
        self.pos += size
        return values

    def u32(self):
        return self.take("<I")[0]

    def text(self, f, at):
        length = self.u32()
        if length > len(self.data) - self.pos:
            self.fail(_error("text_too_long", of=_of(at), label=f.label, value=length))
        raw = bytes(self.data[self.pos:self.pos + length])
        self.pos += length
        try:
            return raw.decode("utf-8")
        except UnicodeDecodeError as e:
            bad = e.start
        self.fail(_error("text_not_utf8", of=_of(at), label=f.label,
                         why="byte %d of it, 0x%02x" % (bad, raw[bad])))

    def count(self, f):
        n = self.u32()
        if n * max(f.type.min_bytes, 1) > len(self.data) - self.pos:
            self.fail(_error("list_too_long", label=f.label, value=n))
        return n


def _check_number(r, f, at, v):
    if ((f.finite and not math.isfinite(v)) or (f.min is not None and not v >= f.min)
            or (f.max is not None and not v <= f.max)):
        r.fail(_format(f.refused, label=f.label, value=_shown_value(v),
                       min="" if f.min is None else _shown_limit(f.min),
                       max="" if f.max is None else _shown_limit(f.max), **{"in": _in(at)}))


def _check_flags(r, f, at, flags):
    known = 0
    for b in f.bits:
        known |= b["value"]
    if flags & ~known:
        r.fail(_error("unknown_bits", label=f.label, value="0x%x" % flags, choices=", ".join(
            "%d %s" % (b["value"], b.get("label", b["name"])) for b in f.bits), **{"in": _in(at)}))
    for b in f.bits:
        if "requires" in b and flags & b["value"]:
            required = next(o["value"] for o in f.bits if o["name"] == b["requires"])
            if not flags & required:
                r.fail(_format(b["refused"], label=f.label, value="0x%x" % flags,
                               **{"in": _in(at)}))


def _all_finite(value):
    # every number of a decoded value (a dict of numbers, arrays, texts, lists and dicts)
    if isinstance(value, dict):
        return all(_all_finite(v) for v in value.values())
    if isinstance(value, (list, tuple)):
        return all(_all_finite(v) for v in value)
    if isinstance(value, np.ndarray):
        return bool(np.all(np.isfinite(value)))
    if isinstance(value, float):
        return math.isfinite(value)
    return True


def _check_struct(r, f, value):
    # a struct-typed field's own checks: every number finite, a unit quaternion
    if f.finite and not _all_finite(value):
        r.fail(f.refused)
    uq = f.unit_quaternion
    if uq:
        q = value[uq["field"]]
        norm = math.sqrt(float(np.dot(q, q)))
        if not uq["min_norm"] <= norm <= uq["max_norm"]:
            r.fail(_format(uq["refused"], value=_shown_value(norm),
                           min=_shown_limit(uq["min_norm"]), max=_shown_limit(uq["max_norm"])))
        if abs(norm - 1.0) > uq["renormalise_beyond"]:
            value[uq["field"]] = q / norm


def _decode_struct(r, s, at):
    out, flags = {}, 0
    for f in s.fields:
        if f.gate and not flags & f.gate:
            out[f.name] = None
            continue
        kind = f.kind
        if kind == "flags":
            flags = r.u32()
            _check_flags(r, f, at, flags)
            for b in f.bits:
                out[b["name"]] = bool(flags & b["value"])
        elif kind in ("f64", "u32", "i32"):
            v = r.take(f.fmt)
            if f.checked:
                for x in v:
                    _check_number(r, f, at, x)
            out[f.name] = v[0] if f.count == 1 else np.array(v) if kind == "f64" else v
        elif kind == "bool":
            v = r.u32()
            if v > 1:
                r.fail(_error("bool", label=f.label, value=v, **{"in": _in(at)}))
            out[f.name] = v == 1
        elif kind == "enum":
            v = r.u32()
            if v >= len(f.values):
                choices = ", ".join("%d %s" % item for item in enumerate(f.values[:-1]))
                choices += " or %d %s" % (len(f.values) - 1, f.values[-1])
                r.fail(_error("enum", label=f.label, value=v, choices=choices, **{"in": _in(at)}))
            out[f.name] = f.values[v]
        elif kind == "text":
            out[f.name] = r.text(f, at)
        elif f.list:
            n = r.count(f)
            if f.type.rows:
                out[f.name] = np.array(r.take("<%dd" % (n * f.type.width))).reshape(n, f.type.width)
            else:
                out[f.name] = [_decode_struct(r, f.type, "%s %d" % (f.item, i)) for i in range(n)]
        else:
            v = _decode_struct(r, f.type, f.name)
            _check_struct(r, f, v)
            out[f.name] = v
    return out


def decode(layout, data, what=None):
    """Decodes a binary message body of the table's `layout` ("tick", "tick_reply") into a dict
    keyed by the table's field and bit names: numbers as floats and ints, vectors of f64 as
    numpy arrays, of i32 as tuples, enums by name, texts as str, an absent gated field as None,
    a list of rows (f64 structs) as an (n, width) array, other lists as lists of dicts. A value
    outside its declaration is a ProtocolError naming the message (`what`, default the
    layout) and the field."""
    r = _Reader(data, what or layout)
    out = _decode_struct(r, STRUCTS[layout], "")
    if r.pos != len(data):
        r.fail(_error("trailing", value=len(data) - r.pos))
    return out


def _encode_struct(parts, s, value):
    flags = 0
    for f in s.fields:
        if f.kind == "flags":
            flags = 0
            for b in f.bits:
                gated = s.gates.get(b["value"])
                on = (value.get(gated) is not None if gated else
                      value.get(b["name"], b.get("default", False)))
                flags |= b["value"] if on else 0
            parts.append(struct.pack("<I", flags))
            continue
        if f.gate and not flags & f.gate:
            continue
        v = value.get(f.name)
        if v is None:
            v = f.default
        kind = f.kind
        if kind in ("f64", "u32", "i32"):
            v = [v] if f.count == 1 else list(v)
            if len(v) != f.count:
                raise ValueError("%s has %d numbers, expected %d" % (f.name, len(v), f.count))
            parts.append(struct.pack(f.fmt, *(float(x) if kind == "f64" else int(x) for x in v)))
        elif kind == "bool":
            parts.append(struct.pack("<I", 1 if v else 0))
        elif kind == "enum":
            if v not in f.values:
                raise ValueError("%s %r, expected one of %s" % (f.label, v, ", ".join(f.values)))
            parts.append(struct.pack("<I", f.values.index(v)))
        elif kind == "text":
            data = v.encode("utf-8")
            parts.append(struct.pack("<I", len(data)) + data)
        elif f.list:
            items = [] if v is None else list(v)
            parts.append(struct.pack("<I", len(items)))
            for item in items:
                if isinstance(item, dict):
                    _encode_struct(parts, f.type, item)
                else:  # a row of a rows struct's numbers
                    parts.append(struct.pack("<%dd" % f.type.width, *(float(x) for x in item)))
        else:
            _encode_struct(parts, f.type, v or {})


def encode(layout, value):
    """Encodes a dict keyed as decode() returns them into a binary message body of `layout`: a
    missing field takes its declared default (zeros, an identity quaternion, an enum's first
    value); a flag bit that gates a field is set when that field is not None. Values are not
    checked here: the receiver checks them."""
    parts = []
    _encode_struct(parts, STRUCTS[layout], value)
    return b"".join(parts)


def decode_tick(data, what="tick"):
    """Decodes a tick (or finish: what="finish") message body into a Tick (frames without
    images); ProtocolError naming the message on a malformed one or an unknown flag or mode."""
    t = Tick()
    t.__dict__.update(decode(_LAYOUTS["tick"], data, what))
    if t.allocation is not None:
        t.allocation = (t.allocation["thrust_allocated_N"], t.saturated)
    for f in t.frames:
        f["image"] = None
    return t


def decode_rate_tick(data):
    """Decodes a rate_tick message body into a dict keyed by the table's names: time_s,
    command {w_B_radps, thrust_N} (what the rate loop tracks) and w_B_radps (the rate gyro's
    sample for PX4's loop, the estimated body rate for the own loop)."""
    return decode(_LAYOUTS["rate_tick"], data, "rate_tick")


def encode_rate_reply(rotors):
    """Encodes a rate_reply from a RotorCommand."""
    return encode(_LAYOUTS["rate_reply"], {"w_cmd_radps": rotors.w_cmd_radps,
                                            "thrust_allocated_N": rotors.thrust_allocated_N,
                                            "saturated": rotors.saturated})


def decode_team_tick(data):
    """Decodes a team_tick message body into (time_s, views): the views of the stack's vehicles
    that have one, in the message's order, each a TeamView; ProtocolError naming the message on
    a malformed one."""
    tick = decode(_LAYOUTS["team_tick"], data, "team_tick")
    return tick["time_s"], [TeamView(tick["time_s"], v["vehicle"], **v["view"])
                            for v in tick["views"]]


def encode_team_tick_reply(replies):
    """Encodes a team_tick_reply from (vehicle, Command, cable_taut) triples, one per view of the
    team_tick in its order: each Command's body rate, thrust, status, solve time and cost."""
    return encode(_LAYOUTS["team_tick_reply"], {"replies": [
        {"vehicle": vehicle, "cable_taut": bool(cable_taut),
         "output": {"command": {"w_B_radps": command.w_B_radps, "thrust_N": command.thrust_N},
                    "status": command.status, "solve_time_ms": command.solve_time_ms,
                    "cost": command.cost}}
        for vehicle, command, cable_taut in replies]})


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


def _check_json_keys(keys, value, where):
    if not isinstance(value, dict):
        raise ProtocolError("%s is %r, expected a JSON object" % (where, value))
    declared = {k["name"]: k for k in keys}
    for key, v in value.items():
        if key not in declared:
            raise ProtocolError("%s's key '%s' is not declared in the message table "
                                "(messages.json)" % (where, key))
        kind = declared[key]["type"]
        if not isinstance(v, _JSON_TYPES[kind]) or (isinstance(v, bool) and kind != "bool"):
            raise ProtocolError("%s's %s is %r, expected %s %s"
                                % (where, key, v, "an" if kind == "integer" else "a", kind))
        if "keys" in declared[key]:
            _check_json_keys(declared[key]["keys"], v, "%s's %s" % (where, key))
    for k in keys:
        if k.get("required") and k["name"] not in value:
            raise ProtocolError("%s has no %s" % (where, k["name"]))


def check_json(message, value):
    """Checks a JSON message (hello, hello_ack, finish_reply) against its keys in the message
    table: ProtocolError naming an undeclared key, a missing required one or a value of another
    JSON type (a nested object's keys likewise). The client checks what it sends."""
    _check_json_keys(JSON_KEYS[message], value, message)


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
        camera_keys = next(k["keys"] for k in JSON_KEYS["hello"] if k["name"] == "camera")
        _field(camera, "ring", where, (str,))
        for key in (k["name"] for k in camera_keys if k["type"] == "integer"):
            if _field(camera, key, where, (int,)) < 0:
                raise ProtocolError("%s: '%s' is %d, expected 0 or more"
                                    % (where, key, camera[key]))
        if camera["slot_bytes"] < 3 * camera["width_px"] * camera["height_px"]:
            raise ProtocolError("%s: 'slot_bytes' %d, expected at least 3 x width x height = %d"
                                % (where, camera["slot_bytes"],
                                   3 * camera["width_px"] * camera["height_px"]))
    return hello


def decode_team_hello(body):
    """The team_hello message's JSON object as a dict, checked against its keys in the message
    table, its vehicles distinct ascending indices into team.vehicles; ProtocolError naming the
    team_hello and what was wrong (for bad UTF-8 or JSON, the line and column). A hello of
    another protocol version is returned unchecked: the caller refuses it by its version."""
    where = "team_hello message"
    text = _decode_utf8(body, where, error=ProtocolError)
    hello = _require_object(_parse_json(text, where, error=ProtocolError), text, where, 1,
                            "the team's parameters", error=ProtocolError)
    if _field(hello, "protocol_version", where, (int,)) != PROTOCOL_VERSION:
        return hello
    check_json("team_hello", hello)
    team = hello["team"]["vehicles"]
    vehicles = hello["vehicles"]
    if (not vehicles or not all(isinstance(v, int) and not isinstance(v, bool)
                                and 0 <= v < len(team) for v in vehicles)
            or vehicles != sorted(set(vehicles))):
        raise ProtocolError("%s: 'vehicles' is %r, expected ascending vehicle indices in [0, %d)"
                            % (where, vehicles, len(team)))
    for i in vehicles:
        if not isinstance(team[i], dict) or not all(
                k in team[i] for k in ("params", "cable_length_m", "p_PA_P_m")):
            raise ProtocolError("%s: team.vehicles[%d] is not an object of params, "
                                "cable_length_m and p_PA_P_m" % (where, i))
    return hello


def encode_reply(command, estimate, rejected=0, resets=0, frames_detected=0, camera_roi=(0, 0, 0, 0)):
    """Encodes a tick reply: a Command or None, a state dict or None (what it leaves out takes
    the table's defaults, the payload's flags an estimate's: not visible, lost), health counters
    and the region of interest (x, y, width, height pixels) the camera should read out next
    besides the whole frame (zero size: none)."""
    if command is not None:
        command = {"command": {"w_B_radps": command.w_B_radps, "thrust_N": command.thrust_N},
                   "status": command.status, "solve_time_ms": command.solve_time_ms,
                   "cost": command.cost}
    if estimate is not None:
        estimate = dict(_ESTIMATE_DEFAULTS, **{k: v for k, v in estimate.items() if v is not None})
    return encode(_LAYOUTS["tick_reply"], {
        "command": command, "estimate": estimate, "rejected_updates": rejected, "resets": resets,
        "frames_detected": frames_detected, "camera_roi": camera_roi})


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

    def hello(self, name, control_rate_hz, batched_ticks=False, owns_rate_loop=False,
              uses_pixels=True):
        """Receives the hello (a dict), maps the frame ring, answers with the ack (declaring
        batched_ticks and owns_rate_loop when asked: docs/protocol.md, Batched ticks, rate_tick
        and rate_reply). uses_pixels=False declares that the stack reads no rendered frame: the
        ring is not mapped, and the simulator sends no frame and renders none."""
        kind, body = self.receive()
        if kind != HELLO:
            raise ProtocolError("expected a hello, got a %s message" % MESSAGE_TYPES[kind])
        hello = decode_hello(body)
        if hello["protocol_version"] != PROTOCOL_VERSION:
            self.send(ERROR, ("this client speaks protocol version %d" % PROTOCOL_VERSION).encode())
            raise ProtocolError("the simulator speaks protocol version %d" % hello["protocol_version"])
        camera = hello.get("camera")
        if camera and uses_pixels:
            name_ = camera["ring"]
            fd = os.open("/dev/shm/" + name_.lstrip("/"), os.O_RDONLY)
            try:
                self.ring = mmap.mmap(fd, camera["slot_bytes"] * camera["slots"], prot=mmap.PROT_READ)
            finally:
                os.close(fd)
            self.camera = camera
        ack = {"protocol_version": PROTOCOL_VERSION, "name": name,
               "control_rate_hz": control_rate_hz}
        if batched_ticks:
            ack["batched_ticks"] = True
        if owns_rate_loop:
            ack["owns_rate_loop"] = True
        if not uses_pixels:
            ack["uses_pixels"] = False
        check_json("hello_ack", ack)
        self.send(HELLO_ACK, json.dumps(ack).encode())
        return hello

    def team_hello(self):
        """Receives the team_hello (a dict, decode_team_hello's). ProtocolError for another
        message (a single vehicle's hello: this stack flies a team), another protocol version,
        or vehicles other than the one HPA_VEHICLE names when it is set (a stack started per
        vehicle flies its own)."""
        kind, body = self.receive()
        if kind != TEAM_HELLO:
            raise ProtocolError("expected a team_hello, got a %s message" % MESSAGE_TYPES[kind])
        hello = decode_team_hello(body)
        if hello["protocol_version"] != PROTOCOL_VERSION:
            raise ProtocolError("the simulator speaks protocol version %d, this client %d"
                                % (hello["protocol_version"], PROTOCOL_VERSION))
        own = os.environ.get("HPA_VEHICLE", "")
        if own and hello["vehicles"] != [int(own) if own.isdigit() else own]:
            raise ProtocolError("started with HPA_VEHICLE=%s, but the team_hello asks for "
                                "vehicles %s" % (own, hello["vehicles"]))
        return hello

    def team_hello_ack(self, hello, name, control_rate_hz, controller=None):
        """Answers the team_hello with the ack: this stack's name (metrics.json's flight_stack),
        the controller it flies (metrics.json's controller; absent: the name), its control rate
        (Hz) and exactly the hello's vehicles."""
        ack = {"protocol_version": PROTOCOL_VERSION, "name": name,
               "control_rate_hz": float(control_rate_hz), "vehicles": hello["vehicles"]}
        if controller is not None:
            ack["controller"] = controller
        check_json("team_hello_ack", ack)
        self.send(TEAM_HELLO_ACK, json.dumps(ack).encode())

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


class _ControlClock:
    """The ticks a loop at rate_hz fires on a tick_hz clock from tick 0: the k-th at tick
    round(k tick_hz / rate_hz), half away from zero (the simulator's LockstepClock)."""

    def __init__(self, tick_hz, rate_hz):
        self.tick_hz, self.rate_hz = float(tick_hz), float(rate_hz)
        self.tick, self.k = 0, 0

    def fires(self):
        """Whether the loop fires at the current tick; moves on to the next tick."""
        at = math.floor(self.k * self.tick_hz / self.rate_hz + 0.5)
        due = at == self.tick
        if due:
            self.k += 1
        self.tick += 1
        return due


def run(controller_class, name=None, control_rate_hz=0.0, batched_ticks=False,
        owns_rate_loop=False, uses_pixels=True):
    """Serves one run: builds controller_class(hello) and calls its step(tick) every tick.
    step returns a Command (a new command), or None (the rate loop keeps the last one); the
    controller may set `estimate` (a state dict) for the simulator's log and rate loop, else the
    latest VIO pose and IMU rate are sent (before the first VIO sample, the hello's initial
    state). With a control_rate_hz, tick.control_due says when a loop at that rate fires;
    batched_ticks=True promises that step commands exactly then (a ProtocolError otherwise),
    and the simulator answers with fewer round trips (docs/protocol.md, Batched ticks).
    owns_rate_loop=True declares that the stack runs the vehicle's rate loop: the simulator runs
    none and at each of the loop's steps (the hello's rate_loop) calls the controller's
    rate_loop(rate_tick), a dict as decode_rate_tick gives it, which returns a RotorCommand.
    uses_pixels=False declares that the controller reads no rendered frame (tick.frames stays
    empty): on the rendered camera the simulator then renders and sends none, so the run is as
    fast as on the analytic one, and its metrics say the camera was not flown."""
    if batched_ticks and not control_rate_hz > 0:
        raise ValueError("batched_ticks needs the control_rate_hz its commands follow")
    client = FlightStackClient()
    try:
        hello = client.hello(name or controller_class.__name__, control_rate_hz, batched_ticks,
                             owns_rate_loop, uses_pixels)
        tick_hz = hello.get("config", {}).get("tick_hz", 1000.0)
        clock = _ControlClock(tick_hz, control_rate_hz) if control_rate_hz > 0 else None
        controller = controller_class(hello)
        last_vio, last_gyro = None, np.zeros(3)
        # before the first VIO sample, the state the run starts from (the simulator refuses a
        # reply without the estimate a tick asks for)
        start = hello.get("config", {}).get("initial_state") or {}
        start = dict(start, q_WB=start.get("q_WB_wxyz", [1.0, 0.0, 0.0, 0.0]))
        while True:
            kind, body = client.receive()
            if kind == RATE_TICK and owns_rate_loop:
                client.send(RATE_REPLY, encode_rate_reply(controller.rate_loop(
                    decode_rate_tick(body))))
                continue
            if kind not in (TICK, FINISH):
                raise ProtocolError("expected a tick or finish, got a %s message"
                                    % MESSAGE_TYPES[kind])
            tick = decode_tick(body, MESSAGE_TYPES[kind])
            if kind == FINISH:
                reply = {"estimator": "", "estimator_health": [], "frames_detected": 0}
                check_json("finish_reply", reply)
                client.send(FINISH_REPLY, json.dumps(reply).encode())
                return 0
            client.attach_frames(tick)
            if len(tick.vio):
                last_vio = tick.vio[-1]
            if len(tick.imu):
                last_gyro = tick.imu[-1, 1:4]
            tick.control_due = clock.fires() if clock is not None else False
            command = controller.step(tick)
            if batched_ticks and (command is not None) != tick.control_due:
                raise ProtocolError("step returned %s at t = %g s, a tick its declared control "
                                    "rate (%g Hz) %s" % (
                                        "a command" if command is not None else "no command",
                                        tick.time_s, control_rate_hz,
                                        "skips" if command is not None else "commands at"))
            if tick.no_reply:
                continue  # the simulator reads no reply to this tick
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
        return _report_failure(client, e)


def _report_failure(client, e):
    # sends the exception's last frames as the error message (the run's run_error), prints the
    # whole traceback to stderr; the stack's exit status 1
    try:
        client.send(ERROR, describe_exception(e).encode("utf-8", "replace"))
    except OSError:
        pass
    print("flight stack: %s: %s" % (type(e).__name__, e), file=sys.stderr)
    traceback.print_exc(file=sys.stderr)
    return 1


def run_team(controller_class, control_rate_hz, name=None, controller=None):
    """Serves a team's stack (docs/protocol.md, Teams): receives the team_hello, builds
    controller_class(hello, vehicle) for each vehicle it lists (one with --team-stack
    per_vehicle, every vehicle with --team-stack one: the same class serves both), answers with
    the team_hello_ack (name, default the class's name; controller, default the name;
    control_rate_hz, the team's control loop in (0, 1000] Hz; the hello's vehicles), then at each
    team_tick calls step(view) of each vehicle that has a view, a TeamView, and replies in the
    tick's order. step returns that vehicle's Command (body rate, thrust, status, cost); the
    reply's solve time is step's wall time (as hpa-flight times each update) and its cable_taut
    the controller's `cable_taut` attribute after step (True when it has none). The finish is
    answered with an empty finish_reply; a controller that raises (or returns something other
    than a Command) ends the run as in run(): its last stack frames go to the simulator as the
    run's error, the whole traceback to stderr, exit status 1. Returns the exit status."""
    if (not isinstance(control_rate_hz, (int, float)) or isinstance(control_rate_hz, bool)
            or not 0.0 < control_rate_hz <= MAX_TEAM_CONTROL_RATE_HZ):
        raise ValueError("control_rate_hz %r, expected a rate in (0, %g] Hz"
                         % (control_rate_hz, MAX_TEAM_CONTROL_RATE_HZ))
    name = name or controller_class.__name__
    client = FlightStackClient()
    try:
        hello = client.team_hello()
        # built before the ack, so a controller that cannot fly the team fails the hello
        controllers = {i: controller_class(hello, i) for i in hello["vehicles"]}
        client.team_hello_ack(hello, name, control_rate_hz,
                              name if controller is None else controller)
        while True:
            kind, body = client.receive()
            if kind == FINISH:
                client.send(FINISH_REPLY, b"{}")
                return 0
            if kind != TEAM_TICK:
                raise ProtocolError("expected a team_tick or finish, got a %s message"
                                    % MESSAGE_TYPES[kind])
            time_s, views = decode_team_tick(body)
            replies = []
            for view in views:
                vehicle = controllers.get(view.vehicle)
                if vehicle is None:
                    raise ProtocolError("a team_tick at t = %g s carries a view of vehicle %d, "
                                        "which this stack does not fly (it flies %s)"
                                        % (time_s, view.vehicle, hello["vehicles"]))
                start = time.perf_counter()
                command = vehicle.step(view)
                solve_time_ms = (time.perf_counter() - start) * 1e3
                if not isinstance(command, Command):
                    raise TypeError("%s.step returned %r for vehicle %d at t = %g s, expected a "
                                    "Command" % (type(vehicle).__name__, command, view.vehicle,
                                                 time_s))
                command = Command(command.w_B_radps, command.thrust_N, command.status,
                                  solve_time_ms, command.cost)
                replies.append((view.vehicle, command, getattr(vehicle, "cable_taut", True)))
            client.send(TEAM_TICK_REPLY, encode_team_tick_reply(replies))
    except EOFError:
        return 0
    except Exception as e:  # tell the simulator why and where (its run error), then fail
        return _report_failure(client, e)
