#!/usr/bin/env python3
"""A geometric position controller for the quadrotor, in Python, flown through hpa-sim's
lockstep protocol:

    hpa run --flight-stack "python3 examples/python/hover_controller.py" \
        scenarios/hover_gripper_pull.yaml

It holds the quadrotor above the payload reference (x_Q* = x_L* + l e3, the payload hanging
under it) from what a flight computer has: VIO poses (30 Hz, late by their latency) and the
IMU gyro (500 Hz). Between VIO poses it predicts the position with the VIO velocity and the
attitude with the gyro. It treats the payload as mass hanging under the vehicle (thrust for
m_Q + m_L) and does not estimate it: a starting point for one's own controller, not HPA-MPC.

The controller (Lee, Leok and McClamroch's geometric control, position loop plus attitude
error to body-rate command): F = (m_Q + m_L) (a* + g e3 + k_p e_p + k_d e_v + k_i int e_p),
thrust = F . R e3, body rate = -k_R vee(R_d^T R - R^T R_d) / 2 with R_d's third axis along F
and zero yaw.
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
# latency), a small integral for the payload's unmodelled pull, a 6 1/s attitude loop (the
# rate loop underneath is PX4's at 1 kHz).
K_P, K_D, K_I, K_R = 4.0, 3.0, 0.5, 6.0
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


class HoverController:
    """Holds the quadrotor above the payload reference from VIO and the gyro."""

    def __init__(self, hello):
        p = hello["config"]["params"]
        self.mass_kg = p["quad_mass_kg"] + p["payload_mass_kg"]
        self.g = p["gravity_mps2"]
        self.cable_m = p["cable_length_m"]
        self.max_thrust_N = 4 * p["k_f_N_per_radps2"] * p["motor_speed_max_radps"] ** 2
        s = hello["config"]["initial_state"]
        self.vio = (0.0, np.array(s["p_WQ_W"]), np.array(s["v_WQ_W"]))  # (t, p, v)
        self.q = np.array(s["q_WB_wxyz"], dtype=float)
        self.gyro = []  # (t, w_B) since the last VIO pose's capture
        self.integral = np.zeros(3)
        self.next_control_s = 0.0
        self.estimate = None

    def step(self, tick):
        for t, wx, wy, wz, _, _, _ in tick.imu:
            self.gyro.append((t, np.array([wx, wy, wz])))
        if len(tick.vio):
            v = tick.vio[-1]
            self.vio = (v[0], v[1:4], v[8:11])
            # re-predict the attitude from the pose's capture time with the gyro since
            self.q = v[4:8] / np.linalg.norm(v[4:8])
            self.gyro = [(t, w) for t, w in self.gyro if t >= v[0]]
            for i, (t, w) in enumerate(self.gyro):
                t_next = self.gyro[i + 1][0] if i + 1 < len(self.gyro) else tick.time_s
                self.q = integrate_gyro(self.q, w, t_next - t)
        elif len(tick.imu):
            for t, w in self.gyro[-len(tick.imu):]:
                self.q = integrate_gyro(self.q, w, 0.002)
        t_vio, p_vio, v_vio = self.vio
        p = p_vio + v_vio * (tick.time_s - t_vio)
        w_B = self.gyro[-1][1] if self.gyro else np.zeros(3)
        self.estimate = {"p_WQ_W": p, "v_WQ_W": v_vio, "q_WB": self.q, "w_B": w_B,
                         "p_WL_W": p - np.array([0, 0, self.cable_m]), "payload_lost": True}
        if tick.time_s + 1e-9 < self.next_control_s:
            return None
        self.next_control_s += 1.0 / CONTROL_RATE_HZ

        ref = tick.reference
        p_star = ref["p_WL_W"] + np.array([0, 0, self.cable_m])
        e_p, e_v = p_star - p, ref["v_WL_W"] - v_vio
        self.integral = np.clip(self.integral + e_p / CONTROL_RATE_HZ, -1.0, 1.0)
        force_W = self.mass_kg * (ref["a_WL_W"] + np.array([0, 0, self.g]) + K_P * e_p + K_D * e_v
                                  + K_I * self.integral)
        R = quat_to_rot(self.q)
        thrust_N = float(np.clip(force_W @ R[:, 2], 0.0, self.max_thrust_N))
        b3 = force_W / np.linalg.norm(force_W)
        b2 = np.cross(b3, [1.0, 0.0, 0.0])
        b2 /= np.linalg.norm(b2)
        Rd = np.column_stack([np.cross(b2, b3), b2, b3])
        E = Rd.T @ R - R.T @ Rd
        e_R = 0.5 * np.array([E[2, 1], E[0, 2], E[1, 0]])
        return Command(-K_R * e_R, thrust_N)


if __name__ == "__main__":
    sys.exit(run(HoverController, name="python hover_controller", control_rate_hz=CONTROL_RATE_HZ))
