"""A differential-drive robot following a path with a pure-pursuit controller in the loop.

    python3 examples/python/diff_drive_pursuit.py [--t-end 30] [--period 0.01]

The path is the wavy road y = A sin(x / lam) (A = 0.5 m, lam = 2 m); the robot
(examples/scenes/diff_drive_servo.yaml, wheel radius r = 0.1 m, track b = 0.5 m) starts
0.3 m off it. Its inputs are the set-points of the two wheel motors (rate motors, torque
kd (set-point - rate)). Every period (10 ms) the controller reads the measured pose (chassis.x,
.y, .heading), and
  1. pure pursuit: the goal is the first path point ahead at the look-ahead distance L from the
     axle midpoint; the arc through it has curvature kappa = 2 sin(alpha) / L (alpha: the
     goal's bearing from the heading), so the wanted turn rate is omega = v kappa at speed v;
  2. the wheel rates that give (v, omega): w_r,l = (v +- omega b / 2) / r;
  3. commands those rates as the motors' set-points, held 10 ms (each motor then drives its
     wheel towards its set-point continuously).
The cross-track error (distance from the axle midpoint to the path) falls from 0.3 m within a
few seconds and then stays near a millimetre: pure pursuit follows a circle exactly in steady
state, and what is left comes from the road's changing curvature and the motors' lag."""

import argparse
import math
from pathlib import Path

import numpy as np

import appell

AMP, LAM = 0.5, 2.0                     # the path y = AMP sin(x / LAM), m
R_WHEEL, TRACK = 0.1, 0.5               # m
SPEED, LOOKAHEAD = 0.5, 0.4             # m/s, m


def path_points(x_end=40.0, ds=0.002):
    x = np.arange(-2.0, x_end, ds)
    return np.column_stack([x, AMP * np.sin(x / LAM)])


def cross_track(P, x, y):
    """Distance from (x, y) to the sampled path P (m)."""
    return float(np.min(np.hypot(P[:, 0] - x, P[:, 1] - y)))


def pure_pursuit(P):
    """The controller f(t, state) -> the two wheel-rate set-points (a dict by input name)."""
    def f(t, s):
        x, y, h = s["chassis.x"], s["chassis.y"], s["chassis.heading"]
        d = np.hypot(P[:, 0] - x, P[:, 1] - y)
        i = int(np.argmin(d))
        ahead = np.nonzero(d[i:] >= LOOKAHEAD)[0]
        gx, gy = P[i + ahead[0]] if ahead.size else P[-1]
        alpha = math.atan2(gy - y, gx - x) - h
        omega = SPEED * 2.0 * math.sin(alpha) / LOOKAHEAD
        w_l = (SPEED - omega * TRACK / 2) / R_WHEEL
        w_r = (SPEED + omega * TRACK / 2) / R_WHEEL
        return {"motor_l.setpoint": w_l, "motor_r.setpoint": w_r}
    return f


def run(scene, t_end=30.0, period=0.01):
    P = path_points()
    sim = appell.Simulation(appell.load(scene))
    res = sim.run(t_end, 0.05, controller=pure_pursuit(P), period=period)
    err = np.array([cross_track(P, x, y) for x, y in zip(res["chassis.x"], res["chassis.y"])])
    return res, err


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--scene", default=str(Path(__file__).resolve().parents[1] / "scenes" /
                                          "diff_drive_servo.yaml"))
    p.add_argument("--t-end", type=float, default=30.0)
    p.add_argument("--period", type=float, default=0.01)
    a = p.parse_args()
    res, err = run(a.scene, a.t_end, a.period)
    t = res.t
    print(f"cross-track error: {err[0]:.3f} m at t = 0, largest after 10 s "
          f"{err[t >= 10].max():.4f} m, at {t[-1]:.0f} s {err[-1]:.4f} m; "
          f"travelled to x = {res['chassis.x'][-1]:.2f} m")


if __name__ == "__main__":
    main()
