"""Every example scene run from Python gives the CSV of `appell run`, to the last digit.

The CLI writes numbers with %.15g; the Python rows are formatted the same way and compared
as text, header included. The scenes are shortened with --t-end like their meson tests; a
few runs also change the mode, the method and the tolerances on both sides."""

import pytest

import appell
from conftest import SCENES, run_cli

CASES = [
    ("rolling_disk", 2, {}),
    ("skate_incline", 2, {}),
    ("chaplygin_sleigh", 5, {}),
    ("turntable_ball", 2, {}),
    ("hoffmann", 2, {}),
    ("rattleback", 2, {}),
    ("heavy_top", 1, {}),
    ("rolling_disk", 1, {"mode": "dae", "rtol": 1e-7, "atol": 1e-9}),
    ("rolling_disk", 1, {"mode": "projected", "method": "verner6"}),
    ("hoffmann", 1, {"mode": "minimal", "method": "bdf", "rtol": 1e-9}),
]


def _fmt(x):
    return "%.15g" % x


@pytest.mark.parametrize("scene,t_end,opts", CASES,
                         ids=[f"{c[0]}-{'-'.join(c[2]) or 'scene'}" for c in CASES])
def test_python_rows_equal_cli_csv(tmp_path, scene, t_end, opts):
    path = SCENES / f"{scene}.yaml"
    out = tmp_path / "cli.csv"
    args = ["run", path, "--t-end", t_end, "--quiet", "--out", out]
    for key, value in opts.items():
        args += [f"--{key}", value]
    run_cli(*args)
    cli = out.read_text().splitlines()
    res = appell.Simulation(appell.load(path), **opts).run(t_end=t_end)
    mine = [",".join(res.columns)] + [",".join(map(_fmt, row)) for row in res.table]
    assert len(mine) == len(cli)
    for i, (a, b) in enumerate(zip(mine, cli)):
        assert a == b, f"row {i} differs:\n  python {a}\n  cli    {b}"
