"""Hostile and wrong calls of the Python package: each is refused with the exception and
message a user can act on, within the limits the command-line tool keeps. Calls that could
take the interpreter down (huge reads, a crash) run in a child interpreter."""

import os
import subprocess
import sys
import textwrap

import pytest

import appell
from conftest import SCENES, run_cli

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
