"""Accuracy on demand from Python and the command line (docs/accuracy.md), against the closed
form of the ball on a turntable (docs/references.md §3: the centre z = x + i y obeys
z' = i kt Omega z + c with kt = 2/7 for a solid ball, c fixed by the initial state)."""

import json

import numpy as np
import pytest

import appell
from conftest import SCENES, run_cli

OMEGA, KT = 2.0, 2.0 / 7.0
SETS = {"output.channels": "[com]", "output.interval": 1.0, "simulation.t_end": 16}


def _exact(t, z0=0.3 + 0j, dz0=0.2j):
    """The centre at times t from z(0) = z0, z'(0) = dz0."""
    w = 1j * KT * OMEGA
    c = dz0 - w * z0
    return (z0 + c / w) * np.exp(w * np.asarray(t)) - c / w


def _true_error(res):
    z = _exact(res["t"])
    return max(np.max(np.abs(res["ball.com.x"] - z.real)),
               np.max(np.abs(res["ball.com.y"] - z.imag)))


@pytest.mark.parametrize("rtol", [1e-4, 1e-6, 1e-8, 1e-10])
def test_estimate_within_factor_3(rtol):
    m = appell.load(SCENES / "turntable_ball.yaml", set=SETS)
    res = appell.Simulation(m, rtol=rtol, atol=rtol, error_estimate=True).run()
    est, true = res.error_estimate["error"], _true_error(res)
    assert est / true < 3 and true / est < 3, (est, true)
    assert res.error_estimate["errors"].shape == res.table.shape


@pytest.mark.parametrize("accuracy", [1e-4, 1e-7])
def test_accuracy_reached(accuracy):
    m = appell.load(SCENES / "turntable_ball.yaml", set=SETS)
    sim = appell.Simulation(m, accuracy=accuracy)
    assert sim.settings["method"] == sim.pick["method"]
    assert sim.settings["rtol"] == sim.pick["rtol"]
    assert _true_error(sim.run()) <= accuracy


def test_cli_estimate_pick_and_control(tmp_path):
    out = tmp_path / "ball.csv"
    sets = [a for k, v in SETS.items() for a in ("--set", f"{k}={v}")]
    r = run_cli("run", SCENES / "turntable_ball.yaml", *sets, "--out", out, "--accuracy",
                "1e-6", "--error-estimate")
    assert "picked" in r.stderr and "estimated global error" in r.stderr
    rec = json.loads((tmp_path / "ball.csv.run.json").read_text())
    acc = rec["accuracy"]
    # only the centre is output: the orientation is left out of the error control
    assert acc["uncontrolled"] == ["ball.qw", "ball.qx", "ball.qy", "ball.qz"]
    assert acc["pick"]["accuracy"] == 1e-6 and rec["settings"]["rtol"] == acc["pick"]["rtol"]
    run = appell.read_run(out)
    true = _true_error(run)
    assert true <= 1e-6
    est = acc["error_estimate"]["error"]
    assert est / true < 3 and true / est < 3, (est, true)
    errors = np.loadtxt(tmp_path / "ball.csv.error.csv", delimiter=",", skiprows=1)
    assert errors.shape == run.table.shape and np.max(errors[:, 1:]) == pytest.approx(est)
    fig = tmp_path / "err.png"
    run_cli("plot", out, "--error", "--y", "ball.com.x", "-o", fig)
    assert fig.stat().st_size > 0
    # every coordinate controlled: more steps, the same error level
    r2 = run_cli("run", SCENES / "turntable_ball.yaml", *sets, "--out", tmp_path / "all.csv",
                 "--method", acc["pick"]["method"], "--rtol", str(acc["pick"]["rtol"]),
                 "--atol", str(acc["pick"]["rtol"]), "--error-control", "all")
    rec2 = json.loads((tmp_path / "all.csv.run.json").read_text())
    assert rec2["accuracy"]["uncontrolled"] == [] and rec2["steps"] > rec["steps"]


def test_no_estimate_removes_old_error_file(tmp_path):
    out = tmp_path / "b.csv"
    sets = [a for k, v in SETS.items() for a in ("--set", f"{k}={v}")]
    run_cli("run", SCENES / "turntable_ball.yaml", *sets, "--out", out, "--error-estimate")
    assert (tmp_path / "b.csv.error.csv").exists()
    run_cli("run", SCENES / "turntable_ball.yaml", *sets, "--out", out)
    assert not (tmp_path / "b.csv.error.csv").exists()
    r = run_cli("plot", out, "--error", "--y", "ball.com.x", "-o", tmp_path / "e.png",
                check=False)
    assert r.returncode == 2 and "--error-estimate" in r.stderr
