"""hpa_sim on hostile inputs: every file the loaders refuse is an InputError naming the file, the
line and (where it helps) the column; every message the lockstep client refuses is a
ProtocolError naming the message. Good inputs, written by hand in the formats docs/design.md
section 8 and docs/protocol.md describe, still load."""

import json
import os
import re
import socket
import struct
import tempfile
import unittest
import warnings

import numpy as np

from hpa_sim import InputError, ProtocolError, load_log, load_metrics, load_runs, lockstep

import fake_simulator

# log.csv's header as the simulator writes it (harness/runner/src/metrics.cc, WriteLogCsv)
_STATE = ["pL_x", "pL_y", "pL_z", "vL_x", "vL_y", "vL_z", "pQ_x", "pQ_y", "pQ_z", "vQ_x", "vQ_y",
          "vQ_z", "q_w", "q_x", "q_y", "q_z", "w_x", "w_y", "w_z", "mode"]
LOG_HEADER = (["time_s"] + ["true_" + n for n in _STATE] + ["est_" + n for n in _STATE] +
              ["ref_pL_x", "ref_pL_y", "ref_pL_z", "ref_pQ_x", "ref_pQ_y", "ref_pQ_z",
               "cmd_w_x", "cmd_w_y", "cmd_w_z", "cmd_thrust_N", "status", "solve_ms", "cost",
               "tension_N", "gripper", "est_rejected_updates", "est_resets", "mixer_saturated",
               "est_payload_lost", "est_payload_supported"])


def log_row(time_s, status="success"):
    """One log.csv row: a hover at 1.5 m with the payload hanging 0.5 m below, taut."""
    state = [0, 0, 1, 0, 0, 0, 0, 0, 1.5, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 1]
    cells = ([time_s] + state + state + [0, 0, 1, 0, 0, 1.5, 0.01, -0.02, 0, 8.05923, status,
                                         0.272427, 11.2024, 0.95, 0, 0, 0, 0, 0, 0])
    return ",".join(str(c) for c in cells)


GOOD_LOG = "\n".join([",".join(LOG_HEADER), log_row(0), log_row(0.007), log_row(0.013)]) + "\n"

GOOD_METRICS = {
    "scenario": "hover", "controller": "hpa_mpc", "camera": "analytic", "seed": 1,
    "sim_time_s": 12.0, "wall_time_s": 3.1, "crashed": False, "crash_time_s": None,
    "crash_reason": None, "run_error": None, "payload_rmse_m": [0.01, 0.01, 0.02],
    "slack_detection_latency_s": {"mean": None, "max": None, "missed": 0},
    "crash_note": "NaN and Infinity inside a string are text, not numbers",
    "expect": {"passed": True, "failed": []}}


def run_line(index, crashed=False):
    """One runs.jsonl record as hpa sweep writes it: one line, no spaces."""
    metrics = dict(GOOD_METRICS, seed=100 + index, crashed=crashed)
    return json.dumps({"sweep_id": "e0ec72ed5d2766e7", "sweep": "s.yaml", "base": "b.yaml",
                       "run": index, "draw": index, "seed": 100 + index,
                       "values": {"events.0.force.0": 0.1 + 0.1 * index},
                       "controller": "hpa_mpc", "status": "ok", "error": None,
                       "metrics": metrics}, separators=(",", ":"))


class HostileFileTest(unittest.TestCase):
    """Writes each hostile file into its own temporary folder."""

    def setUp(self):
        self._dir = tempfile.TemporaryDirectory()
        self.addCleanup(self._dir.cleanup)

    def write(self, name, data):
        path = os.path.join(self._dir.name, name)
        with open(path, "wb") as f:
            f.write(data.encode("utf-8") if isinstance(data, str) else data)
        return path

    def assertRefused(self, load, path, line=None, column=None, *fragments):
        """load(path) raises an InputError that starts with PATH: (no line given), PATH:LINE:
        with or without a column (no column given) or PATH:LINE:COLUMN:, and says each
        fragment."""
        with self.assertRaises(InputError) as caught:
            load(path)
        message = str(caught.exception)
        where = re.escape(path) + (":%d" % line if line else "") + (
            ":%d" % column if column else r"(:\d+)?" if line else "") + ": "
        self.assertRegex(message, "^" + where)
        for fragment in fragments:
            self.assertIn(fragment, message)
        return message


class MetricsTest(HostileFileTest):
    def test_good_metrics_load(self):
        path = self.write("metrics.json", json.dumps(GOOD_METRICS, indent=2) + "\n")
        self.assertEqual(load_metrics(path), GOOD_METRICS)

    def test_byte_order_mark_is_accepted(self):
        path = self.write("metrics.json", b"\xef\xbb\xbf" + json.dumps(GOOD_METRICS).encode())
        self.assertEqual(load_metrics(path), GOOD_METRICS)

    def test_missing_file_names_it(self):
        path = os.path.join(self._dir.name, "no_such_run", "metrics.json")
        self.assertRefused(load_metrics, path, None, None, "cannot read")

    def test_malformed_json_names_line_and_column(self):
        path = self.write("metrics.json", '{\n  "seed": 1,\n  "crashed": fals\n}\n')
        self.assertRefused(load_metrics, path, 3, 14, "not valid JSON")

    def test_invalid_utf8_names_line_and_column(self):
        path = self.write("metrics.json", b'{\n  "scenario": "h\xffover"\n}\n')
        self.assertRefused(load_metrics, path, 2, 17, "0xff", "UTF-8")

    def test_nan_is_refused(self):
        path = self.write("metrics.json", '{\n  "seed": 1,\n  "mode_accuracy": NaN\n}\n')
        self.assertRefused(load_metrics, path, 3, 20, "NaN", "finite")

    def test_infinity_is_refused(self):
        for token, column in (("Infinity", 20), ("-Infinity", 20), ("1e999", 20)):
            with self.subTest(token=token):
                path = self.write("metrics.json", '{\n  "seed": 1,\n  "wall_time_s": %s\n}' % token)
                self.assertRefused(load_metrics, path, 3, column - 2, token, "finite")

    def test_a_list_is_refused(self):
        path = self.write("metrics.json", "\n  [1, 2, 3]\n")
        self.assertRefused(load_metrics, path, 2, 3, "an array", "expected an object")

    def test_errors_are_value_errors(self):
        path = self.write("metrics.json", "[]")
        self.assertRaises(ValueError, load_metrics, path)


class LogTest(HostileFileTest):
    def test_good_log_loads(self):
        log = load_log(self.write("log.csv", GOOD_LOG))
        self.assertEqual(list(log), LOG_HEADER)
        np.testing.assert_array_equal(log["time_s"], [0, 0.007, 0.013])
        self.assertEqual(log["time_s"].dtype, np.float64)
        self.assertEqual(list(log["status"]), ["success"] * 3)
        self.assertEqual(log["cmd_thrust_N"][0], 8.05923)

    def test_byte_order_mark_is_accepted(self):
        log = load_log(self.write("log.csv", b"\xef\xbb\xbf" + GOOD_LOG.encode()))
        self.assertIn("time_s", log)
        self.assertEqual(list(log), LOG_HEADER)

    def test_crlf_line_ends_are_accepted(self):
        log = load_log(self.write("log.csv", GOOD_LOG.replace("\n", "\r\n")))
        self.assertEqual(len(log["time_s"]), 3)

    def test_missing_file_names_it(self):
        self.assertRefused(load_log, os.path.join(self._dir.name, "log.csv"), None, None,
                           "cannot read")

    def test_empty_file_is_refused(self):
        self.assertRefused(load_log, self.write("log.csv", ""), 1, None, "empty")

    def test_header_only_is_refused(self):
        path = self.write("log.csv", ",".join(LOG_HEADER) + "\n")
        self.assertRefused(load_log, path, 2, None, "no rows")

    def test_non_numeric_cell_names_line_and_column(self):
        rows = GOOD_LOG.splitlines()
        rows[2] = rows[2].replace("8.05923", "eight", 1)
        column = LOG_HEADER.index("cmd_thrust_N") + 1
        self.assertRefused(load_log, self.write("log.csv", "\n".join(rows) + "\n"), 3, column,
                           "cmd_thrust_N", "'eight'", "expected a finite number")

    def test_empty_cell_is_refused(self):
        rows = GOOD_LOG.splitlines()
        rows[1] = rows[1].replace(",0.272427,", ",,", 1)
        column = LOG_HEADER.index("solve_ms") + 1
        self.assertRefused(load_log, self.write("log.csv", "\n".join(rows) + "\n"), 2, column,
                           "solve_ms")

    def test_nan_cell_is_refused(self):
        for token in ("nan", "NaN", "inf", "-inf"):
            with self.subTest(token=token):
                rows = GOOD_LOG.splitlines()
                rows[3] = rows[3].replace("11.2024", token, 1)
                column = LOG_HEADER.index("cost") + 1
                self.assertRefused(load_log, self.write("log.csv", "\n".join(rows) + "\n"), 4,
                                   column, "'%s'" % token, "finite")

    def test_the_earliest_bad_line_is_named(self):
        rows = GOOD_LOG.splitlines()
        rows[3] = rows[3].replace("0.013", "x", 1)  # first column, later line
        rows[2] = rows[2].replace("11.2024", "y", 1)  # later column, earlier line
        self.assertRefused(load_log, self.write("log.csv", "\n".join(rows) + "\n"), 3,
                           LOG_HEADER.index("cost") + 1, "'y'")

    def test_duplicate_column_names_are_refused(self):
        header = LOG_HEADER[:]
        header[5] = "true_pL_x"
        text = "\n".join([",".join(header)] + GOOD_LOG.splitlines()[1:]) + "\n"
        self.assertRefused(load_log, self.write("log.csv", text), 1, 6, "'true_pL_x'",
                           "twice", "columns 2 and 6")

    def test_short_row_is_refused(self):
        rows = GOOD_LOG.splitlines()
        rows[3] = rows[3][:40]
        self.assertRefused(load_log, self.write("log.csv", "\n".join(rows)), 4, None,
                           "expected %d" % len(LOG_HEADER))

    def test_invalid_utf8_names_line(self):
        data = GOOD_LOG.encode().replace(b"success", b"succ\xe9ss", 1)
        self.assertRefused(load_log, self.write("log.csv", data), 2, None, "UTF-8")


class RunsTest(HostileFileTest):
    def test_good_runs_load(self):
        runs = load_runs(self.write("runs.jsonl", run_line(0) + "\n" + run_line(1) + "\n"))
        self.assertEqual([r["run"] for r in runs], [0, 1])
        self.assertEqual(runs[1]["metrics"]["seed"], 101)
        self.assertIsNone(runs[0]["metrics"]["crash_time_s"])

    def test_complete_last_line_without_newline_loads(self):
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # no warning: the line is whole
            runs = load_runs(self.write("runs.jsonl", run_line(0) + "\n" + run_line(1)))
        self.assertEqual(len(runs), 2)

    def test_empty_file_is_no_runs(self):
        self.assertEqual(load_runs(self.write("runs.jsonl", "")), [])

    def test_missing_file_names_it(self):
        self.assertRefused(load_runs, os.path.join(self._dir.name, "runs.jsonl"), None, None,
                           "cannot read")

    def test_folder_is_refused(self):
        path = os.path.join(self._dir.name, "runs.jsonl")
        os.mkdir(path)
        self.assertRefused(load_runs, path, None, None, "not a regular file")

    @unittest.skipUnless(hasattr(os, "mkfifo"), "no named pipes here")
    def test_pipe_is_refused_without_waiting_for_a_writer(self):
        path = os.path.join(self._dir.name, "runs.jsonl")
        os.mkfifo(path)
        self.assertRefused(load_runs, path, None, None, "not a regular file")

    def test_torn_last_line_is_skipped_with_a_warning(self):
        path = self.write("runs.jsonl", run_line(0) + "\n" + run_line(1) + "\n" + run_line(2)[:57])
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            runs = load_runs(path)
        self.assertEqual([r["run"] for r in runs], [0, 1])
        self.assertEqual(len(caught), 1)
        message = str(caught[0].message)
        self.assertTrue(message.startswith(path + ":3:"), message)
        self.assertIn("torn", message)
        self.assertEqual(caught[0].filename, __file__)  # the warning points at the caller

    def test_torn_last_line_cut_inside_a_character_is_skipped(self):
        torn = run_line(2).replace("hpa_mpc", "hpa_mpc \u00e9").encode()
        cut = torn.index(b"\xc3") + 1  # half of the two-byte character
        path = self.write("runs.jsonl", (run_line(0) + "\n").encode() + torn[:cut])
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            runs = load_runs(path)
        self.assertEqual(len(runs), 1)
        self.assertTrue(str(caught[0].message).startswith(path + ":2:"), caught[0].message)

    def test_bad_line_before_the_last_is_an_error(self):
        text = run_line(0) + "\n" + run_line(1)[:57] + "\n" + run_line(2) + "\n"
        self.assertRefused(load_runs, self.write("runs.jsonl", text), 2, None, "not valid JSON")

    def test_bad_last_line_with_its_newline_is_an_error(self):
        text = run_line(0) + "\n" + run_line(1)[:57] + "\n"
        self.assertRefused(load_runs, self.write("runs.jsonl", text), 2, None, "not valid JSON")

    def test_line_that_is_not_an_object_is_refused(self):
        for value in ("[1, 2]", '"run 1"', "3", "null"):
            with self.subTest(value=value):
                text = run_line(0) + "\n" + value + "\n" + run_line(2) + "\n"
                self.assertRefused(load_runs, self.write("runs.jsonl", text), 2, 1,
                                   "expected an object")

    def test_last_line_that_is_not_an_object_is_refused_not_skipped(self):
        text = run_line(0) + "\n[1, 2]"
        self.assertRefused(load_runs, self.write("runs.jsonl", text), 2, 1, "an array")

    def test_nan_names_line_and_column(self):
        bad = run_line(1).replace('"wall_time_s":3.1', '"wall_time_s":NaN')
        text = run_line(0) + "\n" + bad + "\n"
        column = bad.index("NaN") + 1
        self.assertRefused(load_runs, self.write("runs.jsonl", text), 2, column, "NaN")

    def test_infinity_names_line_and_column(self):
        bad = run_line(1).replace('"sim_time_s":12.0', '"sim_time_s":-Infinity')
        text = run_line(0) + "\n" + bad + "\n" + run_line(2) + "\n"
        column = bad.index("-Infinity") + 1
        self.assertRefused(load_runs, self.write("runs.jsonl", text), 2, column, "-Infinity")

    def test_invalid_utf8_names_line(self):
        data = (run_line(0) + "\n").encode() + b'{"run": "\xff"}\n' + (run_line(2) + "\n").encode()
        self.assertRefused(load_runs, self.write("runs.jsonl", data), 2, 10, "0xff")


# --- the lockstep client's decoding, on messages built here byte by byte (docs/protocol.md) ---

def pack_state(mode=1, flags=0):
    """A state: 20 f64 (time, p_WL_W, v_WL_W, p_WQ_W, v_WQ_W, q_WB, w_B) then mode and flags."""
    values = [0.5, 0, 0, 1, 0, 0, 0, 0, 0, 1.5, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0]
    return struct.pack("<20dII", *values, mode, flags)


def pack_tick(flags=0, found=1, reason=b"", truth_mode=1, truth_flags=0, frames=0):
    """A tick: allocation per flags, the reference, one IMU and one VIO sample, one detection,
    `frames` frames and, with flag 4, the truth."""
    out = struct.pack("<dI", 0.25, flags)
    if flags & 1:
        out += struct.pack("<d", 8.1)
    out += struct.pack("<9d", 0, 0, 1, 0, 0, 0, 0, 0, 0)
    out += struct.pack("<I7d", 1, 0.249, 0.01, 0.02, 0.03, 0, 0, 9.81)
    out += struct.pack("<I11d", 1, 0.2, 0, 0, 1.5, 1, 0, 0, 0, 0, 0, 0)
    out += struct.pack("<IdI6dI", 1, 0.24, found, 0.1, 0.2, 0.5, 320, 240, 12, len(reason)) + reason
    out += struct.pack("<I", frames)
    for slot in range(frames):
        out += struct.pack("<d4iII", 0.23, 0, 0, 64, 48, slot, slot)
    if flags & 4:
        out += pack_state(truth_mode, truth_flags)
    return out


def good_hello(**changes):
    hello = {"protocol_version": 1, "scenario": "hover", "seed": 1,
             "config": {"params": {"cable_length_m": 0.5}},
             "camera": {"ring": "/hpa_ring", "slots": 4, "width_px": 64, "height_px": 48,
                        "slot_bytes": 64 * 48 * 3}}
    hello.update(changes)
    return json.dumps(hello).encode()


class LockstepTest(unittest.TestCase):
    def assertProtocolError(self, decode, data, *fragments):
        """decode(data) raises a ProtocolError saying each fragment."""
        with self.assertRaises(ProtocolError) as caught:
            decode(data)
        for fragment in fragments:
            self.assertIn(fragment, str(caught.exception))
        return str(caught.exception)

    def test_good_tick_decodes(self):
        t = lockstep.decode_tick(pack_tick(flags=1 | 2 | 4 | 8 | 16, reason="seen \u00e9".encode(),
                                           truth_mode=0, truth_flags=7, frames=2))
        self.assertEqual(t.time_s, 0.25)
        self.assertEqual(t.allocation, (8.1, True))
        self.assertTrue(t.need_estimate and t.gripper_active)
        self.assertEqual(t.imu.shape, (1, 7))
        self.assertEqual(t.vio.shape, (1, 11))
        self.assertEqual(t.detections[0]["reason"], "seen \u00e9")
        self.assertTrue(t.detections[0]["found"])
        self.assertEqual([f["whole_slot"] for f in t.frames], [0, 1])
        self.assertEqual(t.truth["mode"], "slack")
        self.assertTrue(t.truth["payload_visible"] and t.truth["payload_supported"])

    def test_truth_taut_decodes(self):
        self.assertEqual(lockstep.decode_tick(pack_tick(flags=4, truth_mode=1)).truth["mode"], "taut")

    def test_unknown_cable_mode_is_refused(self):
        self.assertProtocolError(lockstep.decode_tick, pack_tick(flags=4, truth_mode=7),
                                 "malformed tick message", "cable mode 7")

    def test_unknown_state_flags_are_refused(self):
        self.assertProtocolError(lockstep.decode_tick, pack_tick(flags=4, truth_flags=8),
                                 "malformed tick message", "truth flags 0x8")

    def test_unknown_tick_flags_are_refused(self):
        self.assertProtocolError(lockstep.decode_tick, pack_tick(flags=64),
                                 "malformed tick message", "flags 0x40", "unknown bits")

    def test_saturated_without_allocation_is_refused(self):
        self.assertProtocolError(lockstep.decode_tick, pack_tick(flags=2),
                                 "malformed tick message", "without an allocation")

    def test_detection_found_other_than_0_or_1_is_refused(self):
        self.assertProtocolError(lockstep.decode_tick, pack_tick(found=2),
                                 "malformed tick message", "detection 0 found 2")

    def test_detection_reason_not_utf8_is_refused(self):
        self.assertProtocolError(lockstep.decode_tick, pack_tick(reason=b"lost \xff"),
                                 "malformed tick message", "detection 0's reason", "UTF-8")

    def test_short_tick_is_refused(self):
        self.assertProtocolError(lockstep.decode_tick, pack_tick()[:-3],
                                 "malformed tick message", "ends early")

    def test_trailing_bytes_are_refused(self):
        self.assertProtocolError(lockstep.decode_tick, pack_tick() + b"\0",
                                 "malformed tick message", "1 bytes after its end")

    def test_finish_errors_name_the_finish(self):
        self.assertProtocolError(lambda d: lockstep.decode_tick(d, "finish"),
                                 pack_tick(flags=4, truth_mode=7), "malformed finish message")

    def test_header_decodes(self):
        header = struct.pack("<III", lockstep.MAGIC, lockstep.TICK, 123)
        self.assertEqual(lockstep.decode_header(header), (lockstep.TICK, 123))

    def test_header_bad_magic_is_refused(self):
        self.assertProtocolError(lockstep.decode_header, b"GET / HTTP/1",
                                 "not an hpa lockstep message", "magic")

    def test_header_unknown_type_is_refused(self):
        self.assertProtocolError(lockstep.decode_header,
                                 struct.pack("<III", lockstep.MAGIC, 99, 0), "message type 99")

    def test_header_too_long_is_refused(self):
        header = struct.pack("<III", lockstep.MAGIC, lockstep.TICK, lockstep.MAX_MESSAGE_BYTES + 1)
        self.assertProtocolError(lockstep.decode_header, header, "tick message", "at most")

    def test_receive_refuses_unknown_type(self):
        # the client's own socket read, on one end of a socket pair
        ours, theirs = socket.socketpair()
        self.addCleanup(ours.close)
        self.addCleanup(theirs.close)
        client = lockstep.FlightStackClient.__new__(lockstep.FlightStackClient)
        client.sock, client.ring = ours, None
        theirs.sendall(struct.pack("<III", lockstep.MAGIC, 7, 4) + b"boom")
        self.assertProtocolError(lambda _: client.receive(), None, "the simulator reported: boom")
        theirs.sendall(struct.pack("<III", lockstep.MAGIC, 42, 0))
        self.assertProtocolError(lambda _: client.receive(), None, "message type 42")

    def test_good_hello_decodes(self):
        hello = lockstep.decode_hello(good_hello())
        self.assertEqual(hello["protocol_version"], 1)
        self.assertEqual(hello["camera"]["slots"], 4)
        without_camera = json.loads(good_hello())
        del without_camera["camera"]
        self.assertNotIn("camera", lockstep.decode_hello(json.dumps(without_camera).encode()))

    def test_hello_of_another_version_is_returned_for_the_caller_to_refuse(self):
        self.assertEqual(lockstep.decode_hello(good_hello(protocol_version=2, camera=[]))
                         ["protocol_version"], 2)

    def test_hello_malformed_json_is_refused(self):
        self.assertProtocolError(lockstep.decode_hello, b'{"protocol_version": 1,\n "seed": }',
                                 "hello message:2:10:", "not valid JSON")

    def test_hello_invalid_utf8_is_refused(self):
        self.assertProtocolError(lockstep.decode_hello, b'{"scenario": "\xc3("}',
                                 "hello message:1:15:", "UTF-8")

    def test_hello_nan_is_refused(self):
        self.assertProtocolError(lockstep.decode_hello, b'{"protocol_version": 1, "seed": NaN}',
                                 "hello message:1:33:", "NaN")

    def test_hello_not_an_object_is_refused(self):
        self.assertProtocolError(lockstep.decode_hello, b"[1]", "hello message:1:1:",
                                 "expected an object")

    def test_hello_without_version_is_refused(self):
        self.assertProtocolError(lockstep.decode_hello, b'{"seed": 1}', "hello message",
                                 "'protocol_version'")

    def test_hello_version_not_a_number_is_refused(self):
        self.assertProtocolError(lockstep.decode_hello, b'{"protocol_version": "1"}',
                                 "hello message", "'protocol_version' is '1'")

    def test_hello_camera_without_ring_is_refused(self):
        hello = json.loads(good_hello())
        del hello["camera"]["ring"]
        self.assertProtocolError(lockstep.decode_hello, json.dumps(hello).encode(),
                                 "hello message's camera", "'ring'")

    def test_hello_camera_slots_too_small_is_refused(self):
        hello = json.loads(good_hello())
        hello["camera"]["slot_bytes"] = 100
        self.assertProtocolError(lockstep.decode_hello, json.dumps(hello).encode(),
                                 "hello message's camera", "'slot_bytes' 100")

    def test_reply_encodes(self):
        reply = lockstep.encode_reply(lockstep.Command([0.1, 0.2, 0.3], 8.0, "fallback"),
                                      {"mode": "slack", "payload_lost": False})
        flags, = struct.unpack_from("<I", reply)
        self.assertEqual(flags, 3)
        status, = struct.unpack_from("<I", reply, 4 + 32)
        self.assertEqual(status, lockstep.STATUS.index("fallback"))
        mode, state_flags = struct.unpack_from("<II", reply, 4 + 56 + 160)
        self.assertEqual((mode, state_flags), (0, 0))

    def test_reply_unknown_status_is_refused(self):
        with self.assertRaises(ValueError) as caught:
            lockstep.encode_reply(lockstep.Command([0, 0, 0], 8.0, "fine"), None)
        self.assertIn("'fine'", str(caught.exception))

    def test_reply_unknown_estimate_mode_is_refused(self):
        with self.assertRaises(ValueError) as caught:
            lockstep.encode_reply(None, {"mode": "loose"})
        self.assertIn("'loose'", str(caught.exception))


class Hover:
    """A controller for run(): a constant command."""

    def __init__(self, hello):
        self.hello = hello

    def step(self, tick):
        return lockstep.Command([0, 0, 0], 8.0)


class RunTest(unittest.TestCase):
    """run() against a simulator played by a thread on a Unix socket."""

    def serve(self, messages):
        """Serves the hello then `messages` (type, body), one per reply; returns the replies
        (type, body) and run()'s exit code."""
        code, replies = fake_simulator.serve(Hover, good_hello(camera=None), messages)
        return replies, code

    def test_a_session_is_served(self):
        replies, code = self.serve([(lockstep.TICK, pack_tick(flags=8)),
                                    (lockstep.FINISH, pack_tick())])
        self.assertEqual(code, 0)
        self.assertEqual([kind for kind, _ in replies],
                         [lockstep.HELLO_ACK, lockstep.TICK_REPLY, lockstep.FINISH_REPLY])
        self.assertEqual(json.loads(replies[0][1])["name"], "test")

    def test_unknown_mode_ends_the_run_telling_the_simulator(self):
        replies, code = self.serve([(lockstep.TICK, pack_tick(flags=4, truth_mode=7))])
        self.assertEqual(code, 1)
        self.assertEqual(replies[-1][0], lockstep.ERROR)
        self.assertIn("malformed tick message: truth cable mode 7", replies[-1][1].decode())

    def test_unexpected_message_type_ends_the_run(self):
        replies, code = self.serve([(lockstep.HELLO, good_hello())])
        self.assertEqual(code, 1)
        self.assertIn("expected a tick or finish, got a hello message", replies[-1][1].decode())


if __name__ == "__main__":
    unittest.main()
