#!/usr/bin/python3
"""How long `appell run` takes to stop after SIGINT when the output interval is long.

    bench/signal_latency.py [APPELL] [--repeat N]

Runs the rolling disk (examples/scenes/rolling_disk.yaml) to t = 2000 s with one output
interval of 2000 s and a rtol of 1e-12, so that the whole run is one call of ap_sim_advance
that takes several seconds; sends SIGINT 0.5 s after the temporary output file appears and
measures the wall time from the signal to the process's exit. Prints one line per run (latency,
exit code, temporary files left) and the median. APPELL defaults to build/tools/appell. A
version that looks at signals only between output rows needs the rest of the interval (or
fails at max_steps, exit 3); one that polls between internal steps exits within a step.
"""
import glob
import os
import signal
import statistics
import subprocess
import sys
import tempfile
import time


def one(appell, scene):
    with tempfile.TemporaryDirectory() as d:
        out = os.path.join(d, "disk.csv")
        p = subprocess.Popen([appell, "run", scene, "--quiet", "--out", out, "--t-end", "2000",
                              "--interval", "2000", "--rtol", "1e-12", "--atol", "1e-14",
                              "--set", "simulation.max_steps=100000000"],
                             stderr=subprocess.PIPE)
        start = time.monotonic()
        while not glob.glob(out + ".*") and p.poll() is None and time.monotonic() - start < 30:
            time.sleep(0.005)
        time.sleep(0.5)
        sent = time.monotonic()
        p.send_signal(signal.SIGINT)
        err = p.communicate()[1].decode(errors="replace").strip()
        latency = time.monotonic() - sent
        left = len(glob.glob(out + "*"))
        return latency, p.returncode, left, err


def main():
    args = [a for a in sys.argv[1:]]
    repeat = 3
    if "--repeat" in args:
        i = args.index("--repeat")
        repeat = int(args[i + 1])
        del args[i:i + 2]
    appell = args[0] if args else "build/tools/appell"
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    scene = os.path.join(root, "examples", "scenes", "rolling_disk.yaml")
    lat = []
    for _ in range(repeat):
        latency, code, left, err = one(appell, scene)
        lat.append(latency)
        print(f"latency {latency:.4f} s  exit {code}  files left {left}  {err}")
    print(f"median latency {statistics.median(lat):.4f} s over {repeat} runs ({appell})")


if __name__ == "__main__":
    main()
