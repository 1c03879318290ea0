#!/usr/bin/env python3
"""A geometric position controller for the quadrotor, in Python, flown through hpa-sim's
lockstep protocol:

    hpa run examples/python/hover_gripper_pull_example.yaml \
        --flight-stack "python3 examples/python/hover_controller.py"

(hover_gripper_pull with this controller's own expect bounds: docs/python.md).

It holds the quadrotor above the payload reference (x_Q* = x_L* + l e3, the payload hanging
under it) from what a flight computer has: VIO poses (30 Hz, late by their latency), the IMU
(500 Hz) and the thrust the rate loop allocated. Each VIO pose resets the position and velocity
at its capture time and the IMU carries them to now (so a VIO dropout is bridged). It does not
track the payload; it tells a taut cable from a slack one by the tension the accelerometer and
the thrust imply (a tension cue, as the in-process estimator has), reports that as the
estimate's `mode`, and carries the payload's weight only while the cable is taut. On a scenario
with `estimation.ground_truth: true` it flies on the true state the ticks carry instead. A
starting point for one's own controller, not HPA-MPC.

The controller (Lee, Leok and McClamroch's geometric control, position loop plus attitude
error to body-rate command): F = m (a* + g e3 + k_p e_p + k_d e_v + k_i int e_p) with
m = m_Q + m_L taut and m_Q slack, thrust = F . R e3 / s (s the rotors' thrust scale the tension
cue learns), body rate = -k_R vee(R_d^T R - R^T R_d) / 2 with R_d's third axis along F and zero
yaw.
"""

import os
import sys

import numpy as np

try:
    # the installed package (python3 -m pip install ./python, docs/extending.md)
    from hpa_sim import Command, run
except ImportError:
    # else the client beside this example: hpa's source tree, or an installed share/hpa
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..",
                                    "python"))
    from hpa_sim import Command, run

# Gains: a 2 rad/s position loop with damping 0.75 (slow against the 30 Hz VIO and its
# latency), an integral for what the thrust scale the tension cue learns leaves (drag, the
# payload's swing), a 6 1/s attitude loop (the rate loop underneath is PX4's at 1 kHz).
K_P, K_D, K_I, K_R = 4.0, 3.0, 1.0, 6.0
CONTROL_RATE_HZ = 100.0


def quat_to_rot(q):
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def quat_mul(a, b):
    w1, x1, y1, z1 = a
    w2, x2, y2, z2 = b
    return np.array([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                     w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2])


def integrate_gyro(q, w_B_radps, dt_s):
    angle = np.linalg.norm(w_B_radps) * dt_s
    if angle < 1e-12:
        return q
    axis = w_B_radps / np.linalg.norm(w_B_radps)
    dq = np.concatenate([[np.cos(angle / 2)], np.sin(angle / 2) * axis])
    q = quat_mul(q, dq)
    return q / np.linalg.norm(q)


class TensionCue:
    """Whether the cable is slack, from the tension the IMU and the thrust imply. Taut, the cable
    pulls the quadrotor down along it: m_Q s_W = f R e3 + T xi (s the specific force, f the
    thrust, xi the cable's direction from the vehicle, about -e3 under a hovering vehicle), so
    T = xi . (m_Q R s_B - f R e3). The allocated thrust is the model's, a few per cent off the
    rotors' (the flight profile's thrust-coefficient mismatch: 0.2-0.3 N, a quarter of the
    payload's weight), so the cue learns the rotors' scale while taut, where the tension is the
    one the payload's reference asks for, m_L |a_L* + g e3|. The tension is low-passed over a few
    IMU samples; the cable is slack below a quarter of the payload's weight and taut again above
    three quarters of it (a re-taut's snap reads above 1.2)."""

    FILTER_TIME_CONSTANT_S = 0.02  # averages the accelerometer noise over ~10 IMU samples
    SCALE_TIME_CONSTANT_S = 1.0  # the thrust scale drifts with the battery, over seconds
    SLACK_FRACTION, TAUT_FRACTION = 0.25, 0.75  # of the hanging weight m_L g (hysteresis)

    def __init__(self, p):
        self.quad_mass_kg, self.payload_mass_kg = p["quad_mass_kg"], p["payload_mass_kg"]
        self.g = p["gravity_mps2"]
        self.weight_N = self.payload_mass_kg * self.g
        self.motor_time_constant_s = p["motor_time_constant_s"]
        self.thrust_N = (self.quad_mass_kg + self.payload_mass_kg) * self.g
        self.thrust_scale = 1.0  # the rotors' thrust over the allocated one
        self.tension_N = self.weight_N  # the run starts hanging: taut
        self.slack = False
        self.last_time_s = None

    def update(self, time_s, specific_force_B_mps2, R_WB, thrust_allocated_N, a_WL_W_ref):
        """Feeds one IMU sample (its time, specific force in the body frame), the attitude, the
        thrust last allocated (N) and the payload reference's acceleration (m/s^2); returns
        whether the cable is slack."""
        dt_s = 0.0 if self.last_time_s is None else time_s - self.last_time_s
        if dt_s < 0.0:
            return self.slack
        self.last_time_s = time_s
        # the rotors reach the allocated thrust through their spin-up lag
        self.thrust_N += (1.0 - np.exp(-dt_s / self.motor_time_constant_s)) * (
            thrust_allocated_N - self.thrust_N)
        # vertical parts (xi = -e3): T = s f (R e3)_z - m_Q (R s_B)_z
        lift_N = self.thrust_N * R_WB[2, 2]
        specific_force_z_N = self.quad_mass_kg * (R_WB[2, :] @ specific_force_B_mps2)
        if lift_N > 0.0:
            expected_N = 0.0 if self.slack else self.payload_mass_kg * np.linalg.norm(
                a_WL_W_ref + [0.0, 0.0, self.g])
            scale = (expected_N + specific_force_z_N) / lift_N
            self.thrust_scale += (1.0 - np.exp(-dt_s / self.SCALE_TIME_CONSTANT_S)) * (
                scale - self.thrust_scale)
        tension_N = self.thrust_scale * lift_N - specific_force_z_N
        self.tension_N += (1.0 - np.exp(-dt_s / self.FILTER_TIME_CONSTANT_S)) * (
            tension_N - self.tension_N)
        if self.slack and self.tension_N > self.TAUT_FRACTION * self.weight_N:
            self.slack = False
        if not self.slack and self.tension_N < self.SLACK_FRACTION * self.weight_N:
            self.slack = True
        return self.slack


def blend_toward(q_from, q_to, fraction):
    """The attitude `fraction` of the way from q_from to q_to (w, x, y, z), along the shorter
    rotation between them."""
    w1, x1, y1, z1 = q_from
    d = quat_mul(q_to, np.array([w1, -x1, -y1, -z1]))  # q_to q_from^-1
    if d[0] < 0.0:
        d = -d
    angle = 2.0 * np.arctan2(np.linalg.norm(d[1:]), d[0])
    if angle < 1e-12:
        return q_from
    axis = d[1:] / np.linalg.norm(d[1:])
    step = np.concatenate([[np.cos(fraction * angle / 2)], np.sin(fraction * angle / 2) * axis])
    q = quat_mul(step, q_from)
    return q / np.linalg.norm(q)


class VioImuState:
    """The vehicle's position, velocity and attitude from VIO poses and the IMU: each pose (late
    by its latency) resets the position and velocity at its capture time and pulls the attitude
    a tenth of the way toward its own (averaging the pose's 0.01 rad noise over about ten poses:
    a tilt error lets gravity leak into the dead reckoning), and the IMU samples since then
    carry the state to now (the gyro turns the attitude, the specific force in the world plus
    gravity moves it), so a VIO dropout of a few seconds is bridged by the IMU."""

    KEEP_IMU_S = 1.0  # IMU samples kept for re-prediction: longer than any VIO latency
    ATTITUDE_GAIN = 0.1  # the share of a pose's attitude taken at each pose

    def __init__(self, initial_state, g):
        self.g = g
        self.t_s = 0.0  # time of the state (the last IMU sample's)
        self.p_WQ_W = np.array(initial_state["p_WQ_W"], dtype=float)
        self.v_WQ_W = np.array(initial_state["v_WQ_W"], dtype=float)
        self.q_WB = np.array(initial_state["q_WB_wxyz"], dtype=float)
        self.w_B = np.zeros(3)
        self.imu = []  # (t_s, w_B, specific force_B, q_WB before the sample), oldest first

    def update(self, tick):
        """Takes a tick's IMU samples and VIO poses; the state is then at the last sample."""
        self.imu = [s for s in self.imu if s[0] >= tick.time_s - self.KEEP_IMU_S]
        start = len(self.imu)
        self.imu += [(row[0], row[1:4], row[4:7], None) for row in tick.imu]
        if len(tick.vio):
            # re-predict from the newest pose's capture with the IMU samples since
            v = tick.vio[-1]
            later = [i for i, s in enumerate(self.imu) if s[0] >= v[0]]
            start = later[0] if later else len(self.imu)
            q_then = self.imu[start][3] if later and self.imu[start][3] is not None else self.q_WB
            self.t_s, self.p_WQ_W, self.v_WQ_W = v[0], v[1:4].copy(), v[8:11].copy()
            self.q_WB = blend_toward(q_then, v[4:8] / np.linalg.norm(v[4:8]), self.ATTITUDE_GAIN)
            self.imu = self.imu[start:]
            start = 0
        for i in range(start, len(self.imu)):
            t_s, w_B, f_B, _ = self.imu[i]
            self.imu[i] = (t_s, w_B, f_B, self.q_WB)
            dt_s = t_s - self.t_s
            if dt_s > 0.0:
                a_W = quat_to_rot(self.q_WB) @ f_B - np.array([0.0, 0.0, self.g])
                self.p_WQ_W = self.p_WQ_W + self.v_WQ_W * dt_s + 0.5 * a_W * dt_s ** 2
                self.v_WQ_W = self.v_WQ_W + a_W * dt_s
                self.q_WB = integrate_gyro(self.q_WB, w_B, dt_s)
                self.t_s = t_s
            self.w_B = w_B

    def at(self, time_s):
        """Position (m) and velocity (m/s) at time_s, a few ms past the last sample."""
        return self.p_WQ_W + self.v_WQ_W * (time_s - self.t_s), self.v_WQ_W


class HoverController:
    """Holds the quadrotor above the payload reference from VIO, the IMU and the allocated
    thrust, carrying the payload's weight while the tension cue says the cable is taut."""

    def __init__(self, hello):
        p = hello["config"]["params"]
        self.quad_mass_kg, self.payload_mass_kg = p["quad_mass_kg"], p["payload_mass_kg"]
        self.g = p["gravity_mps2"]
        self.cable_m = p["cable_length_m"]
        self.max_thrust_N = 4 * p["k_f_N_per_radps2"] * p["motor_speed_max_radps"] ** 2
        self.state = VioImuState(hello["config"]["initial_state"], self.g)
        self.integral = np.zeros(3)
        self.next_control_s = 0.0
        self.estimate = None
        self.tension = TensionCue(p)
        self.thrust_allocated_N = self.tension.thrust_N  # until the first allocation arrives

    def step(self, tick):
        self.state.update(tick)
        # the cable's mode from the tension each IMU sample implies
        if tick.allocation is not None:
            self.thrust_allocated_N = tick.allocation[0]
        R = quat_to_rot(self.state.q_WB)
        for t, _, _, _, fx, fy, fz in tick.imu:
            self.tension.update(t, np.array([fx, fy, fz]), R, self.thrust_allocated_N,
                                tick.reference["a_WL_W"])
        slack = self.tension.slack
        p, v = self.state.at(tick.time_s)
        # the estimate the simulator logs: the vehicle's state, the cable's mode, and the payload
        # only guessed (hanging under the vehicle, flagged lost: this controller does not track it)
        self.estimate = {"p_WQ_W": p, "v_WQ_W": v, "q_WB": self.state.q_WB, "w_B": self.state.w_B,
                         "p_WL_W": p - np.array([0, 0, self.cable_m]),
                         "mode": "slack" if slack else "taut", "payload_lost": True}
        if tick.truth is not None:
            # the scenario's ground-truth switch: fly on the true state, as the in-process
            # controllers do, so that what the run records as its basis is what flew
            self.estimate = tick.truth
            p, v = tick.truth["p_WQ_W"], tick.truth["v_WQ_W"]
            R = quat_to_rot(tick.truth["q_WB"])
            slack = tick.truth["mode"] == "slack"
        if tick.time_s + 1e-9 < self.next_control_s:
            return None
        self.next_control_s += 1.0 / CONTROL_RATE_HZ

        ref = tick.reference
        p_star = ref["p_WL_W"] + np.array([0, 0, self.cable_m])
        e_p, e_v = p_star - p, ref["v_WL_W"] - v
        # taut, the vehicle carries the payload too; slack, only itself
        mass_kg = self.quad_mass_kg + (0.0 if slack else self.payload_mass_kg)
        self.integral = np.clip(self.integral + e_p / CONTROL_RATE_HZ, -1.0, 1.0)
        force_W = mass_kg * (ref["a_WL_W"] + np.array([0, 0, self.g]) + K_P * e_p + K_D * e_v
                             + K_I * self.integral)
        # the thrust to allocate for the force wanted, through the rotors' learned scale
        thrust_N = float(np.clip(force_W @ R[:, 2] / self.tension.thrust_scale, 0.0,
                                 self.max_thrust_N))
        b3 = force_W / np.linalg.norm(force_W)
        b2 = np.cross(b3, [1.0, 0.0, 0.0])
        b2 /= np.linalg.norm(b2)
        Rd = np.column_stack([np.cross(b2, b3), b2, b3])
        E = Rd.T @ R - R.T @ Rd
        e_R = 0.5 * np.array([E[2, 1], E[0, 2], E[1, 0]])
        return Command(-K_R * e_R, thrust_N)


if __name__ == "__main__":
    sys.exit(run(HoverController, name="python hover_controller", control_rate_hz=CONTROL_RATE_HZ))
