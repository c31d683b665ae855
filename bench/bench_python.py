"""bench_python: what Python costs per run, against the command-line tool.

1. Sweep: the same plan (a grid of the rolling disk, 5 s each at rtol 1e-8) through
   appell.sweep(jobs=1) in this process and through `appell sweep --jobs 1` as a child process;
   CPU time per run of each (this process's CPU time for Python, the child's user + system time
   for the CLI) and the Python overhead (Python - CLI) / CLI.
2. Single runs: appell.Simulation(model).run() (load + create + rows as NumPy arrays) against
   `appell run --quiet --out /dev/null` (load + create + rows as CSV text, plus the start of a
   process); CPU per run of each.
Each measurement is repeated --repeat times (default 3) and the median is reported, with the
load average before and after. CPU times do not count waiting for the processor, so they are
meaningful on a shared machine; wall times are printed too.

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=build/python /usr/bin/python3 bench/bench_python.py \
        [--runs 1000] [--single 100] [--repeat 3] [--exe build/tools/appell]
"""

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time

import appell

HERE = os.path.dirname(os.path.abspath(__file__))
SCENE = os.path.join(HERE, "..", "examples", "scenes", "rolling_disk.yaml")


def child_cpu():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def grid(runs):
    a = max(1, int(runs ** 0.5))
    b = -(-runs // a)
    return {"initial.disk.tilt": f"60*deg:89*deg:{a}", "initial.disk.spin_rate": f"-8:-4:{b}"}


def python_sweep(runs):
    c0, w0 = time.process_time(), time.perf_counter()
    t = appell.sweep(SCENE, grid=grid(runs), set={"simulation.t_end": 5, "simulation.rtol": 1e-8},
                     jobs=1)
    return time.process_time() - c0, time.perf_counter() - w0, len(t["run"])


def cli_sweep(exe, runs, out):
    g = grid(runs)
    args = [exe, "sweep", SCENE, "--quiet", "--jobs", "1", "--t-end", "5", "--rtol", "1e-8",
            "--out", out] + sum((["--grid", f"{p}={v}"] for p, v in g.items()), [])
    c0, w0 = child_cpu(), time.perf_counter()
    subprocess.run(args, check=True)
    return child_cpu() - c0, time.perf_counter() - w0


def python_single(n):
    c0, w0 = time.process_time(), time.perf_counter()
    for _ in range(n):
        m = appell.load(SCENE, set={"simulation.t_end": 5, "simulation.rtol": 1e-8})
        appell.Simulation(m).run()
    return time.process_time() - c0, time.perf_counter() - w0


def cli_single(exe, n):
    args = [exe, "run", SCENE, "--quiet", "--t-end", "5", "--rtol", "1e-8", "--out", os.devnull]
    c0, w0 = child_cpu(), time.perf_counter()
    for _ in range(n):
        subprocess.run(args, check=True)
    return child_cpu() - c0, time.perf_counter() - w0


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=1000)
    ap.add_argument("--single", type=int, default=100)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--exe", default=os.path.join(HERE, "..", "build", "tools", "appell"))
    a = ap.parse_args()
    la0 = os.getloadavg()
    python_sweep(20)   # warm-up: imports, page cache
    out = os.path.join(tempfile.mkdtemp(), "sweep.csv")
    py, cli = [], []
    for _ in range(a.repeat):
        cpu, wall, n = python_sweep(a.runs)
        py.append((cpu / n, wall / n))
        cpu, wall = cli_sweep(a.exe, a.runs, out)
        cli.append((cpu / n, wall / n))
    pc, cc = statistics.median(x[0] for x in py), statistics.median(x[0] for x in cli)
    pw, cw = statistics.median(x[1] for x in py), statistics.median(x[1] for x in cli)
    print(f"sweep of {n} runs, jobs=1, median of {a.repeat}:")
    print(f"  python  {1e3 * pc:8.3f} ms CPU per run  ({1e3 * pw:.3f} ms wall)")
    print(f"  cli     {1e3 * cc:8.3f} ms CPU per run  ({1e3 * cw:.3f} ms wall)")
    print(f"  python overhead {100 * (pc - cc) / cc:+.2f}% CPU ({100 * (pw - cw) / cw:+.2f}% wall)")
    ps, cs = [], []
    for _ in range(a.repeat):
        ps.append(python_single(a.single)[0] / a.single)
        cs.append(cli_single(a.exe, a.single)[0] / a.single)
    p1, c1 = statistics.median(ps), statistics.median(cs)
    print(f"single runs ({a.single}, load + run + rows), median of {a.repeat}:")
    print(f"  python Simulation.run  {1e3 * p1:8.3f} ms CPU per run")
    print(f"  appell run (process)   {1e3 * c1:8.3f} ms CPU per run")
    print(f"  python overhead {100 * (p1 - c1) / c1:+.2f}% CPU")
    la1 = os.getloadavg()
    print("load average before %.2f %.2f %.2f, after %.2f %.2f %.2f on %d processors"
          % (*la0, *la1, os.cpu_count()))


if __name__ == "__main__":
    sys.exit(main())
