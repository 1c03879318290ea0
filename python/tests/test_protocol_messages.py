"""Every message type of the lockstep protocol through the Python client: the binary messages
round-trip with every field of the message table (hpa_sim/messages.json) set to a value other
than its default; the golden encodings the C++ encoder wrote (flight/tests/protocol_golden.json,
checked byte for byte by flight_test's ProtocolMessagesTest) decode to their values and those
values encode to the same bytes; the JSON messages and the error message cross a session with a
simulator played here.

`python3 python/tests/test_protocol_messages.py --update` rewrites the golden file's values from
its hex (after a new field: see flight/tests/protocol_messages_test.cc)."""

import json
import math
import os
import sys
import unittest

import numpy as np

from hpa_sim import lockstep

import fake_simulator

GOLDEN = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "flight", "tests",
                      "protocol_golden.json")
LAYOUTS = {t["name"]: t["layout"] for t in lockstep.TABLE["message_types"] if "layout" in t}


def plain(value):
    """A decoded value as JSON holds it: arrays and tuples as lists."""
    if isinstance(value, dict):
        return {k: plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [plain(v) for v in value]
    if isinstance(value, np.floating):
        return float(value)
    if isinstance(value, np.integer):
        return int(value)
    return value


def load_golden():
    with open(GOLDEN, encoding="utf-8") as f:
        return json.load(f)


def sample(struct, k=0):
    """A value of `struct` with every field and bit away from its declared default, the k-th
    sample of it (numbers differ between samples and fields)."""
    out = {}
    for i, f in enumerate(struct.fields):
        x = 0.5 + 0.25 * i + 10.0 * k  # exact in binary, differs per field and sample
        if f.kind == "flags":
            for b in f.bits:
                out[b["name"]] = not b.get("default", False)
        elif f.kind == "f64":
            v = [x + j / 8.0 for j in range(f.count)]
            out[f.name] = v[0] if f.count == 1 else v
        elif f.kind in ("u32", "i32"):
            top = int(f.max) if f.max is not None else 1000
            v = [min(7 + i + j + k, top) for j in range(f.count)]
            out[f.name] = v[0] if f.count == 1 else v
        elif f.kind == "bool":
            out[f.name] = not f.default
        elif f.kind == "enum":
            out[f.name] = [v for v in f.values if v != f.default][-1]
        elif f.kind == "text":
            out[f.name] = "sample %d \u00e9" % i
        elif f.list:
            items = [sample(f.type, k + j + 1) for j in range(2)]
            if f.type.rows:  # decoded as an (n, width) array, columns in the table's order
                items = [[x for g in f.type.fields for x in
                          (item[g.name] if g.count > 1 else [item[g.name]])] for item in items]
            out[f.name] = items
        else:
            out[f.name] = sample(f.type, k + 1)
            if f.unit_quaternion:  # a quaternion the field's check accepts, not the identity
                out[f.name][f.unit_quaternion["field"]] = [0.5, -0.5, 0.5, 0.5]
    return out


def differs_from_defaults(test, struct, value, where):
    """Fails `test` for each field of `struct` that `value` leaves at its default (a list: in
    every item; a gated field: absent)."""
    for f in struct.fields:
        name = "%s.%s" % (where, f.name)
        if f.kind == "flags":
            for b in f.bits:
                if b["value"] not in struct.gates:
                    test.assertNotEqual(value[b["name"]], b.get("default", False), name)
            continue
        v = value[f.name]
        test.assertIsNotNone(v, name + " is absent")
        if f.list:
            test.assertGreater(len(v), 0, name + " is empty")
            if f.type.rows:
                column = 0
                for g in f.type.fields:
                    cells = [row[column:column + g.count] for row in v]
                    default = g.default if g.count > 1 else [g.default]
                    test.assertTrue(any(c != default for c in cells), "%s.%s" % (name, g.name))
                    column += g.count
            else:
                for g in f.type.fields:
                    if g.kind == "flags":
                        continue
                    test.assertTrue(any(item[g.name] != g.default for item in v),
                                    "%s.%s" % (name, g.name))
        elif f.kind == "struct":
            differs_from_defaults(test, f.type, v, name)
        else:
            default = f.default
            test.assertNotEqual(plain(v), plain(default), name)


class RoundTripTest(unittest.TestCase):
    def test_every_binary_message_round_trips_with_every_field_set(self):
        for message, layout in sorted(LAYOUTS.items()):
            with self.subTest(message=message):
                value = sample(lockstep.STRUCTS[layout])
                differs_from_defaults(self, lockstep.STRUCTS[layout], value, message)
                data = lockstep.encode(layout, value)
                back = plain(lockstep.decode(layout, data, message))
                self.assertEqual(back, plain(value))
                self.assertEqual(lockstep.encode(layout, back), data)

    def test_tick_object_carries_every_field(self):
        tick = lockstep.decode_tick(lockstep.encode("tick", sample(lockstep.STRUCTS["tick"])))
        for f in lockstep.STRUCTS["tick"].fields:
            if f.kind != "flags":
                self.assertTrue(hasattr(tick, f.name), f.name)
        self.assertEqual(len(tick.allocation), 2)  # (thrust_allocated_N, saturated)
        self.assertEqual(tick.imu.shape, (2, 7))
        self.assertEqual(tick.vio.shape, (2, 11))
        self.assertIsNone(tick.frames[0]["image"])

    def test_a_session_carries_every_message_type(self):
        """hello, hello_ack, tick, tick_reply, rate_tick, rate_reply, finish, finish_reply and,
        from a stack that raises, error, through the client's own socket code."""
        hello = json.dumps({"protocol_version": lockstep.PROTOCOL_VERSION, "scenario": "s",
                            "seed": 3, "config": {}}).encode()
        # without frames: this hello has no camera ring to map them from; the truth (the
        # estimate the stack sends) with a unit quaternion
        value = dict(sample(lockstep.STRUCTS["tick"]), frames=[])
        value["truth"]["q_WB"] = [0.5, -0.5, 0.5, 0.5]
        value["no_reply"] = False  # a tick this simulator reads the reply of
        tick = lockstep.encode("tick", value)

        class Stack:
            def __init__(self, hello):
                self.estimate = None

            def step(self, tick):
                return lockstep.Command([0.25, -0.5, 0.125], 7.5, "max_iterations", 1.5, 2.0)

        code, replies = fake_simulator.serve(Stack, hello, [(lockstep.TICK, tick),
                                                            (lockstep.FINISH, tick)])
        self.assertEqual(code, 0)
        self.assertEqual([k for k, _ in replies],
                         [lockstep.HELLO_ACK, lockstep.TICK_REPLY, lockstep.FINISH_REPLY])
        ack = json.loads(replies[0][1])
        self.assertEqual((ack["protocol_version"], ack["name"]),
                         (lockstep.PROTOCOL_VERSION, "test"))
        reply = lockstep.decode("tick_reply", replies[1][1])
        self.assertEqual(reply["command"]["status"], "max_iterations")
        self.assertEqual(list(reply["command"]["command"]["w_B_radps"]), [0.25, -0.5, 0.125])
        # the tick's truth is the estimate a stack without its own sends
        self.assertEqual(plain(reply["estimate"]["p_WQ_W"]), value["truth"]["p_WQ_W"])
        finish = json.loads(replies[2][1])
        self.assertEqual(sorted(finish), ["estimator", "estimator_health", "frames_detected"])

        # a stack that owns the rate loop: the rate_tick reaches its rate_loop, the ack says so
        rate_value = sample(lockstep.STRUCTS["rate_tick"])
        class OwnsRateLoop(Stack):
            def rate_loop(self, rate_tick):
                if plain(rate_tick) != plain(rate_value):  # the rate_tick as it was sent
                    raise ValueError("rate_tick decoded as %r" % rate_tick)
                return lockstep.RotorCommand([1000.5, 1100.25, 950.125, 1830.0], 6.5, True)

        code, replies = fake_simulator.serve(
            OwnsRateLoop, hello, [(lockstep.TICK, tick),
                                  (lockstep.RATE_TICK, lockstep.encode("rate_tick", rate_value)),
                                  (lockstep.FINISH, tick)], owns_rate_loop=True)
        self.assertEqual(code, 0)
        self.assertEqual([k for k, _ in replies], [lockstep.HELLO_ACK, lockstep.TICK_REPLY,
                                                   lockstep.RATE_REPLY, lockstep.FINISH_REPLY])
        self.assertTrue(json.loads(replies[0][1])["owns_rate_loop"])
        rotors = plain(lockstep.decode("rate_reply", replies[2][1]))
        self.assertEqual(rotors, {"w_cmd_radps": [1000.5, 1100.25, 950.125, 1830.0],
                                  "thrust_allocated_N": 6.5, "saturated": True})

        class Raises(Stack):
            def step(self, tick):
                raise ValueError("boom")

        code, replies = fake_simulator.serve(Raises, hello, [(lockstep.TICK, tick)])
        self.assertEqual(code, 1)
        self.assertEqual(replies[-1][0], lockstep.ERROR)
        self.assertIn("ValueError: boom", replies[-1][1].decode("utf-8"))


class JsonMessagesTest(unittest.TestCase):
    """The JSON messages' keys, declared in the table, checked as the C++ side checks them."""

    def test_what_the_client_sends_is_checked_against_the_tables_keys(self):
        ack = {"protocol_version": lockstep.PROTOCOL_VERSION, "name": "s", "control_rate_hz": 100,
               "batched_ticks": True}
        lockstep.check_json("hello_ack", ack)
        with self.assertRaisesRegex(lockstep.ProtocolError, "key 'rate_hz' is not declared"):
            lockstep.check_json("hello_ack", dict(ack, rate_hz=1))
        with self.assertRaisesRegex(lockstep.ProtocolError, "batched_ticks is 1, expected a bool"):
            lockstep.check_json("hello_ack", dict(ack, batched_ticks=1))
        with self.assertRaisesRegex(lockstep.ProtocolError, "hello_ack has no protocol_version"):
            lockstep.check_json("hello_ack", {"name": "s"})
        camera = {"ring": "/r", "slots": 6, "width_px": 4, "height_px": 2}
        hello = {"protocol_version": 1, "scenario": "s", "seed": 1, "rates": [], "config": {},
                 "camera": camera}
        with self.assertRaisesRegex(lockstep.ProtocolError, "hello's camera has no slot_bytes"):
            lockstep.check_json("hello", hello)
        lockstep.check_json("finish_reply", {"estimator": "", "estimator_health": [],
                                             "frames_detected": 0})


@unittest.skipUnless(os.path.exists(GOLDEN), "no golden file (not a source tree)")
class GoldenTest(unittest.TestCase):
    """The C++ encoder's bytes, read and written by the Python client."""

    def test_golden_bytes_decode_to_their_values_and_back(self):
        golden = load_golden()
        self.assertEqual({e["message"] for e in golden["messages"]}, set(LAYOUTS))
        for entry in golden["messages"]:
            with self.subTest(name=entry["name"]):
                layout = LAYOUTS[entry["message"]]
                data = bytes.fromhex(entry["hex"])
                decoded = lockstep.decode(layout, data, entry["message"])
                self.assertEqual(plain(decoded), entry["value"])
                self.assertEqual(lockstep.encode(layout, entry["value"]), data)
                self.assertEqual(lockstep.encode(layout, decoded), data)

    def test_the_full_samples_set_every_field(self):
        golden = {e["name"]: e for e in load_golden()["messages"]}
        for name in ("tick", "tick_reply"):
            differs_from_defaults(self, lockstep.STRUCTS[LAYOUTS[name]], golden[name]["value"],
                                  name)

    def test_golden_negative_zeros_keep_their_sign(self):
        tick = {e["name"]: e for e in load_golden()["messages"]}["tick"]["value"]
        self.assertEqual(math.copysign(1.0, tick["reference"]["a_WL_W"][0]), -1.0)


def update():
    """Rewrites the golden file's values from its hex."""
    golden = load_golden()
    for entry in golden["messages"]:
        data = bytes.fromhex(entry["hex"])
        entry["value"] = plain(lockstep.decode(LAYOUTS[entry["message"]], data, entry["message"]))
    with open(GOLDEN + ".tmp", "w", encoding="utf-8") as f:
        json.dump(golden, f, indent=2, ensure_ascii=False)
        f.write("\n")
    os.replace(GOLDEN + ".tmp", GOLDEN)
    print("rewrote " + GOLDEN)


if __name__ == "__main__":
    if "--update" in sys.argv:
        update()
    else:
        unittest.main()
