"""appell.linearize: operating points, A and B, eigenvalues and speed sweeps from Python.

References: the rolling disk's critical speed sqrt(g r / 3) for the uniform disk
(docs/references.md §4, steady upright rolling), the Whipple bicycle's eigenvalues at 5 m/s
(Meijaard et al. 2007, Table 2) and its mass matrix M (their §5: B's speed rows are M^-1 for a
roll torque and a steer torque, exactly), the eigen-equation A x = lambda x, and `appell linearize`'s own
CSV (the same library path: equal to the last digit)."""

import math

import numpy as np
import pytest

import appell
from conftest import SCENES, run_cli

BIKE = SCENES / "bicycle.yaml"
ROLL_STEER = ["rear_frame.tilt", "front_frame.angle", "rear_frame.wx", "front_frame.angle_dot"]
TABLE2_V5 = np.array([-14.07838969279825, -0.77534188219584 + 4.46486771378823j,
                      -0.77534188219584 - 4.46486771378823j, -0.32286642900409])
M_REF = np.array([[80.81722, 2.31941332208709], [2.31941332208709, 0.29784188199686]])


def _match(got, want):
    """Largest distance from each of got to the nearest unused of want."""
    left, worst = list(want), 0.0
    for z in got:
        j = int(np.argmin([abs(z - w) for w in left]))
        worst = max(worst, abs(z - left.pop(j)))
    return worst


def test_disk_critical_speed_by_sweep():
    sw = appell.linearize(SCENES / "rolling_disk.yaml", sweep=np.linspace(0, 5, 101))
    assert sw.eigenvalues.shape == (101, len(sw.subsystem)) and sw.p[-1] == 5
    meetings = [p for p in sw.points if p["kind"] == "meeting"]
    assert len(meetings) == 1 and meetings[0]["rising"]
    assert meetings[0]["p"] == pytest.approx(math.sqrt(9.81 * 0.5 / 3), abs=1e-10)


def test_disk_point_structure():
    lin = appell.linearize(appell.load(SCENES / "rolling_disk.yaml"), speed=3)
    nx = len(lin.state_names)
    assert lin.A.shape == (nx, nx) == lin.A_error.shape and lin.rates.shape == (nx,)
    assert lin.speed == 3 and lin.q.shape == (6,) and lin.v.shape == (5,)
    cyclic = {n for n, c in zip(lin.state_names, lin.cyclic) if c}
    assert cyclic == {"disk.x", "disk.y", "disk.heading", "disk.spin"}
    assert set(lin.subsystem) == set(lin.state_names) - cyclic
    # eigenvectors: A_sub x = lambda x
    for j, lam in enumerate(lin.eigenvalues):
        x = lin.eigenvectors[:, j]
        r = lin.A_sub @ x - lam * x
        assert np.linalg.norm(r) <= 1e-12 * np.linalg.norm(lin.A_sub) * np.linalg.norm(x)
    assert np.all(lin.rcond > 0) and np.all(lin.error > 0)


def test_bicycle_table2_and_mass_matrix():
    lin = appell.linearize(BIKE, speed=5)
    assert list(lin.subsystem) == ROLL_STEER
    assert _match(lin.eigenvalues, TABLE2_V5) <= 1e-11
    assert lin.input_names == ("rear_frame.wx", "front_frame.angle_dot")
    Minv = lin.block(["rear_frame.wx", "front_frame.angle_dot"], matrix="B")
    assert np.max(np.abs(np.linalg.inv(Minv) - M_REF)) <= 1e-12
    cyclic = {n for n, c in zip(lin.state_names, lin.cyclic) if c}
    assert cyclic == {"rear_frame.x", "rear_frame.y", "rear_frame.heading", "rear_wheel.angle",
                      "front_wheel.angle"}


def test_bicycle_sweep_characteristic_speeds():
    sw = appell.linearize(BIKE, sweep=np.linspace(0, 10, 101))
    # Meijaard et al. 2007, Table 2(a); tolerances as tests/test_lin_bicycle.c explains
    want = [("meeting", 0.68428307889246, 1e-12), ("crossing", 4.29238253634111, 1e-12),
            ("crossing", 6.02426201538837, 1e-12)]
    assert len(sw.points) == 3
    for (kind, v, tol), p in zip(want, sorted(sw.points, key=lambda p: p["p"])):
        assert p["kind"] == kind and p["p"] == pytest.approx(v, abs=tol)


def test_equal_to_cli_csv(tmp_path):
    out = tmp_path / "eig.csv"
    run_cli("linearize", BIKE, "--speed", "5", "--csv", out)
    rows = [line.split(",") for line in out.read_text().splitlines()[1:]]
    lin = appell.linearize(BIKE, speed=5)
    assert len(rows) == len(lin.eigenvalues)
    for row, z, rc in zip(rows, lin.eigenvalues, lin.rcond):
        assert (float(row[1]), float(row[2])) == (z.real, z.imag)   # %.17g: exact
        assert row[3] == "%.6g" % rc


def test_overrides_and_errors():
    m = appell.load(BIKE)
    heavy = appell.linearize(m, speed=5, set={"bodies.rear_frame.mass": 90})
    assert _match(heavy.eigenvalues, TABLE2_V5) > 1e-3          # the override took effect
    with pytest.raises(appell.Error, match="no state named 'roll'"):
        appell.linearize(m, speed=5, states=["roll"])
    with pytest.raises(appell.Error, match="'rear_frame.tlt' is not a state variable .*did you "
                       "mean 'rear_frame.tilt'"):
        appell.linearize(m, speed=5, free=["rear_frame.tlt"])
    with pytest.raises(appell.Error, match="linearize.speed"):
        appell.linearize(SCENES / "hoffmann.yaml", speed=1)
    with pytest.raises(ValueError, match="ascending"):
        appell.linearize(m, sweep=[1, 0.5])
    with pytest.raises(ValueError, match="about"):
        appell.linearize(m, about="sideways")
