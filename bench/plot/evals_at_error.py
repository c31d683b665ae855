#!/usr/bin/env python3
"""Right-hand-side evaluations (or CPU time) needed to reach an error, per work-precision curve.

Reads work-precision CSVs with bench_wp's columns (wp_appell.csv, wp_sympy.csv,
wp_scipy_hand.csv) and prints, for each curve (problem, tool, mode, method), the evaluations
at the error levels 1e-5 ... 1e-12, interpolated linearly in (log error, log evaluations)
between the first pair of consecutive sweep points that brackets the level (as report.py
does for CPU time); "-" where no pair brackets it. Evaluations do not depend on the machine
or its load. With --cpu the CPU time (ms) of the run is interpolated instead. Only the Python
standard library is used.

Usage: evals_at_error.py CSV... [--problems a,b] [--methods a,b] [--md] [--cpu]
"""
import csv
import math
import os
import sys

LEVELS = [1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12]


def at(points, level):
    for (e1, n1), (e2, n2) in zip(points, points[1:]):
        if e1 > 0 and e2 > 0 and e1 != e2 and (e1 - level) * (e2 - level) <= 0:
            f = math.log(e1 / level) / math.log(e1 / e2)
            return math.exp(math.log(n1) + f * (math.log(n2) - math.log(n1)))
    return None


def main(argv):
    files, problems, methods, md, col = [], None, None, False, "rhs_evals"
    i = 0
    while i < len(argv):
        if argv[i] == "--problems":
            problems, i = argv[i + 1].split(","), i + 1
        elif argv[i] == "--methods":
            methods, i = argv[i + 1].split(","), i + 1
        elif argv[i] == "--md":
            md = True
        elif argv[i] == "--cpu":
            col = "cpu_s"
        else:
            files.append(argv[i])
        i += 1
    curves = {}
    for path in files:
        if not os.path.exists(path):
            print(f"evals_at_error: {path} is absent, skipped", file=sys.stderr)
            continue
        for r in csv.DictReader(open(path)):
            if r["status"] != "0" or float(r[col]) <= 0:
                continue
            if problems and r["problem"] not in problems:
                continue
            if methods and r["method"] not in methods:
                continue
            key = (r["problem"], r["tool"], r["mode"], r["method"])
            scale = 1e3 if col == "cpu_s" else 1.0
            curves.setdefault(key, []).append((float(r["err"]), scale * float(r[col])))
    head = ["problem", "tool", "mode", "method"] + ["%.0e" % e for e in LEVELS]
    if md:
        print("| " + " | ".join(head) + " |")
        print("|" + "---|" * len(head))
    else:
        print("%-13s %-11s %-9s %-9s" % tuple(head[:4]) + "".join("%7s" % h for h in head[4:]))
    for key in sorted(curves):
        vals = [at(curves[key], e) for e in LEVELS]
        cells = [("%.3g" if col == "cpu_s" else "%.0f") % v if v else "-" for v in vals]
        if md:
            print("| " + " | ".join(list(key) + cells) + " |")
        else:
            print("%-13s %-11s %-9s %-9s" % key + "".join("%7s" % c for c in cells))


if __name__ == "__main__":
    main(sys.argv[1:])
