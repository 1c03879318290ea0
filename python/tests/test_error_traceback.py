"""A stack that raises tells the simulator where: the error message (the run's run_error) names
the innermost stack frames as FILE:LINE in FUNCTION, then the exception, within
lockstep.ERROR_MAX_BYTES. The simulator is played by a thread on a Unix socket."""

import json
import os
import struct
import unittest

from hpa_sim import lockstep

import fake_simulator

THIS_FILE = os.path.abspath(__file__)


def _hello():
    """The smallest hello run() accepts: protocol version 1, no camera."""
    return json.dumps({"protocol_version": 1, "scenario": "hover", "seed": 1}).encode()


def _tick(time_s=0.001):
    """A tick with no sensor messages that asks for an estimate (flag 8)."""
    return struct.pack("<dI9dIIII", time_s, 8, *([0.0] * 9), 0, 0, 0, 0)


def _gains(scale):
    raise ValueError("boom at scale %g" % scale)  # the innermost frame the error must name


def _gains_line():
    """The line of _gains's raise in this file."""
    return _gains.__code__.co_firstlineno + 1


class RaisesInStep:
    """A controller whose step raises two calls down (step -> _control -> _gains)."""

    def __init__(self, hello):
        self.hello = hello

    def step(self, tick):
        return self._control(tick)

    def _control(self, tick):
        return _gains(2.0)


class RaisesLongText:
    """A controller whose exception text is far longer than an error message may be."""

    def __init__(self, hello):
        raise RuntimeError("\u00e9" * 100000)


def serve(controller_class):
    """Runs run(controller_class) against a simulator that sends the hello, then ticks until
    the stack answers with something other than a tick reply; returns run()'s exit code and the
    error message's text (None if there was none)."""
    code, replies = fake_simulator.serve(controller_class, _hello(),
                                         [(lockstep.TICK, _tick())] * 3)
    errors = [body for kind, body in replies if kind == lockstep.ERROR]
    return code, (errors[0].decode("utf-8") if errors else None)


class ErrorTracebackTest(unittest.TestCase):
    def test_a_raising_step_names_its_innermost_frames_then_the_exception(self):
        code, text = serve(RaisesInStep)
        self.assertEqual(code, 1)
        self.assertIsNotNone(text, "the stack sent no error message")
        self.assertTrue(text.startswith("Traceback (last 3 frames, 1 before them left out): "),
                        text)
        # the three innermost frames, outermost first, then the exception
        self.assertIn("%s:%d in _gains" % (THIS_FILE, _gains_line()), text)
        self.assertIn("in step; ", text)
        self.assertIn("in _control; ", text)
        self.assertLess(text.index("in step;"), text.index("in _control;"))
        self.assertLess(text.index("in _control;"), text.index("in _gains;"))
        self.assertNotIn("in run;", text)  # the fourth frame from the top is left out
        self.assertTrue(text.endswith("; ValueError: boom at scale 2"), text)

    def test_a_long_exception_text_is_cut_within_the_limit(self):
        code, text = serve(RaisesLongText)
        self.assertEqual(code, 1)
        data = text.encode("utf-8")
        self.assertLessEqual(len(data), lockstep.ERROR_MAX_BYTES)
        self.assertLess(lockstep.ERROR_MAX_BYTES, lockstep.MAX_MESSAGE_BYTES)
        self.assertIn("in __init__; RuntimeError: \u00e9\u00e9", text)
        self.assertRegex(text, r" \.\.\. \(\d+ bytes cut\)$")
        # what was kept and what was cut add up to the whole text (frames, type, 100000 x 2 bytes)
        cut = int(text.rsplit("(", 1)[1].split()[0])
        kept = len(text.rsplit(" ... (", 1)[0].encode("utf-8"))
        head = text[:text.index("RuntimeError: ") + len("RuntimeError: ")]
        self.assertEqual(kept + cut, len(head.encode("utf-8")) + 2 * 100000)

    def test_an_exception_without_a_traceback_is_its_type_and_text(self):
        self.assertEqual(lockstep.describe_exception(KeyError("x")), "KeyError: 'x'")
        self.assertEqual(lockstep.describe_exception(StopIteration()), "StopIteration")


if __name__ == "__main__":
    unittest.main()
