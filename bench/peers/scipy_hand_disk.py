#!/usr/bin/python3
"""SciPy's DOP853 on the rolling disk's hand-reduced ODE: the integrators compared on one ODE.

bench_wp integrates the disk's hand-reduced ODE (bench_wp.c, disk_hand: seven equations in the
lean frame, y = (x, y, psi, theta, w1, w2, w3)) with every stepper of Appell, and sympy_peer.py
runs SciPy on SymPy's own disk model, whose state and error weights differ. This script runs
scipy.integrate.solve_ivp (DOP853 and RK45) on exactly bench_wp's hand ODE, from the initial
state and against the reference positions bench_wp wrote (problems.txt), in two ways:
  t_eval   one solve over [0, T] with t_eval = the 10 output times (SciPy's dense output);
  stops    one solve per output interval, restarted at each output time (as bench_wp's runs
           stop exactly at every output);
at rtol = atol = 1e-3 ... 1e-12, recording the largest centre error over the outputs and the
right-hand-side evaluations (nfev). The CSV has bench_wp's columns (tool scipy_hand, mode
t_eval or stops); CPU times are not comparable with C and are left 0.

Usage: /usr/bin/python3 scipy_hand_disk.py PROBLEMS_FILE --csv OUT.csv
"""
import argparse
import math
import sys

import scipy
from scipy.integrate import solve_ivp


def read_disk(path):
    p = {"exact": []}
    for line in open(path):
        w = line.split()
        if len(w) < 2 or w[0] != "rolling_disk":
            continue
        if w[1] == "param":
            p.update({w[i]: float(w[i + 1]) for i in range(2, len(w), 2)})
        elif w[1] == "euler":
            p["y0"] = [float(v) for v in w[2:]]
        elif w[1] == "T":
            p["T"] = float(w[2])
        elif w[1] == "exact":
            p["exact"].append([float(v) for v in w[2:]])
    return p


def hand_rhs(p):
    """bench_wp.c's disk_hand, term by term."""
    m, r, g = p["m"], p["r"], p["grav"]
    A, C, mr2 = 0.25 * m * r * r, 0.5 * m * r * r, m * r * r

    def f(t, y):
        cp, sp, ct, st = math.cos(y[2]), math.sin(y[2]), math.cos(y[3]), math.sin(y[3])
        tt, w1, w2, w3 = st / ct, y[4], y[5], y[6]
        return [r * (w2 * cp + w1 * ct * sp), r * (w2 * sp - w1 * ct * cp), w3 / ct, w1,
                ((C + mr2) * w2 * w3 - A * w3 * w3 * tt + m * g * r * st) / (A + mr2),
                -mr2 * w1 * w3 / (C + mr2), w1 * w3 * tt - (C / A) * w1 * w2]
    return f


def run(f, p, method, tol, stops):
    ex, err, nfev, steps = p["exact"], 0.0, 0, 0
    if not stops:
        s = solve_ivp(f, (0.0, p["T"]), p["y0"], method=method, t_eval=[e[0] for e in ex],
                      rtol=tol, atol=tol)
        if not s.success:
            return False, math.inf, s.nfev
        for i, e in enumerate(ex):
            err = max(err, abs(s.y[0][i] - e[1]), abs(s.y[1][i] - e[2]))
        return True, err, s.nfev
    y, t = list(p["y0"]), 0.0
    for e in ex:
        s = solve_ivp(f, (t, e[0]), y, method=method, rtol=tol, atol=tol)
        if not s.success:
            return False, math.inf, nfev + s.nfev
        y, t, nfev = s.y[:, -1], e[0], nfev + s.nfev
        err = max(err, abs(y[0] - e[1]), abs(y[1] - e[2]))
    return True, err, nfev


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("problems")
    ap.add_argument("--csv", required=True)
    a = ap.parse_args()
    p = read_disk(a.problems)
    f = hand_rhs(p)
    print(f"SciPy {scipy.__version__} on bench_wp's hand-reduced rolling disk ODE", flush=True)
    out = open(a.csv, "w")
    out.write("problem,tool,mode,method,tol,h,status,err,cpu_s,cpu_lo,cpu_hi,reps,steps,"
              "rhs_evals,err_fails,us_per_eval,residual\n")
    for method in ("DOP853", "RK45"):
        for mode in ("t_eval", "stops"):
            for i in range(10):
                tol = 10.0 ** (-3 - i)
                ok, err, nfev = run(f, p, method, tol, mode == "stops")
                print(f"  rolling_disk scipy_hand {mode:6s} {method:6s} {tol:7.0e} "
                      f"{err:9.2e} {nfev:7d} evals" + ("" if ok else "  FAILED"), flush=True)
                out.write(f"rolling_disk,scipy_hand,{mode},{method},{tol:.3g},0,"
                          f"{0 if ok else -1},{err:.6e},0,0,0,1,-1,{nfev},-1,0,0\n")
    out.close()


if __name__ == "__main__":
    sys.exit(main())
