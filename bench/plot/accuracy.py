#!/usr/bin/env python3
"""How each method's global error relates to the tolerance (docs/steppers.md, "Accuracy").

Runs build/bench/bench_wp --one for every reference problem with a closed form (knife edge on an
incline, Chaplygin sleigh, ball on a turntable at constant and varying Omega, bead on a rotating
line), every adaptive method and rtol = atol = TOL in 1e-6 ... 1e-12, in Appell's minimal mode,
and prints a Markdown table: per method and TOL, the worst over the problems of
err / (TOL * scale), err being the largest position error (m) over the outputs against the
exact solution (bench_wp) and scale = max(1, the largest |position| of the exact solution at
the outputs, m) (bench_wp --describe): the global error in units of the tolerance.

Usage: OPENBLAS_NUM_THREADS=1 bench/plot/accuracy.py [BUILD_DIR]     (about a minute)
"""

import os
import re
import subprocess
import sys
import tempfile

PROBLEMS = ["knife_edge", "sleigh", "turntable", "turntable_var", "rotating_line"]
METHODS = ["bs3", "dopri5", "verner6", "fehlberg8", "dop853", "adams", "bdf"]
TOLS = [1e-6, 1e-8, 1e-10, 1e-12]


def err_of(exe, problem, method, tol):
    r = subprocess.run([exe, "--one", problem, "appell", "minimal", method, repr(tol),
                        "--reps", "1"], capture_output=True, text=True,
                       env={**os.environ, "OPENBLAS_NUM_THREADS": "1"})
    m = re.search(r"err ([0-9.e+-]+|nan|inf)", r.stdout)
    return float(m.group(1)) if r.returncode == 0 and m else float("nan")


def scales(exe):
    """max(1, max |exact position|) per problem, from bench_wp --describe."""
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "describe.txt")
        subprocess.run([exe, "--describe", path, "--problems", ",".join(PROBLEMS)],
                       capture_output=True, check=True)
        out = {p: 1.0 for p in PROBLEMS}
        for line in open(path):
            f = line.split()
            if len(f) > 3 and f[1] == "exact" and f[0] in out:
                out[f[0]] = max([out[f[0]]] + [abs(float(x)) for x in f[3:]])
    return out


def main():
    build = sys.argv[1] if len(sys.argv) > 1 else "build"
    exe = os.path.join(build, "bench", "bench_wp")
    scale = scales(exe)
    print("| method | " + " | ".join(f"rtol {t:.0e}" for t in TOLS) + " | worst problem at 1e-12 |")
    print("| --- |" + " --- |" * (len(TOLS) + 1))
    for method in METHODS:
        cells, worst_at_tight = [], ""
        for tol in TOLS:
            ratios = {p: err_of(exe, p, method, tol) / (tol * scale[p]) for p in PROBLEMS}
            worst = max(ratios, key=lambda p: ratios[p] if ratios[p] == ratios[p] else 1e300)
            cells.append(f"{ratios[worst]:.2g}")
            if tol == TOLS[-1]:
                worst_at_tight = worst
        print(f"| `{method}` | " + " | ".join(cells) + f" | {worst_at_tight} |")


if __name__ == "__main__":
    main()
