"""Named output channels in Python (docs/scenes.md "output"): the bicycle's `lean:
rear_frame.roll` and `speed: hypot(rear_frame.vx, rear_frame.vy)` are Result keys, equal to the
roll computed here from the free joint's quaternion (times the child frame's Rx(90 deg)^T) and
to the hypot of the speed columns; an expression given with set= becomes a key too (the rolling
disk's centre height minus r sin(tilt), zero by its geometry)."""

import numpy as np

import appell
from conftest import SCENES


def roll_from_quaternion(qw, qx, qy, qz):
    # R of the joint frame (unit quaternion [w x y z]) times Rx(-90 deg): the body axes
    R = np.array([[1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qw * qz), 2 * (qx * qz + qw * qy)],
                  [2 * (qx * qy + qw * qz), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qw * qx)],
                  [2 * (qx * qz - qw * qy), 2 * (qy * qz + qw * qx), 1 - 2 * (qx * qx + qy * qy)]])
    Rc = np.array([[1, 0, 0], [0, 0, 1], [0, -1, 0]])
    B = R @ Rc
    return np.arctan2(B[2, 1], B[2, 2])


def test_named_channels_are_keys():
    m = appell.load(SCENES / "bicycle.yaml")
    r = appell.Simulation(m).run(t_end=1.0, dt=0.05)
    q = [r["rear_frame." + c] for c in ("qw", "qx", "qy", "qz")]
    want = np.array([roll_from_quaternion(*x) for x in zip(*q)])
    assert np.max(np.abs(r["lean"] - want)) < 1e-12
    assert np.max(np.abs(want)) > 0.05
    assert np.max(np.abs(r["speed"] - np.hypot(r["rear_frame.vx"], r["rear_frame.vy"]))) == 0


def test_channel_from_set():
    m = appell.load(SCENES / "rolling_disk.yaml",
                    set={"output.channels": "[coordinates, {h: disk.z - 0.5*sin(disk.tilt)}]"})
    r = appell.Simulation(m).run(t_end=0.2, dt=0.1)
    # a disk of radius 0.5 on the plane: its centre is 0.5 sin(tilt) high
    assert "h" in r.columns
    assert np.max(np.abs(r["h"])) < 1e-12
