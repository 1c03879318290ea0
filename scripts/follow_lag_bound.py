#!/usr/bin/python3
"""How late a quadrotor may follow a moved payload and still see it in its downward camera.

A vehicle that copies the hand's minimum-jerk move delayed by tau is tilted atan(a / g) toward its
acceleration; the payload, e = y_L(t) - y_Q(t) aside and h below the camera, is then
atan(e / h) + tilt off the optical axis (accelerating toward the payload turns the camera away
from it). Prints the worst angle over the move for a range of delays, against the camera's
half-angle across y (docs/results.md, "Person moves the payload (VI-C)").

Usage: scripts/follow_lag_bound.py [--distance-m 0.3] [--depth-m 0.25] [--half-angle-deg 37.5]
"""
import argparse
import math

GRAVITY_MPS2 = 9.81


def min_jerk(distance_m, duration_s, t_s):
    """Position and acceleration of a minimum-jerk move of distance_m over duration_s at t_s."""
    s = min(max(t_s / duration_s, 0.0), 1.0)
    p_m = distance_m * (10 * s**3 - 15 * s**4 + 6 * s**5)
    a_mps2 = 0.0 if s in (0.0, 1.0) else distance_m / duration_s**2 * (60 * s - 180 * s**2 + 120 * s**3)
    return p_m, a_mps2


def worst_angle_deg(distance_m, duration_s, delay_s, depth_m, samples=3000):
    """Largest angle off the optical axis over the move for a follower delay_s late."""
    worst = 0.0
    for i in range(samples + 1):
        t_s = -0.5 + (duration_s + 1.0) * i / samples
        y_payload_m, _ = min_jerk(distance_m, duration_s, t_s)
        y_quad_m, a_quad_mps2 = min_jerk(distance_m, duration_s, t_s - delay_s)
        tilt_deg = math.degrees(math.atan(a_quad_mps2 / GRAVITY_MPS2))
        angle_deg = math.degrees(math.atan((y_payload_m - y_quad_m) / depth_m)) + tilt_deg
        worst = max(worst, abs(angle_deg))
    return worst


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--distance-m", type=float, default=0.3)
    parser.add_argument("--depth-m", type=float, default=0.25)
    parser.add_argument("--half-angle-deg", type=float, default=37.5)
    args = parser.parse_args()
    for duration_s in (1.5, 0.75):
        for delay_s in (0.0, 0.05, 0.1, 0.15, 0.2, 0.25, 0.3):
            worst = worst_angle_deg(args.distance_m, duration_s, delay_s, args.depth_m)
            print(f"move {args.distance_m} m in {duration_s} s, delay {delay_s:.2f} s: worst "
                  f"{worst:5.1f} deg off the axis (half-angle {args.half_angle_deg})")


if __name__ == "__main__":
    main()
