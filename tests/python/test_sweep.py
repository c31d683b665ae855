"""Sweeps: appell.sweep and `appell sweep` give the same table byte for byte; shards merge into
the whole; random values are reproducible and have the asked-for distribution; failed runs are
rows; and a sweep of the rolling disk reproduces the critical speed of upright rolling.

The critical speed comes from the linearized equations of the rolling disk (docs/references.md
§4): upright straight rolling of a uniform disk is stable iff v^2 > g r / 3. The
same linearization gives, above it, the largest lean reached from a small initial lean delta
with no lean rate and no turning: delta (2 / (1 - v_c^2 / v^2) - 1); below it the lean grows
like exp(s t), s^2 = (4/5)(g/r)(1 - v^2/v_c^2)."""

import math

import numpy as np
import pytest

import appell
from conftest import SCENES, run_cli

SHORT = {"simulation.t_end": 1, "simulation.rtol": 1e-8}


def _sweep_args():
    return dict(grid={"initial.disk.tilt": "70*deg:89*deg:3", "bodies.disk.mass": [1, 2.5]},
                random={"initial.disk.spin_rate": "normal(-6,0.5)"}, samples=2, seed=7,
                set=SHORT, channels=["disk.tilt", "energy_error"], times=[0.25, 1])


def _cli_sweep(disk, out, *extra):
    return run_cli("sweep", disk, "--grid", "initial.disk.tilt=70*deg:89*deg:3",
                   "--grid", "bodies.disk.mass=1,2.5", "--random",
                   "initial.disk.spin_rate=normal(-6,0.5)", "--samples", 2, "--seed", 7,
                   "--set", "simulation.t_end=1", "--rtol", "1e-8", "--channel", "disk.tilt",
                   "--channel", "energy_error", "--at", "0.25,1", "--out", out, "--quiet", *extra)


def test_python_and_cli_tables_are_the_same_bytes(tmp_path, disk):
    _cli_sweep(disk, tmp_path / "cli.csv", "--jobs", 2)
    table = appell.sweep(disk, jobs=1, **_sweep_args())
    table.to_csv(tmp_path / "py.csv")
    assert (tmp_path / "py.csv").read_bytes() == (tmp_path / "cli.csv").read_bytes()
    assert len(table["run"]) == table.runs == 12 and np.all(table["status"] == 0)
    # each row is the run `appell run` makes with the same overrides
    i = 5
    sets = [f"{p}={float(table[p][i])!r}" for p in table.paths]
    r = appell.Simulation(appell.load(disk, set=list(sets) + ["simulation.t_end=1",
                                                             "simulation.rtol=1e-8"])).run()
    assert np.array_equal([table[f"{n}@end"][i] for n in r.coordinate_names], r.q[-1])
    assert table["disk.tilt@0.25"][i] == r["disk.tilt"][25]
    assert table["energy_drift"][i] == np.max(np.abs(r["energy_error"]))


def test_threads_do_not_change_the_table(disk):
    a = appell.sweep(disk, jobs=1, **_sweep_args())
    b = appell.sweep(disk, jobs=2, **_sweep_args())
    assert a.columns == b.columns
    for c in a.columns:
        assert np.array_equal(a[c], b[c]) if a[c].dtype != object else list(a[c]) == list(b[c])


def test_shards_merge_into_the_whole(tmp_path, disk):
    _cli_sweep(disk, tmp_path / "all.csv")
    shards = []
    for i in (1, 2, 3):
        shards.append(tmp_path / f"part{i}.csv")
        _cli_sweep(disk, shards[-1], "--shard", f"{i}/3")
    run_cli("sweep", "--merge", "--out", tmp_path / "merged.csv", *reversed(shards))
    assert (tmp_path / "merged.csv").read_bytes() == (tmp_path / "all.csv").read_bytes()
    whole = appell.sweep(disk, **_sweep_args())
    parts = [appell.sweep(disk, shard=(i, 5), **_sweep_args()) for i in range(1, 6)]
    assert np.array_equal(np.concatenate([p["run"] for p in parts]), whole["run"])
    for c in ("disk.x@end", "initial.disk.spin_rate", "disk.tilt@1"):
        assert np.array_equal(np.concatenate([p[c] for p in parts]), whole[c])


def test_merge_refuses_missing_and_duplicate_runs(tmp_path, disk):
    for i in (1, 2):
        _cli_sweep(disk, tmp_path / f"p{i}.csv", "--shard", f"{i}/3")
    r = run_cli("sweep", "--merge", "--out", tmp_path / "m.csv", tmp_path / "p1.csv",
                tmp_path / "p2.csv", check=False)
    assert r.returncode == 2 and "4 of 12 runs are missing: 8..11" in r.stderr
    r = run_cli("sweep", "--merge", "--out", tmp_path / "m.csv", tmp_path / "p1.csv",
                tmp_path / "p1.csv", check=False)
    assert r.returncode == 2 and "run 0 is in" in r.stderr
    assert not (tmp_path / "m.csv").exists()


def test_grid_values_and_expressions(disk):
    t = appell.sweep(disk, grid={"initial.disk.tilt": "70*deg:89*deg:7"}, set=SHORT,
                     final_state=False)
    a, b = appell.constant("70*deg"), appell.constant("89*deg")
    assert a == 70 * (math.pi / 180)
    assert np.array_equal(t["initial.disk.tilt"], np.linspace(a, b, 7))
    w = appell.sweep(disk, grid={"simulation.method": "dopri5,verner6"}, set=SHORT)
    assert list(w["simulation.method"]) == ["dopri5", "verner6"]
    assert w["steps"][0] != w["steps"][1]


def test_random_values_are_reproducible_and_distributed():
    sleigh = SCENES / "chaplygin_sleigh.yaml"
    n = 2000
    args = dict(random={"bodies.sleigh.mass": "normal(1,0.1)",
                        "initial.sleigh.x": "uniform(2,3)"},
                samples=n, seed=11, set={"simulation.t_end": 0.001}, final_state=False, jobs=2)
    a = appell.sweep(sleigh, **args)
    m, x = a["bodies.sleigh.mass"], a["initial.sleigh.x"]
    # sample mean within 4 standard errors; sample deviation within 4 of its standard errors
    assert abs(m.mean() - 1) < 4 * 0.1 / math.sqrt(n)
    assert abs(m.std() - 0.1) < 4 * 0.1 / math.sqrt(2 * n)
    assert x.min() >= 2 and x.max() < 3 and abs(x.mean() - 2.5) < 4 / math.sqrt(12 * n)
    assert abs(np.corrcoef(m, x)[0, 1]) < 4 / math.sqrt(n)
    assert np.array_equal(appell.sweep(sleigh, **args)["bodies.sleigh.mass"], m)
    other = appell.sweep(sleigh, **{**args, "seed": 12})["bodies.sleigh.mass"]
    assert not np.any(other == m)
    part = appell.sweep(sleigh, shard=(3, 4), **args)
    assert np.array_equal(part["bodies.sleigh.mass"], m[part["run"]])


def test_failed_runs_are_rows(disk):
    t = appell.sweep(disk, grid={"bodies.disk.mass": [1, -1, 2],
                                 "simulation.max_steps": [100000, 30]},
                     set={**SHORT, "output.interval": 0.5})   # > 30 steps per interval
    status, msg = t["status"], t["message"]
    assert list(status) == [0, -8, -1, -1, 0, -8]
    assert "rolling_disk.yaml:" in msg[2] and "must be positive" in msg[2]
    assert "the simulation failed at t = " in msg[1]
    assert math.isnan(t["t"][2]) and 0 < t["t"][1] < 1 and t["t"][0] == 1
    assert np.all(np.isfinite([t["disk.x@end"][i] for i in (0, 1, 4, 5)]))
    assert list(t.failed) == [1, 2, 3, 5]


def test_a_bad_path_fails_before_any_run(tmp_path, disk):
    with pytest.raises(appell.SceneError, match="did you mean 'mass'"):
        appell.sweep(disk, grid={"bodies.disk.mas": [1, 2]})
    r = run_cli("sweep", disk, "--grid", "bodies.disk.mas=1,2", "--out", tmp_path / "x.csv",
                check=False)
    assert r.returncode == 2 and "did you mean 'mass'" in r.stderr
    assert not list(tmp_path.iterdir())


def test_bad_jobs_are_refused_as_arguments(disk):
    # jobs=-1 raised SceneError('invalid batch definition'); 2.5 ran on 2 threads.
    for bad in (-1, 2.5, "2"):
        with pytest.raises(ValueError, match="jobs must be a whole number") as info:
            appell.sweep(disk, grid={"bodies.disk.mass": [1, 2]}, set=SHORT, jobs=bad)
        assert not isinstance(info.value, appell.SceneError)


def test_progress_is_reported(disk):
    calls = []
    appell.sweep(disk, grid={"initial.disk.tilt": "60*deg:89*deg:8"}, set=SHORT,
                 progress=lambda done, total: calls.append((done, total)))
    assert calls and calls[-1] == (8, 8)


def test_critical_speed_of_upright_rolling(disk):
    g, r = 9.81, 0.5                       # the scene's gravity and radius
    v_c = math.sqrt(g * r / 3)             # docs/references.md §4: stable iff v^2 > g r / 3
    ratios = [0.5, 0.8, 0.9, 0.95, 0.98, 1.02, 1.05, 1.1, 1.2, 1.5, 2.0]
    leans = [0.01, 0.05]                   # initial lean from upright, degrees
    t_end, dt = 10.0, 0.05
    times = [i * dt for i in range(int(t_end / dt) + 1)]
    t = appell.sweep(
        disk, grid={"initial.disk.tilt": [f"{90 - d!r}*deg" for d in leans],
                    "initial.disk.spin_rate": [-f * v_c / r for f in ratios]},
        set={"initial.disk.heading_rate": 0, "simulation.t_end": t_end,
             "simulation.rtol": 1e-8, "simulation.atol": 1e-10},
        channels=["disk.tilt"], times=times, jobs=2)
    assert np.all(t["status"] == 0)
    tilt = np.stack([t[f"disk.tilt@{x:.10g}"] for x in times], axis=1)
    lean = np.degrees(np.max(np.abs(tilt - math.pi / 2), axis=1))
    for i in range(len(t["run"])):
        delta = 90 - math.degrees(t["initial.disk.tilt"][i])
        f = -t["initial.disk.spin_rate"][i] * r / v_c
        if f < 1:      # unstable: the lean grows by orders of magnitude within 10 s
            assert lean[i] / delta > 200, (f, delta, lean[i])
        else:          # stable: bounded, the amplitude of the linearized motion
            bound = 2 / (1 - 1 / f ** 2) - 1
            assert lean[i] / delta == pytest.approx(bound, rel=0.05), (f, delta, lean[i])


def _mass_sweep(disk, out, grid, *extra):
    return run_cli("sweep", disk, "--grid", f"bodies.disk.mass={grid}", "--set",
                   "simulation.t_end=0.2", "--quiet", "--out", out, *extra, check=False)


def test_merge_refuses_shards_of_another_sweep(tmp_path, disk):
    # Two plans of the same size (1:2:8 and 5:6:8) merged silently before the plan column.
    _mass_sweep(disk, tmp_path / "a.csv", "1:2:8", "--shard", "1/2")
    _mass_sweep(disk, tmp_path / "b.csv", "5:6:8", "--shard", "2/2")
    _mass_sweep(disk, tmp_path / "c.csv", "1:2:8", "--shard", "2/2", "--rtol", "1e-9")
    _mass_sweep(disk, tmp_path / "d.csv", "1.0:2:8", "--shard", "2/2")
    for other in ("b.csv", "c.csv"):
        r = run_cli("sweep", "--merge", "--out", tmp_path / "m.csv", tmp_path / "a.csv",
                    tmp_path / other, check=False)
        assert r.returncode == 2, r.stderr
        assert f"{other}:2: plan " in r.stderr and "shards of different sweeps" in r.stderr
    assert not (tmp_path / "m.csv").exists()
    # the same plan written otherwise (1.0 for 1) is the same sweep
    run_cli("sweep", "--merge", "--out", tmp_path / "m.csv", tmp_path / "a.csv",
            tmp_path / "d.csv")
    ids = {line.split(",")[2] for line in (tmp_path / "m.csv").read_text().splitlines()[1:]}
    assert len(ids) == 1 and len(ids.pop()) == 16


def test_merge_parses_every_row(tmp_path, disk):
    _mass_sweep(disk, tmp_path / "a.csv", "1:2:4", "--shard", "1/2")
    _mass_sweep(disk, tmp_path / "b.csv", "1:2:4", "--shard", "2/2")
    good = (tmp_path / "b.csv").read_text().splitlines(keepends=True)
    n = len(good[0].split(","))
    cases = {  # how row 3 of b.csv is spoilt -> what the message names
        "extra": (lambda r: r[:-1] + ",7\n", f"b.csv:3: {n + 1} fields, but the header has {n}"),
        "missing": (lambda r: r.rsplit(",", 2)[0] + "\n", f"b.csv:3: {n - 2} fields"),
        "garbage": (lambda r: r.replace(",0,", ",zero,", 1), "b.csv:3: column status"),
        "number": (lambda r: ",".join(r.split(",")[:8] + ["1.5x"] + r.split(",")[9:]),  # steps
                   "b.csv:3: column steps: '1.5x' is not a number"),
        "quote": (lambda r: r[:-2] + 'x"y"\n', f"b.csv:3: field {n}: a malformed field"),
        "plan": (lambda r: r.replace(r.split(",")[2], "0123456789abcdeg"),
                 "b.csv:3: column plan"),
        "empty": (lambda r: "\n", "b.csv:3: column run"),
        "huge": (lambda r: "99999999999999999999" + r[r.index(","):],   # fuzz_merge's finding
                 "b.csv:3: column run: '99999999999999999999' is not a whole number"),
    }
    for what, (spoil, says) in cases.items():
        (tmp_path / "b.csv").write_text("".join(good[:2] + [spoil(good[2])] + good[3:]))
        r = run_cli("sweep", "--merge", "--out", tmp_path / "m.csv", tmp_path / "a.csv",
                    tmp_path / "b.csv", check=False)
        assert r.returncode == 2 and says in r.stderr, (what, r.stderr)
        assert not (tmp_path / "m.csv").exists()
    (tmp_path / "b.csv").write_text("".join(good))
    run_cli("sweep", "--merge", "--out", tmp_path / "m.csv", tmp_path / "a.csv",
            tmp_path / "b.csv")
