"""Hostile and wrong calls of the Python package: each is refused with the exception and
message a user can act on, within the limits the command-line tool keeps. Calls that could
take the interpreter down (huge reads, a crash) run in a child interpreter."""

import os
import subprocess
import sys
import textwrap

import pytest

import appell
from conftest import EXE, SCENES, run_cli

LIMIT = "larger than 16 MiB: not a scene file"


def child(code, timeout=60):
    """Runs code in a fresh interpreter with the package; returns the CompletedProcess."""
    prelude = "import resource, sys, appell\n"
    return subprocess.run([sys.executable, "-c", prelude + textwrap.dedent(code)],
                          capture_output=True, text=True, timeout=timeout, env=os.environ)


def peak_mib():
    return "resource.getrusage(resource.RUSAGE_SELF).ru_maxrss // 1024"


def test_load_keeps_the_cli_limits(tmp_path):
    # appell.load("/dev/zero") took 2 GiB before; a 100 MB scene loaded where the CLI refuses.
    big = tmp_path / "big.yaml"
    with open(big, "wb") as f:
        f.write(b"# " + b"x" * (16 << 20) + b"\n")
    cli = run_cli("check", big, check=False)
    assert cli.returncode == 2 and f"{big}: {LIMIT}" in cli.stderr
    for path in ("/dev/zero", str(big), str(tmp_path)):
        r = child(f"""
            try:
                appell.load({path!r})
            except appell.SceneError as e:
                print(type(e).__name__, e.status, e, {peak_mib()})
            """)
        assert r.returncode == 0, r.stderr
        name, status, *msg, peak = r.stdout.split()
        assert name == "SceneError" and status == "-1"
        why = "is a directory, not a scene file" if path == str(tmp_path) else LIMIT
        assert " ".join(msg) == f"{path}: {why}"
        assert int(peak) < 200, f"{path}: {peak} MiB"


def test_loads_keeps_the_cli_limit():
    r = child(f"""
        for text in ("x" * ((16 << 20) + 1), b"x" * ((16 << 20) + 1), "é" * (9 << 20)):
            try:
                appell.loads(text, name="mem.yaml")
            except appell.SceneError as e:
                print(e)
        print({peak_mib()})
        """)
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert lines[:3] == [f"mem.yaml: {LIMIT}"] * 3
    assert int(lines[3]) < 400


def test_load_releases_the_gil_while_reading(tmp_path):
    # a FIFO with no writer blocks the reader; another thread must still run Python code
    fifo = tmp_path / "scene.fifo"
    os.mkfifo(fifo)
    r = child(f"""
        import threading, time
        t = threading.Thread(target=lambda: appell.load({str(fifo)!r}), daemon=True)
        t.start()
        time.sleep(0.2)
        n = 0
        end = time.monotonic() + 0.3
        while time.monotonic() < end:
            n += 1
        print(n)
        open({str(fifo)!r}, "w").close()   # let the reader finish
        t.join(5)
        """)
    assert r.returncode == 0, r.stderr
    assert int(r.stdout.split()[0]) > 1000


STATE_FAIL = """name: motor
bodies:
  fly: {mass: 1, inertia: [0.03, 0.03, 0.05]}
joints:
  fly: {kind: revolute, axis: z}
effects:
  hold: {kind: motor, joint: fly, rate: "fly.angle^0.5", kd: 0.01}
initial:
  fly: {angle: 1, rate: -3}
simulation: {t_end: 1}
output: {interval: 0.5}
"""

POLE = """name: pole
bodies:
  arm: {mass: 1, inertia: [0.03, 0.03, 0.05]}
  fly: {mass: 1, inertia: [0.03, 0.03, 0.05]}
joints:
  arm: {kind: revolute, axis: z, drive: {angle: "1/(1.5 - t)"}}
  fly: {kind: revolute, parent: arm, axis: x}
initial:
  fly: {rate: 1}
simulation: {t_end: 2, max_steps: 20000}
output: {interval: 0.5}
"""


@pytest.mark.parametrize("how", [("--method", "dopri5"), ("--method", "bdf"),
                                 ("--method", "adams"), ("--mode", "dae")])
def test_a_state_expression_failing_mid_run_is_located(tmp_path, how):
    # exit 3 with no file:line:column and a hint blaming the motor's gains before
    scene = tmp_path / "motor.yaml"
    scene.write_text(STATE_FAIL)
    where = f"{scene}:7:41: effects.hold.rate: 'fly.angle^0.5' is not finite at t = "
    r = run_cli("run", scene, *how, "--quiet", "-o", tmp_path / "out.csv", check=False)
    assert r.returncode == 3 and where in r.stderr and "^ 0.5 = nan" in r.stderr, r.stderr
    assert "large gains" not in r.stderr
    m = appell.load(scene, set=[f"simulation.{how[0][2:]}={how[1]}"])
    with pytest.raises(appell.SceneError) as info:
        appell.Simulation(m).run()
    e = info.value
    assert (e.line, e.column) == (7, 41) and str(e).startswith(where)
    assert e.status == -4 and "the simulation failed at t = " in str(e)
    t = appell.sweep(scene, grid={"bodies.fly.mass": [1, 2]},
                     set={f"simulation.{how[0][2:]}": how[1]})
    assert list(t["status"]) == [-4, -4] and t["message"][0].startswith(where)


def test_a_drive_with_a_pole_is_located_not_blamed_on_max_steps(tmp_path):
    # bdf reported 'raise max_steps' after 10^6 steps, with nothing about the drive
    scene = tmp_path / "pole.yaml"
    scene.write_text(POLE)
    for method in ("bdf", "dopri5"):
        r = run_cli("run", scene, "--method", method, "--quiet", "-o", tmp_path / "o.csv",
                    check=False)
        assert r.returncode == 3, r.stderr
        assert "step size that kept shrinking" in r.stderr and "raise max_steps" not in r.stderr
        assert "check them before raising max_steps" in r.stderr
        assert (f"{scene}:6:49: joints.arm.drive.angle: '1/(1.5 - t)' is not finite at t = 1.5: "
                "1 / 0 = inf") in r.stderr


def test_sweep_options_refused_up_front_with_their_limits(tmp_path, disk):
    out = tmp_path / "x.csv"
    mass = ("--grid", "bodies.disk.mass=1,2")
    cases = [  # arguments -> the message (each was accepted or said "out of memory")
        (("--random", "bodies.disk.mass=uniform(1,2)", "--samples", "1e12"),
         "--samples 1e12: at most 10^9 random samples per grid point"),
        (mass + ("--channel", "disk.tilx"),
         "--channel 'disk.tilx': no output column of that name in the scene (did you mean "
         "'disk.tilt'?"),
        (mass + ("--channel", "disk.tilt", "--at", "1,,2"), "--at '1,,2': time 2 is empty"),
        (mass + ("--channel", "disk.tilt", "--at", ","), "--at ',': time 1 is empty"),
        (("--grid", "initial.disk.x=-1e308:1e308:3"),
         "B - A = 1e+308 - (-1e+308) overflows: the values would not be finite"),
    ]
    for args, says in cases:
        r = run_cli("sweep", disk, *args, "--out", out, check=False)
        assert r.returncode == 2 and says in r.stderr, (args, r.stderr)
        assert not out.exists()


@pytest.mark.parametrize("kw, exc, says", [
    (dict(grid=5), TypeError, "grid must be a dict {path: values}, got int"),
    (dict(random=[1]), TypeError, "random must be a dict"),
    (dict(random={"bodies.disk.mass": "uniform(1,2)"}, samples=10 ** 12), ValueError,
     "samples must be from 1 to 10**9"),
    (dict(samples="3"), TypeError, "samples must be a whole number"),
    (dict(seed=-1), ValueError, "seed must be a whole number from 0"),
    (dict(shard=3), TypeError, "shard must be a pair (i, n)"),
    (dict(channels=5), TypeError, "channels must be a str or a sequence of str"),
    (dict(channels=["disk.tilx"]), appell.SceneError, "did you mean 'disk.tilt'?"),
    (dict(times="x"), TypeError, "times must be numbers"),
    (dict(set=["simulation.t_end=0.01\x00junk"]), ValueError, "a NUL character inside"),
    (dict(set={"simulation.t_end": "0.01\x00"}), ValueError, "a NUL character inside"),
    (dict(chunk_size=0), ValueError, "chunk_size must be a whole number >= 1"),
    (dict(chunk_size=-3), ValueError, "chunk_size must be a whole number >= 1"),
])
def test_sweep_argument_errors_name_the_argument(disk, kw, exc, says):
    args = dict(grid={"bodies.disk.mass": [1, 2]}, set={"simulation.t_end": 0.01})
    args.update(kw)
    with pytest.raises(exc) as info:
        appell.sweep(disk, **args)
    assert says in str(info.value)


def test_load_refuses_a_nul_inside_an_override(disk):
    with pytest.raises(ValueError, match="a NUL character inside"):
        appell.load(disk, set=["bodies.disk.mass=2\x00"])


def test_linearize_plot_target_checked_before_anything_is_written(tmp_path):
    # --plot f.jpg exited 1 and left f.jpg.csv; a missing directory was named as a .csv path
    disk = SCENES / "rolling_disk.yaml"
    sweep = ("linearize", disk, "--sweep", "speed=0:5:11")
    for fig, says in ((tmp_path / "f.jpg", "the figure must end in .png or .svg"),
                      (tmp_path / "no" / "f.png",
                       "its directory does not exist"),
                      (tmp_path / "d.png", "is a directory")):
        if fig.name == "d.png":
            fig.mkdir()
        r = run_cli(*sweep, "--plot", fig, check=False)
        assert r.returncode == 2 and f"--plot {fig}: {says}" in r.stderr, r.stderr
        assert ".csv" not in r.stderr
        assert [p.name for p in tmp_path.iterdir()] in ([], ["d.png"])
    (tmp_path / "d.png").rmdir()
    r = run_cli(*sweep, "--plot", tmp_path / "f.svg")
    assert [p.name for p in tmp_path.iterdir()] == ["f.svg"]   # no side CSV, no temporary
    assert (tmp_path / "f.svg").read_text().count("<path") > 10


def _with_lin(tmp_path, name, scene, old, new):
    path = tmp_path / name
    text = scene.read_text() if hasattr(scene, "read_text") else scene
    assert old in text
    path.write_text(text.replace(old, new))
    return path


def test_check_reports_what_run_and_linearize_refuse(tmp_path):
    # appell check said 0 for each of these; linearize (or run) refused them afterwards
    sleigh = SCENES / "chaplygin_sleigh.yaml"
    init = "  initial: {sleigh: {heading_rate: 0}}\n"
    cases = [
        (_with_lin(tmp_path, "free.yaml", sleigh, init, init + "  free: [sleigh.hedding]\n"),
         ":41:10: linearize.free[0]: 'sleigh.hedding' is not a state variable",
         "did you mean 'sleigh.heading'?"),
        (_with_lin(tmp_path, "indep.yaml", sleigh, init, init + "  independent: [sleigh.vxx]\n"),
         ":41:17: linearize.independent[0]: 'sleigh.vxx' is not a state variable", ""),
        (_with_lin(tmp_path, "inputs.yaml", sleigh, init, init + "  inputs: [sleigh.wz]\n"),
         ":41:12: linearize.inputs[0]: 'sleigh.wz' is not a speed", ""),
        (_with_lin(tmp_path, "speed.yaml", sleigh, "speed: {sleigh: {vx: -1}}",
                   "speed: {sleigh: {x: -1}}"),
         ":41:20: linearize.speed.sleigh.x: 'x' is a coordinate; speed: gives the initial rates",
         ""),
        (_with_lin(tmp_path, "driven.yaml", POLE, "simulation:",
                   "linearize:\n  initial: {arm: {angle: 0.1}}\nsimulation:"),
         ":11:26: linearize.initial.arm.angle: coordinate 'angle' of joint 'arm' is driven", ""),
    ]
    for path, where, more in cases:
        for cmd in ("check", "linearize"):
            r = run_cli(cmd, path, check=False)
            assert r.returncode == 2 and f"{path}{where}" in r.stderr and more in r.stderr, \
                (cmd, r.stderr)
            assert "--set" not in r.stderr
    tree_dae = ("--set", "simulation.path=tree", "--set", "simulation.mode=dae")
    for cmd in ("check", "run"):
        r = run_cli(cmd, sleigh, *tree_dae, *(("-o", tmp_path / "o.csv") if cmd == "run" else ()),
                    check=False)
        assert r.returncode == 2 and "path: tree forms no g or A, which mode: dae needs" \
            in r.stderr, (cmd, r.stderr)
    r = run_cli("check", sleigh)
    assert "linearize    section good: about a steady motion, with a speed parameter" in r.stdout


def test_ctrl_c_stops_a_linearize_sweep_promptly():
    # 10^6 speeds took 51 s with Ctrl-C ignored; the signal now stops it at the next speed
    r = child(f"""
        import os, signal, threading, time
        import numpy as np
        speeds = np.linspace(0.5, 5, 10 ** 6)
        m = appell.load({str(SCENES / "rolling_disk.yaml")!r})
        t = []
        threading.Timer(1.0, lambda: (t.append(time.perf_counter()),
                                      os.kill(os.getpid(), signal.SIGINT))).start()
        try:
            appell.linearize(m, sweep=speeds)
            print("finished")
        except KeyboardInterrupt:
            print("stopped", time.perf_counter() - t[0])
        """)
    assert r.returncode == 0, r.stderr
    word, *late = r.stdout.split()
    assert word == "stopped" and float(late[0]) < 1.0, r.stdout   # polled every 0.2 s


def test_run_warns_when_a_method_cannot_deliver_the_tolerance(tmp_path):
    # CVODE BDF at rtol 1e-12 missed the skate and sleigh bounds by 2.6x, silently
    sleigh = SCENES / "chaplygin_sleigh.yaml"
    for method, rtol, warned in (("bdf", "1e-12", True), ("adams", "1e-10", True),
                                 ("bdf", "1e-8", False), ("dop853", "1e-12", False)):
        r = run_cli("run", sleigh, "--method", method, "--rtol", rtol, "--t-end", "0.1",
                    "--quiet", "-o", tmp_path / "o.csv")
        says = f"warning: method {method} at rtol = {rtol}: below rtol 1e-08 its global error"
        assert (says in r.stderr) == warned, (method, rtol, r.stderr)
    r = run_cli("run", sleigh, "--mode", "dae", "--method", "bdf", "--rtol", "1e-12",
                "--t-end", "0.1", "--quiet", "-o", tmp_path / "o.csv", check=False)
    assert "warning: method" not in r.stderr   # DAE mode integrates with IDA


def test_an_interrupted_sweep_resumes_to_the_same_table(tmp_path, disk):
    # an interrupted sweep kept nothing and reran from scratch
    import random
    import signal
    import time
    args = [EXE, "sweep", disk, "--grid", "initial.disk.tilt=70*deg:89*deg:300",
            "--grid", "bodies.disk.mass=1,2", "--set", "simulation.t_end=0.3",
            "--channel", "disk.tilt", "--jobs", "2", "--quiet"]
    args = [str(a) for a in args]
    subprocess.run(args + ["--out", str(tmp_path / "full.csv")], check=True)
    full = (tmp_path / "full.csv").read_bytes()
    rng = random.Random()
    for k, sig in enumerate((signal.SIGKILL, signal.SIGINT)):
        out = tmp_path / f"part{k}.csv"
        p = subprocess.Popen(args + ["--out", str(out)], stderr=subprocess.DEVNULL)
        time.sleep(rng.uniform(0.3, 1.2))
        p.send_signal(sig)
        p.wait()
        partial = tmp_path / f"part{k}.csv.partial"
        if p.returncode == 0:   # it finished first on this machine: nothing to resume
            continue
        assert not out.exists() and partial.exists()
        r = subprocess.run(args + ["--out", str(out)], capture_output=True, text=True)
        assert r.returncode == 2 and "--resume continues it" in r.stderr
        if len(partial.read_bytes().splitlines()) > 1:   # rows of this plan: not another's
            other = args[:4] + ["initial.disk.tilt=70*deg:89*deg:301"] + args[5:]
            r = subprocess.run(other + ["--out", str(out), "--resume"], capture_output=True,
                               text=True)
            assert r.returncode == 2 and "another sweep's or shard's checkpoint" in r.stderr, \
                r.stderr
        subprocess.run(args + ["--out", str(out), "--resume"], check=True)
        assert out.read_bytes() == full and not partial.exists()
