"""Shared fixtures of the Python tests: where the sources and the appell command are.

meson runs these with PYTHONPATH=build/python (the package as built), APPELL_EXE (the
command-line tool) and APPELL_SOURCE_DIR (the repository), with OPENBLAS_NUM_THREADS=1."""

import os
import subprocess
from pathlib import Path

import pytest

SOURCE = Path(os.environ["APPELL_SOURCE_DIR"] if "APPELL_SOURCE_DIR" in os.environ
              else Path(__file__).resolve().parents[2])
SCENES = SOURCE / "examples" / "scenes"
BAD = SOURCE / "tests" / "scenes"
EXE = os.environ.get("APPELL_EXE", str(SOURCE / "build" / "tools" / "appell"))


def run_cli(*args, check=True):
    """appell ARGS...; returns the CompletedProcess (text)."""
    r = subprocess.run([EXE, *map(str, args)], capture_output=True, text=True)
    if check and r.returncode != 0:
        raise AssertionError(f"appell {' '.join(map(str, args))} exited {r.returncode}:\n{r.stderr}")
    return r


@pytest.fixture
def disk():
    return SCENES / "rolling_disk.yaml"
