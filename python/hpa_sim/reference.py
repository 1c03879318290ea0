"""The payload reference a hello describes, evaluated in Python as the simulator evaluates it.

A team's stack gets no reference in its team_tick: the team_hello's `reference` (the same object
as a single vehicle's hello's config.reference) describes it, and each stack builds it, as
hpa-flight builds the C++ Reference (controller/src/reference.cc). PayloadReference does the same
for the built-in types: hover, line, lissajous, circle, figure_eight (the Lissajous family) and
csv (its samples travel in the hello).

    from hpa_sim import PayloadReference
    reference = PayloadReference(hello["reference"])
    r = reference.at(t_s)   # dict: p_WL_W, v_WL_W, a_WL_W, j_WL_W (numpy arrays, world)
"""

import math

import numpy as np

# the types whose evaluation this module carries (those the C++ registry has built in)
TYPES = ("hover", "line", "lissajous", "circle", "figure_eight", "csv")


def _min_jerk(tau):
    # s(tau) = 10 tau^3 - 15 tau^4 + 6 tau^5 and its derivatives in tau 1..4, held outside [0, 1]
    if tau <= 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0
    if tau >= 1.0:
        return 1.0, 0.0, 0.0, 0.0, 0.0
    t2, t3 = tau * tau, tau * tau * tau
    t4, t5 = t3 * tau, t3 * tau * tau
    return (10 * t3 - 15 * t4 + 6 * t5, 30 * t2 - 60 * t3 + 30 * t4, 60 * tau - 180 * t2 + 120 * t3,
            60 - 360 * tau + 360 * t2, -360 + 720 * tau)


def _vector(spec, key):
    v = np.array(spec[key], dtype=float)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise ValueError("reference: '%s' is %r, expected 3 finite numbers" % (key, spec[key]))
    return v


class PayloadReference:
    """The payload reference of a hello's `reference` object (type, payload_position_W_m,
    lissajous, line_*, samples_t_p_v_a): at(t_s) gives the payload's position, velocity,
    acceleration and jerk at simulated time t_s, as the simulator's Reference gives them (the
    payload's centre, world frame). A type outside TYPES (one registered beyond the built-ins)
    or a spec missing its keys is a ValueError naming it."""

    def __init__(self, spec):
        if not isinstance(spec, dict) or not isinstance(spec.get("type"), str):
            raise ValueError("reference: %r, expected an object with a 'type'" % (spec,))
        self.type = spec["type"]
        if self.type not in TYPES:
            raise ValueError("reference type '%s': the Python client evaluates %s"
                             % (self.type, ", ".join(TYPES)))
        try:
            if self.type == "hover":
                self._position = _vector(spec, "payload_position_W_m")
            elif self.type == "line":
                self._start = _vector(spec, "line_start_W_m")
                self._delta = _vector(spec, "line_end_W_m") - self._start
                self._duration = float(spec["line_duration_s"])
                self._start_time = float(spec["line_start_time_s"])
                if not self._duration > 0.0:
                    raise ValueError("reference: line_duration_s %r, expected > 0"
                                     % self._duration)
            elif self.type == "csv":
                rows = np.array(spec["samples_t_p_v_a"], dtype=float)
                if rows.ndim != 2 or rows.shape[0] < 2 or rows.shape[1] != 10:
                    raise ValueError("reference: samples_t_p_v_a has shape %s, expected at least "
                                     "two rows of 10 numbers" % (rows.shape,))
                self._samples = rows
            else:  # the Lissajous family: circle and figure_eight fill the same keys
                self._lissajous = {k: float(v) for k, v in spec["lissajous"].items()
                                   if k != "centre"}
                self._centre = _vector(spec["lissajous"], "centre")
                if not (self._lissajous["period_s"] > 0.0 and self._lissajous["ramp_s"] >= 0.0):
                    raise ValueError("reference: lissajous needs period_s > 0 and ramp_s >= 0")
        except KeyError as e:
            raise ValueError("reference of type '%s' has no %s" % (self.type, e)) from None
        self._evaluate = {"hover": self._hover, "line": self._line,
                          "csv": self._csv}.get(self.type, self._lissajous_at)

    def at(self, t_s):
        """The payload reference at time t_s: a dict of p_WL_W (m), v_WL_W (m/s), a_WL_W
        (m/s^2) and j_WL_W (m/s^3), each a numpy array of 3, world frame."""
        d = self._evaluate(float(t_s))
        return {"p_WL_W": d[0], "v_WL_W": d[1], "a_WL_W": d[2], "j_WL_W": d[3]}

    def _hover(self, t_s):
        zero = np.zeros(3)
        return self._position.copy(), zero, zero.copy(), zero.copy()

    def _line(self, t_s):
        # a minimum-jerk straight line, holding its start before start_time
        tau_s = t_s - self._start_time
        s = _min_jerk(tau_s / self._duration)
        return tuple([self._start + s[0] * self._delta]
                     + [s[i] / self._duration ** i * self._delta for i in (1, 2, 3)])

    def _csv(self, t_s):
        # linear in p, v and a between samples; the first sample before them, the last at rest
        rows = self._samples
        zero = np.zeros(3)
        if t_s <= rows[0, 0]:
            return rows[0, 1:4].copy(), rows[0, 4:7].copy(), rows[0, 7:10].copy(), zero
        if t_s >= rows[-1, 0]:
            return rows[-1, 1:4].copy(), zero, zero.copy(), zero.copy()
        k = int(np.searchsorted(rows[:, 0], t_s, side="right"))
        a, b = rows[k - 1], rows[k]
        h = b[0] - a[0]
        w = (t_s - a[0]) / h
        p, v, acc = (a[i:i + 3] + w * (b[i:i + 3] - a[i:i + 3]) for i in (1, 4, 7))
        return p, v, acc, (b[7:10] - a[7:10]) / h

    def _lissajous_at(self, t_s):
        # x_L = [a sin(theta), b sin(n theta + phi), c sin(m theta)] + [0, 0, psi] + centre, the
        # phase rate ramped from 0 to w over `ramp` by a minimum-jerk blend
        s_ = self._lissajous
        w = 2.0 * math.pi / s_["period_s"]
        ramp = s_["ramp_s"]
        th = [0.0, 0.0, 0.0, 0.0]  # theta and its time derivatives 1..3
        if t_s > 0.0:
            if ramp > 0.0 and t_s < ramp:
                tau = t_s / ramp
                s = _min_jerk(tau)
                th = [w * ramp * (2.5 * tau ** 4 - 3.0 * tau ** 5 + tau ** 6), w * s[0],
                      w * s[1] / ramp, w * s[2] / ramp ** 2]
            else:
                th = [w * (0.5 * max(ramp, 0.0) + (t_s - max(ramp, 0.0))), w, 0.0, 0.0]
        amp = np.array([s_["a"], s_["b"], s_["c"]])
        freq = np.array([1.0, s_["n"], s_["m"]])
        offset = np.array([0.0, s_["phi"], 0.0])
        # f^(i)(theta) = A k^i sin(k theta + offset + i pi / 2), then the chain rule
        f = [amp * freq ** i * np.sin(freq * th[0] + offset + i * math.pi / 2.0)
             for i in range(4)]
        p = f[0] + np.array([0.0, 0.0, s_["psi"]]) + self._centre
        v = f[1] * th[1]
        acc = f[2] * th[1] ** 2 + f[1] * th[2]
        jerk = f[3] * th[1] ** 3 + 3.0 * f[2] * th[1] * th[2] + f[1] * th[3]
        return p, v, acc, jerk
