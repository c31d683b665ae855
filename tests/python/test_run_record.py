"""Runs that stop keep their rows and say why; every file the package writes obeys the rules
of `appell run --out` (docs/cli.md "Output files and signals", "The run record").

References: a successful run of the same scene (a failed run's rows up to the failure are the
same numbers), Python's own json module (the record is valid JSON and reads back to the
strings written, escapes and invalid bytes included), the file system itself (a FIFO stays a
FIFO, a link a link, /dev/full a character device). Every call that could replace a device or
crash the interpreter runs in a subprocess."""

import json
import os
import shutil
import stat
import subprocess
import sys
import textwrap
import threading

import numpy as np
import pytest

import appell
from conftest import BAD, SCENES, run_cli

DRIVE = "t*t + 0/step(1.005 - t)"            # t^2, then 0/0 (NaN) after t = 1.005
NAN_DRIVE = {"joints.wheel.drive.angle": DRIVE}


def _python(code, **kw):
    """Run code in a fresh interpreter with the package; returns the CompletedProcess."""
    return subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True,
                          text=True, timeout=120, **kw)


def _table():
    return appell.sweep(SCENES / "rolling_disk.yaml", grid={"bodies.disk.mass": [1, 2]},
                        set={"simulation.t_end": 0.2})


def _no_temporaries(directory):
    return [n for n in os.listdir(directory) if ".tmp." in n or ".appell-tmp." in n] == []


# ---- runs that stop ------------------------------------------------------------------------

def test_failed_run_keeps_rows_and_says_why():
    drive = BAD / "drive_abs.yaml"
    ok = appell.Simulation(appell.load(drive, set=NAN_DRIVE)).run(t_end=1, dt=0.01)
    assert ok.status == "ok" and ok.message == "" and ok.events == []
    with pytest.raises(appell.Error) as info:
        appell.Simulation(appell.load(drive, set=NAN_DRIVE)).run(t_end=2, dt=0.01)
    r = info.value.result
    assert r.status == "failed" and "the simulation failed at t = 1" in r.message
    assert r.events == []
    assert len(r) == len(ok) == 101                        # every row up to the failure
    assert np.array_equal(r.table, ok.table)               # the same steps up to t = 1


def test_cli_failure_record_reads_back(tmp_path):
    out = tmp_path / "fail.csv"
    r = run_cli("run", BAD / "drive_abs.yaml", "--set", f"joints.wheel.drive.angle={DRIVE}",
                "--t-end", "2", "--out", out, "--quiet", check=False)
    assert r.returncode == 3
    run = appell.read_run(out)
    rec = json.loads((tmp_path / "fail.csv.run.json").read_text())
    assert run.record == rec and run.status == rec["status"] == "failed"
    assert rec["exit_code"] == 3 and rec["rows"] == len(run) == 101
    assert rec["message"] == r.stderr.strip() == run.message
    assert run.t[-1] == 1 and 1 <= rec["t"] <= 1.005      # the last row, where it gave up
    assert "0 / 0 = nan" in rec["message"]                 # the expression, located
    assert rec["overrides"] == [f"joints.wheel.drive.angle={DRIVE}", "simulation.t_end=2"]
    assert rec["settings"]["mode"] == "minimal" and rec["settings"]["t_end"] == 2
    # the Python run of the same scene has the same rows (15 digits in the CSV)
    with pytest.raises(appell.Error) as info:
        appell.Simulation(appell.load(BAD / "drive_abs.yaml", set=NAN_DRIVE)).run(t_end=2)
    assert np.allclose(info.value.result.table, run.table, rtol=1e-14, atol=1e-300)
    assert appell.read_run(tmp_path / "fail.csv.run.json").status == "failed"


def test_record_strings_are_valid_json(tmp_path):
    name = os.fsencode(tmp_path) + b'/a "q" \\ \xff\xfe.csv'
    value = 'a "quoted" \\ name\ttab'
    r = subprocess.run([os.environ.get("APPELL_EXE", "appell"), "run",
                        str(SCENES / "rolling_disk.yaml"), "--t-end", "0.05", "--quiet",
                        "--set", f"name={value}", "--out", name], capture_output=True)
    assert r.returncode == 0, r.stderr
    with open(name + b".run.json", "rb") as f:
        rec = json.loads(f.read().decode("utf-8"))           # strictly valid UTF-8 JSON
    assert rec["out"] == os.fsdecode(name).encode("utf-8", "surrogateescape").decode(
        "utf-8", "replace")                                  # U+FFFD for the bytes that are not
    assert rec["overrides"] == [f"name={value}", "simulation.t_end=0.05"]
    assert rec["name"] == value
    assert rec["status"] == "ok" and rec["rows"] == 6 and rec["events"] == []


def test_keyboard_interrupt_carries_the_rows():
    r = _python("""
        import signal, threading, appell
        sim = appell.Simulation(appell.load(%r))
        threading.Timer(1.0, signal.raise_signal, (signal.SIGINT,)).start()
        try:
            sim.run(t_end=1e4, dt=0.01)
        except KeyboardInterrupt as e:
            r = e.result
            print(r.status, len(r), r.t[-1] > r.t[-2], r.t[-1] == sim.t, r.message)
    """ % str(SCENES / "rolling_disk.yaml"))
    assert r.returncode == 0, r.stderr
    status, rows, rising, at_stop, message = r.stdout.split(" ", 4)
    assert status == "interrupted" and int(rows) > 10 and rising == at_stop == "True"
    assert message.startswith("interrupted by KeyboardInterrupt at t = ")


def test_sweep_rows_have_outcome_and_events(tmp_path, disk):
    t = appell.sweep(disk, grid={"bodies.disk.mass": [1, -1]}, set={"simulation.t_end": 0.1})
    assert list(t["outcome"]) == ["ok", "failed"] and list(t["events"]) == ["", ""]
    assert t.columns[t.columns.index("status") + 1:][:2] == ("outcome", "events")
    run_cli("sweep", disk, "--grid", "bodies.disk.mass=1,-1", "--set", "simulation.t_end=0.1",
            "--out", tmp_path / "cli.csv", "--quiet")
    t.to_csv(tmp_path / "py.csv")
    assert (tmp_path / "py.csv").read_bytes() == (tmp_path / "cli.csv").read_bytes()


# ---- Table.to_csv: the rules of --out --------------------------------------------------------

def test_to_csv_refuses_a_directory_and_leaves_nothing(tmp_path):
    t = _table()
    with pytest.raises(IsADirectoryError, match="is a directory"):
        t.to_csv(tmp_path)
    with pytest.raises(FileNotFoundError, match="its directory does not exist"):
        t.to_csv(tmp_path / "missing" / "x.csv")
    assert os.listdir(tmp_path) == [] and _no_temporaries(tmp_path.parent)


def test_to_csv_refuses_the_scene(tmp_path):
    scene = tmp_path / "disk.yaml"
    scene.write_bytes((SCENES / "rolling_disk.yaml").read_bytes())
    os.link(scene, tmp_path / "alias.yaml")
    t = appell.sweep(scene, grid={"bodies.disk.mass": [1]}, set={"simulation.t_end": 0.1})
    for target in (scene, tmp_path / "alias.yaml"):
        with pytest.raises(FileExistsError, match="refusing to overwrite"):
            t.to_csv(target)
    assert scene.read_bytes() == (SCENES / "rolling_disk.yaml").read_bytes()
    assert _no_temporaries(tmp_path)


def test_to_csv_follows_links_and_keeps_modes(tmp_path):
    t = _table()
    t.to_csv(tmp_path / "ref.csv")
    target, link = tmp_path / "file.csv", tmp_path / "link.csv"
    target.write_text("old\n")
    target.chmod(0o444)                           # read-only: replaced, keeps its mode
    link.symlink_to("file.csv")
    t.to_csv(link)
    assert link.is_symlink() and target.read_bytes() == (tmp_path / "ref.csv").read_bytes()
    assert stat.S_IMODE(target.stat().st_mode) == 0o444
    (tmp_path / "dangling.csv").symlink_to("nowhere/x.csv")
    with pytest.raises(FileNotFoundError, match="cannot be reached"):
        t.to_csv(tmp_path / "dangling.csv")
    assert _no_temporaries(tmp_path)


def test_to_csv_writes_a_fifo_in_place(tmp_path):
    t = _table()
    t.to_csv(tmp_path / "ref.csv")
    fifo = tmp_path / "pipe.csv"
    os.mkfifo(fifo)
    got = []
    reader = threading.Thread(target=lambda: got.append(open(fifo, "rb").read()))
    reader.start()
    t.to_csv(fifo)
    reader.join(30)
    assert got == [(tmp_path / "ref.csv").read_bytes()]
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode) and _no_temporaries(tmp_path)


def test_to_csv_failed_write_leaves_the_old_file(tmp_path):
    target = tmp_path / "x.csv"
    target.write_text("old\n")
    r = _python("""
        import resource, signal, appell
        t = appell.sweep(%r, grid={"bodies.disk.mass": [1, 2]}, set={"simulation.t_end": 0.2})
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (100, 100))
        try:
            t.to_csv(%r)
        except OSError as e:
            print(type(e).__name__, e.errno, e.filename)
    """ % (str(SCENES / "rolling_disk.yaml"), str(target)))
    assert r.returncode == 0, r.stderr
    assert r.stdout.split() == ["OSError", "27", str(target)]   # EFBIG
    assert target.read_text() == "old\n" and os.listdir(tmp_path) == ["x.csv"]


def test_to_csv_on_dev_full_is_written_in_place():
    before = os.stat("/dev/full")
    r = _python("""
        import appell
        t = appell.sweep(%r, grid={"bodies.disk.mass": [1]}, set={"simulation.t_end": 0.1})
        try:
            t.to_csv("/dev/full")
        except OSError as e:
            print(e.errno)
    """ % str(SCENES / "rolling_disk.yaml"))
    assert r.returncode == 0, r.stderr
    assert r.stdout.split() == ["28"]                     # ENOSPC: written to the device
    after = os.stat("/dev/full")
    assert stat.S_ISCHR(after.st_mode) and after.st_rdev == before.st_rdev
    assert after.st_ino == before.st_ino
    assert not [n for n in os.listdir("/dev") if n.startswith("full.")]


@pytest.mark.skipif(shutil.which("gnuplot") is None, reason="gnuplot (gnuplot-nox) is missing")
def test_plot_says_how_the_run_ended(tmp_path):
    out = tmp_path / "fail.csv"
    r = run_cli("run", BAD / "drive_abs.yaml", "--set", f"joints.wheel.drive.angle={DRIVE}",
                "--t-end", "2", "--out", out, "--quiet", check=False)
    assert r.returncode == 3
    run_cli("plot", out, "--y", "arm.angle", "-o", tmp_path / "a.svg")
    svg = (tmp_path / "a.svg").read_text()
    assert "failed at t = 1" in svg and "user callback reported failure" in svg
    run_cli("plot", out, "--y", "arm.angle", "--title", "mine", "-o", tmp_path / "b.svg")
    assert "failed at" not in (tmp_path / "b.svg").read_text()        # --title wins
    (tmp_path / "fail.csv.run.json").write_text('{"format": "appell run record 1", "status": ')
    run_cli("plot", out, "--y", "arm.angle", "-o", tmp_path / "c.svg")  # not a record: ignored
    assert "failed at" not in (tmp_path / "c.svg").read_text()
