"""The Python API: loading, names, settings, runs, errors with status and location, threads.

References: the scene files and their fixtures (tests/scenes, the positions test_scene.c
checks in C), the command-line tool's own output (appell check, the CSV header), the energy
invariant of the rolling disk (docs/references.md §4, the rolling disk: rolling without
slip does no work), and serial runs for the threaded ones."""

import signal
import threading
import time

import numpy as np
import pytest

import appell
from conftest import BAD, SCENES, run_cli


def test_model_names_and_settings(disk):
    m = appell.load(disk)
    assert (m.name, m.n, m.k, m.b) == ("rolling_disk", 6, 5, 2)
    assert m.coordinate_names == ("disk.x", "disk.y", "disk.qw", "disk.qx", "disk.qy", "disk.qz")
    assert m.speed_names == ("disk.vx", "disk.vy", "disk.wx", "disk.wy", "disk.wz")
    assert m.constraint_names == ("roll.x", "roll.y")
    header = run_cli("run", disk, "--t-end", "0.01", "--quiet").stdout.splitlines()[0]
    assert ",".join(m.channel_names) == header
    s = m.settings
    assert (s["mode"], s["method"], s["rtol"], s["atol"], s["t_end"], s["interval"]) == \
        ("minimal", "dopri5", 1e-9, 1e-11, 15.0, 0.01)
    assert m.bodies == {"disk": "disk"} and m.constraints == {"roll": "rolling"}
    assert m.conserves_energy


def test_overrides_and_loads(disk):
    text = disk.read_text()
    a = appell.load(disk, set={"bodies.disk.mass": 2.5, "simulation.rtol": 1e-7})
    b = appell.loads(text, name="disk.yaml", set=["bodies.disk.mass=2.5", "simulation.rtol=1e-7"])
    assert a.settings["rtol"] == 1e-7 == b.settings["rtol"]
    ra = appell.Simulation(a).run(t_end=0.5)
    rb = appell.Simulation(b).run(t_end=0.5)
    assert np.array_equal(ra.table, rb.table)
    # mass enters the energy linearly: E(m = 2.5) = 2.5 E(m = 1)
    r1 = appell.Simulation(appell.load(disk)).run(t_end=0)
    assert ra["energy"][0] == pytest.approx(2.5 * r1["energy"][0], rel=1e-14)


def test_initial_state(disk):
    q0, v0, report = appell.load(disk).initial_state()
    assert q0.shape == (6,) and v0.shape == (5,)
    assert np.linalg.norm(q0[2:]) == pytest.approx(1.0, abs=1e-15)   # a unit quaternion
    assert isinstance(report, str)


def test_run_arrays_and_energy(disk):
    m = appell.load(disk)
    sim = appell.Simulation(m, rtol=1e-10, atol=1e-12)
    res = sim.run(t_end=4, dt=0.05)
    assert len(res) == 81 and res.t[0] == 0 and res.t[-1] == 4
    assert res.q.shape == (81, 6) and res.v.shape == (81, 5)
    assert np.array_equal(res["disk.x"], res.q[:, 0]) and np.array_equal(res["disk.wz"], res.v[:, 4])
    t, q, v = sim.state
    assert t == 4 and np.array_equal(q, res.q[-1]) and np.array_equal(v, res.v[-1])
    # Rolling without slip conserves energy: the error is a few hundred rtol of E at most.
    E0 = res["energy"][0]
    assert np.max(np.abs(res["energy_error"])) < 100 * 1e-10 * E0
    assert np.max(res["residual"]) < 1e-12
    more = sim.run(t_end=5, dt=0.25)   # continues from t = 4; energy_error still from t = 0
    assert more.t[0] == 4 and more.t[-1] == 5
    assert np.max(np.abs(more["energy_error"])) < 100 * 1e-10 * E0
    st = sim.stats
    assert st["steps"] > 0 and st["rhs_evals"] > st["steps"] and st["max_residual"] < 1e-12


def test_settings_override_the_scene(disk):
    """Simulation(mode=, method=, rtol=) runs exactly as the scene with those settings."""
    m = appell.load(disk)
    tables = []
    for mode, method in (("projected", "verner6"), ("dae", "dopri5"), ("minimal", "bdf")):
        sim = appell.Simulation(m, mode=mode, method=method, rtol=1e-8, atol=1e-10)
        assert sim.settings["mode"] == mode and sim.settings["rtol"] == 1e-8
        res = sim.run(t_end=0.3)
        same = appell.load(disk, set={"simulation.mode": mode, "simulation.method": method,
                                      "simulation.rtol": 1e-8, "simulation.atol": 1e-10})
        assert np.array_equal(res.table, appell.Simulation(same).run(t_end=0.3).table)
        tables.append(res.table)
    assert not np.array_equal(tables[0], tables[1]) and not np.array_equal(tables[1], tables[2])


# Fixtures of tests/scenes and the location test_scene.c expects for each.
BAD_SCENES = [
    ("unknown_key.yaml", 3, 5, "did you mean 'mass'?"),
    ("negative_mass.yaml", 3, 11, "must be positive"),
    ("missing_body.yaml", 8, 31, "no body named 'dsik'"),
    ("bad_expression.yaml", 12, 35, "cannot parse"),
    ("inertia_not_pd.yaml", 4, 14, "not positive definite"),
    ("malformed.yaml", 3, 1, "malformed YAML"),
]


@pytest.mark.parametrize("name,line,column,phrase", BAD_SCENES)
def test_bad_scene_raises_with_location(name, line, column, phrase):
    with pytest.raises(appell.SceneError) as info:
        appell.load(BAD / name)
    e = info.value
    assert (e.line, e.column) == (line, column)
    assert e.filename.endswith(name) and phrase in e.message
    assert str(e).startswith(f"{e.filename}:{line}:{column}: ")
    assert e.status == -1 and e.reason == "invalid argument or definition"
    assert isinstance(e, appell.Error) and isinstance(e, ValueError)


def test_bad_override_and_missing_file(disk):
    with pytest.raises(appell.SceneError, match="did you mean 'mass'") as info:
        appell.load(disk, set={"bodies.disk.mas": 2})
    assert info.value.status == -1
    with pytest.raises(FileNotFoundError):
        appell.load(SCENES / "no_such_scene.yaml")


def test_run_failure_raises_with_status_and_partial_rows(disk):
    sim = appell.Simulation(appell.load(disk), max_steps=20)
    with pytest.raises(appell.Error) as info:
        sim.run(t_end=5, dt=0.5)
    e = info.value
    assert e.status == -8 and "the simulation failed at t = " in e.message
    assert not isinstance(e, appell.SceneError)
    assert 1 <= len(e.result) < 11 and e.result.t[-1] <= sim.t < 5


def test_bad_arguments(disk):
    m = appell.load(disk)
    with pytest.raises(ValueError, match="mode"):
        appell.Simulation(m, mode="fast")
    with pytest.raises(ValueError, match="unknown method"):
        appell.Simulation(m, method="euler")
    with pytest.raises(ValueError, match="q0 must have 6"):
        appell.Simulation(m, q0=[0, 0, 1])
    with pytest.raises(ValueError, match="rtol"):
        appell.Simulation(m, rtol=-1)
    sim = appell.Simulation(m)
    sim.advance(0.1)
    with pytest.raises(ValueError, match="t_end"):
        sim.run(t_end=0.05)
    with pytest.raises(appell.Error, match="cannot parse"):
        appell.constant("70*")
    assert appell.constant("70*deg") == pytest.approx(70 * np.pi / 180, rel=1e-15)
    assert {"dopri5", "verner6", "bdf"} <= {x["name"] for x in appell.methods()}


def test_argument_errors_name_the_numbers(disk):
    # PyErr_Format has no %g: the messages once read "the current time %.17g".
    sim = appell.Simulation(appell.load(disk))
    sim.advance(0.25)
    with pytest.raises(ValueError) as info:
        sim.run(t_end=0.125, dt=0.5)
    assert "%" not in str(info.value)
    assert "time 0.25 " in str(info.value) and "t_end = 0.125," in str(info.value)
    with pytest.raises(ValueError) as info:
        sim.advance(float("nan"))
    assert "%" not in str(info.value) and "time 0.25 " in str(info.value)


def test_max_steps_must_be_a_whole_number(disk):
    # 2.5 was truncated to 2, and 1e30 cast to long (undefined; LONG_MIN here), which the
    # library then refused with a message about switch_growth.
    m = appell.load(disk)
    for bad in (2.5, 1e30, 0):
        with pytest.raises(ValueError, match="max_steps must be a whole number"):
            appell.Simulation(m, max_steps=bad)
    assert appell.Simulation(m, max_steps=1e6).settings["max_steps"] == 1000000


def test_an_interval_past_t_end_ends_at_t_end(disk):
    # dt more than 1e9 times t_end - t0 once gave the row at t0 only, without integrating.
    m = appell.load(disk)
    sim = appell.Simulation(m)
    res = sim.run(t_end=0.5, dt=1e9)
    assert list(res.t) == [0.0, 0.5] and sim.t == 0.5
    one = appell.Simulation(m).run(t_end=0.5, dt=0.5)   # the same single advance to 0.5
    assert np.array_equal(res.table, one.table)


def test_inconsistent_initial_speeds_are_refused(disk):
    m = appell.load(disk)
    q0, v0, _ = m.initial_state()
    v_bad = v0.copy()
    v_bad[0] += 1.0   # the centre slides 1 m/s: far off A v + a0 = 0
    with pytest.raises(appell.Error) as info:
        appell.Simulation(m, v0=v_bad)
    assert info.value.status == -6   # AP_ERR_INCONSISTENT


def _runs(model, configs):
    return [appell.Simulation(model, mode=mode, method=method).run(t_end=1).table
            for mode, method in configs]


def test_threads_share_a_model_and_equal_serial_runs(disk):
    m = appell.load(disk)
    configs = [("minimal", "dopri5"), ("projected", "verner6"), ("dae", "dopri5"),
               ("minimal", "bdf")]
    serial = _runs(m, configs)
    out = [None] * len(configs)

    def work(i):
        out[i] = _runs(m, [configs[i]])[0]

    threads = [threading.Thread(target=work, args=(i,)) for i in range(len(configs))]
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    for a, b in zip(serial, out):
        assert np.array_equal(a, b)


def test_gil_is_released_while_integrating(disk):
    """While one thread integrates, the main thread keeps running Python code."""
    sim = appell.Simulation(appell.load(disk), rtol=1e-12, atol=1e-14)
    span = {}

    def work():
        span["start"] = time.perf_counter()
        sim.run(t_end=80, dt=1.0)
        span["end"] = time.perf_counter()

    th = threading.Thread(target=work)
    stamps = []
    th.start()
    while th.is_alive():
        stamps.append(time.perf_counter())
    th.join()
    inside = [s for s in stamps if span["start"] + 0.02 < s < span["end"] - 0.02]
    assert span["end"] - span["start"] > 0.1   # the run is long enough to tell
    assert len(inside) > 1000                  # held GIL: none at all


def test_a_signal_stops_a_long_output_interval(disk):
    """Python's signal handlers run while C integrates one long interval (Ctrl-C works)."""
    sim = appell.Simulation(appell.load(disk), rtol=1e-12, atol=1e-14)

    class Stop(Exception):
        pass

    def handler(sig, frame):
        raise Stop

    old = signal.signal(signal.SIGALRM, handler)
    signal.setitimer(signal.ITIMER_REAL, 0.3)
    start = time.perf_counter()
    try:
        with pytest.raises(Stop):
            sim.run(t_end=1e6, dt=1e6)   # one interval: minutes of integration
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)
    assert time.perf_counter() - start < 5
    t = sim.t
    assert 0 < t < 1e6                   # stopped where it was, and goes on from there
    sim.advance(t + 0.1)
    assert sim.t == t + 0.1


def test_absurd_row_counts_are_refused(disk):
    # dt = 1e-300 cast ceil(T / dt) = Inf to long (undefined behaviour), and dt = 1e-7 over 10 s
    # asked NumPy for 10^8 rows (gigabytes) before integrating a step. The limit is the scene
    # loader's, 10^7 output rows, as for appell run.
    sim = appell.Simulation(appell.load(disk))
    for t_end, dt, rows in ((1.0, 1e-300, r"1e\+300 rows"), (10.0, 1e-7, r"1e\+08 rows")):
        with pytest.raises(ValueError, match="would record " + rows) as info:
            sim.run(t_end=t_end, dt=dt)
        assert "10^7" in str(info.value) and sim.t == 0.0
    assert len(sim.run(t_end=0.01, dt=1e-3).t) == 11



FALL = """
name: fall
bodies:
  slider: {mass: 1, inertia: [0.1, 0.1, 0.1]}
joints:
  slider: {kind: prismatic, axis: z}
effects:
  gravity: {kind: gravity}
initial:
  slider: {position: 0.5, rate: 2.0}
simulation: {t_end: 1, rtol: 1e-10, atol: 1e-12}
output: {interval: 0.5, channels: [coordinates, speeds]}
"""


def test_state_read_from_another_thread_during_a_run_is_one_step():
    """While run() integrates (GIL released), another thread reading state, t, stats and
    warning gets a consistent snapshot: t, q and v of one step. Reference: the closed form of
    a slider falling under gravity, z = z0 + v0 t - g t^2 / 2 and v = v0 - g t, which dopri5
    integrates to round-off (a quadratic); a q or v of another step than t would be off by
    g h_max = 2e-4 or more (h_max = 2e-5). The runs go on for at least 0.6 s of wall time, so
    that several snapshots (one every 0.2 s) are read on any machine."""
    z0, v0, g = 0.5, 2.0, 9.81
    sim = appell.Simulation(appell.loads(FALL), h_max=2e-5)
    done = threading.Event()
    reads = []

    def work():
        start = time.perf_counter()
        try:
            while time.perf_counter() - start < 0.6:
                sim.run(t_end=sim.t + 0.5, dt=0.5)
        finally:
            done.set()

    th = threading.Thread(target=work)
    th.start()
    while not done.is_set():
        t, q, v = sim.state
        reads.append((t, q[0], v[0], sim.t, sim.stats["steps"], sim.warning))
    th.join()
    t_end = sim.t
    assert len(reads) > 100 and len({r[0] for r in reads}) >= 3     # the runs were watched
    steps = [r[4] for r in reads]
    assert steps == sorted(steps)                                   # stats move forward
    for t, z, v, t_alone, _, warning in reads:
        z_ref = z0 + v0 * t - 0.5 * g * t * t
        assert abs(z - z_ref) < 1e-9 * max(1.0, abs(z_ref))         # q of the step at t
        assert abs(v - (v0 - g * t)) < 1e-9 * max(1.0, g * t)       # v of the same step
        assert 0 <= t <= t_alone <= t_end and warning == ""
    t, q, v = sim.state                                             # after the runs: live
    z_ref = z0 + v0 * t_end - 0.5 * g * t_end**2
    assert t == t_end and abs(q[0] - z_ref) < 1e-9 * max(1.0, abs(z_ref))


def test_parameters_dict_and_override():
    """model.parameters (docs/scenes.md "Parameters"): Meijaard's Table 1 names of the bicycle
    scene; set= changes one and every value derived from it (the run moves); a parameter the
    scene does not have is refused with its name."""
    base = appell.load(SCENES / "bicycle.yaml")
    p = base.parameters
    assert p["w"] == 1.02 and p["c"] == 0.08 and p["lambda"] == np.pi / 10 and len(p) == 26
    moved = appell.load(SCENES / "bicycle.yaml", set={"parameters.c": 0.1})
    assert moved.parameters["c"] == 0.1 and moved.parameters["w"] == 1.02
    r0 = appell.Simulation(base).run(t_end=0.5, dt=0.5)
    r1 = appell.Simulation(moved).run(t_end=0.5, dt=0.5)
    assert abs(r0["rear_frame.wx"][-1] - r1["rear_frame.wx"][-1]) > 1e-4
    assert appell.load(SCENES / "rolling_disk.yaml").parameters == {}
    with pytest.raises(appell.SceneError, match="no parameter 'cc' .did you mean 'c'"):
        appell.load(SCENES / "bicycle.yaml", set={"parameters.cc": 0.1})


def test_parameters_sweep_grid_random_and_linearize(tmp_path):
    """A parameter is a sweep path like any other (--grid, --random), and appell linearize
    --sweep takes its bare name: the bicycle's trail c."""
    out = tmp_path / "trail.csv"
    run_cli("sweep", SCENES / "bicycle.yaml", "--grid", "parameters.c=0.06:0.1:3", "--random",
            "parameters.w=uniform(1,1.05)", "--samples", "2", "--t-end", "0.2", "--out", out)
    rows = out.read_text().splitlines()
    head = rows[0].split(",")
    ic, iw = head.index("parameters.c"), head.index("parameters.w")
    cs = sorted({float(r.split(",")[ic]) for r in rows[1:]})
    ws = [float(r.split(",")[iw]) for r in rows[1:]]
    assert len(rows) == 7 and cs == [0.06, 0.08, 0.1] and all(1 <= w <= 1.05 for w in ws)
    r = run_cli("linearize", SCENES / "bicycle.yaml", "--sweep", "c=0.05:0.15:3")
    assert "sweep        parameters.c from 0.05 to 0.15, 3 values" in r.stdout
