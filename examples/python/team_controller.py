#!/usr/bin/env python3
"""A per-vehicle position controller for a team carrying one payload (docs/cooperative.md), in
Python, flown through hpa-sim's lockstep protocol:

    hpa run --flight-stack "python3 examples/python/team_controller.py" \\
        scenarios/ci/team2_line.yaml                      # one process per vehicle
    hpa run --flight-stack "python3 examples/python/team_controller.py" --team-stack one \\
        scenarios/ci/team2_line.yaml                      # one process for the team

Each vehicle holds its own point of the team's layout: its attachment point's reference (the
payload reference of the team_hello, moved by its attachment offset, the payload held level)
with its cable above it along the direction the payload's acceleration asks for (straight up at
rest), x_Q* = x_L* + p_PA_P + l u, u = (a_L* + g e3) / |a_L* + g e3|. It flies there with a
geometric position controller (Lee, Leok and McClamroch, as examples/python/hover_controller.py)
whose feed-forward carries its own weight and its share of the payload's (payload mass / N):

    F = (m_Q + m_L / N) (a_L* + g e3 + k_p e_p + k_d e_v + k_i int e_p)

thrust = F . R e3, body rate = -k_R vee(R_d^T R - R^T R_d) / 2 with R_d's third axis along F and
zero yaw. The payload's state serves only to read whether its cable is taut: the controller
knows nothing of the other vehicles and does not control the payload's swing or attitude. A
starting point for one's own team controller, not RotorTM's cooperative controller.
"""

import os
import sys

import numpy as np

try:
    # the installed package (python3 -m pip install ./python, docs/extending.md)
    from hpa_sim import Command, PayloadReference, run_team
except ImportError:
    # else the client beside this example: hpa's source tree, or an installed share/hpa
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..",
                                    "python"))
    from hpa_sim import Command, PayloadReference, run_team

# Gains: a 2.5 rad/s position loop with damping 0.8 on motion capture (100 Hz, 10 ms late), a
# small integral for what the feed-forward misses (the payload's share is not exactly m_L / N
# when the team tilts), a 6 1/s attitude loop (the autopilot's rate loop underneath runs at
# 500 Hz). The control loop runs at the cooperative controller's 100 Hz.
K_P, K_D, K_I, K_R = 6.0, 4.0, 0.5, 6.0
CONTROL_RATE_HZ = 100.0
LEVEL_GAIN_PER_S = 6.5  # PX4's attitude gain, the level-out's (hpa::LevelOutCommand)
E3 = np.array([0.0, 0.0, 1.0])


def quat_to_rot(q):
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


class TeamVehicle:
    """One vehicle of the team: holds its attachment point's reference at its cable's length
    above, carrying its own weight and its share of the payload's."""

    def __init__(self, hello, vehicle):
        team = hello["team"]
        me = team["vehicles"][vehicle]
        p = me["params"]
        self.vehicle = vehicle
        self.quad_kg = p["quad_mass_kg"]
        self.share_kg = team["payload_mass_kg"] / len(team["vehicles"])
        self.g = team["gravity_mps2"]
        self.cable_m = me["cable_length_m"]
        self.p_PA_P = np.array(me["p_PA_P_m"], dtype=float)
        self.slack_m = p["slack_epsilon_m"]
        self.max_thrust_N = 4 * p["k_f_N_per_radps2"] * p["motor_speed_max_radps"] ** 2
        self.reference = PayloadReference(hello["reference"])
        self.integral = np.zeros(3)
        self.cable_taut = True  # run_team sends it with each reply

    def step(self, view):
        """The body-rate and thrust command from this vehicle's view of the team."""
        mass_kg = self.quad_kg + self.share_kg
        if not view.all_finite():
            return self.level_out(view)
        # taut when its attachment point is (nearly) a cable's length away
        p_A = view.p_WL_W + quat_to_rot(view.q_WP) @ self.p_PA_P
        self.cable_taut = bool(np.linalg.norm(view.p_WQ_W - p_A) > self.cable_m - self.slack_m)

        ref = self.reference.at(view.time_s)
        # the cable's direction a point payload's acceleration asks for, u, and its rate
        n = ref["a_WL_W"] + self.g * E3
        u = n / np.linalg.norm(n)
        u_dot = (ref["j_WL_W"] - u * (u @ ref["j_WL_W"])) / np.linalg.norm(n)
        p_star = ref["p_WL_W"] + self.p_PA_P + self.cable_m * u
        v_star = ref["v_WL_W"] + self.cable_m * u_dot
        e_p, e_v = p_star - view.p_WQ_W, v_star - view.v_WQ_W
        self.integral = np.clip(self.integral + e_p / CONTROL_RATE_HZ, -1.0, 1.0)
        # its own weight and its share of the payload's, with the payload's acceleration
        force_W = mass_kg * (n + K_P * e_p + K_D * e_v + K_I * self.integral)

        R = quat_to_rot(view.q_WB)
        thrust_N = float(np.clip(force_W @ R[:, 2], 0.0, self.max_thrust_N))
        b3 = force_W / np.linalg.norm(force_W)
        b2 = np.cross(b3, [1.0, 0.0, 0.0])
        b2 /= np.linalg.norm(b2)
        Rd = np.column_stack([np.cross(b2, b3), b2, b3])
        E = Rd.T @ R - R.T @ Rd
        e_R = 0.5 * np.array([E[2, 1], E[0, 2], E[1, 0]])
        return Command(-K_R * e_R, thrust_N)

    def level_out(self, view):
        # a non-finite reading: toward level at hover thrust, yaw left alone (zero body rate
        # when the attitude itself is not finite), as hpa::LevelOutCommand
        thrust_N = (self.quad_kg + self.share_kg) * self.g
        w_B = np.zeros(3)
        q = view.q_WB
        if np.all(np.isfinite(q)) and np.linalg.norm(q) > 1e-9:
            z_B_W = quat_to_rot(q)[:, 2]
            axis_W = np.cross(z_B_W, E3)
            if np.linalg.norm(axis_W) > 1e-9:
                tilt = np.arccos(np.clip(z_B_W[2], -1.0, 1.0))
                w_B = LEVEL_GAIN_PER_S * quat_to_rot(q).T @ (axis_W / np.linalg.norm(axis_W) * tilt)
                w_B[2] = 0.0
        return Command(w_B, thrust_N, status="non_finite")


if __name__ == "__main__":
    sys.exit(run_team(TeamVehicle, control_rate_hz=CONTROL_RATE_HZ, name="python team_controller"))
