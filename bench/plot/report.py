#!/usr/bin/env python3
"""Ratios at equal achieved error, tables and work-precision plots from one harness run.

Reads the CSVs scripts/bench wrote into a results directory (bench_wp: wp_appell.csv, with
Appell's curves and the hand-reduced "limit"; when present wp_sympy.csv and sympy_build.csv
from bench/peers/sympy_peer.py, wp_simbody.csv from bench_simbody, and wp_appell_compiled.csv
from bench_wp --compiled: the body ball with compiled kinematics) and writes there
  ratios.csv     per problem and error level 1e-4 ... 1e-10: the best curve of each tool
                 (Appell, the limit, SymPy+SciPy, Simbody) with its interpolated CPU time, and
                 the ratios ours / limit, ours / SymPy, ours / Simbody;
  overhead.csv   per problem, stepper, Appell mode and error level: Appell / hand-reduced ODE
                 under the same stepper;
  summary.md     the tables in Markdown (also printed);
  wp_<problem>.png and .svg   error against CPU time, one curve per tool/mode/method.

Equal achieved error: a curve is its sweep points (error, CPU time) in sweep order; the time
at an error level E is interpolated linearly in (log error, log time) between the first pair
of consecutive points that brackets E. When no pair brackets E and a point is already below
it (the loosest tolerance overshoots), the cheapest such point's time is used and the value
is marked "<=" (an upper bound: a looser tolerance could be cheaper). A curve that never gets
below E has no value there. Only the Python standard library is used.

Usage: report.py RESULTS_DIR [--no-plots]
"""
import csv
import math
import os
import shutil
import statistics
import subprocess
import sys

LEVELS = [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10]
SHOW = [1e-4, 1e-6, 1e-8, 1e-10]
STEPPERS = ["bs3", "dopri5", "verner6", "fehlberg8", "dop853", "rk4", "adams", "bdf"]
COLOR = {m: i + 1 for i, m in enumerate(s for s in STEPPERS if s != "dop853")}
COLOR["ida"] = 8
COLOR["dop853"] = 9
PROBLEMS = ["knife_edge", "sleigh", "turntable", "turntable_var", "rotating_line",
            "rolling_disk"]
TITLES = {
    "knife_edge": "Knife edge on an incline (k 3, b 1; partition switches)",
    "sleigh": "Chaplygin sleigh (k 3, b 1)",
    "turntable": "Ball on a turntable, constant Omega (k 5, b 2, affine)",
    "turntable_var": "Ball on a turntable, Omega(t) (k 5, b 2, rheonomic)",
    "rotating_line": "Bead on a rotating line, 3-D (k 3, b 2, rheonomic)",
    "rolling_disk": "Rolling disk, body model (n 6, k 5, b 2); reference: hand ODE at 1e-14",
}
MODE_ORDER = {"minimal": 0, "projected": 1, "dae": 2}


def read_rows(path):
    if not os.path.exists(path):
        return []
    with open(path) as f:
        return list(csv.DictReader(f))


def curves_of(rows):
    """{(problem, tool, mode, method): [(err, cpu), ...] in sweep order} of successful runs."""
    cur = {}
    for r in rows:
        key = (r["problem"], r["tool"], r["mode"], r["method"])
        pts = cur.setdefault(key, [])
        err, cpu = float(r["err"]), float(r["cpu_s"])
        if int(r["status"]) == 0 and math.isfinite(err) and err > 0 and cpu > 0:
            pts.append((err, cpu))
    return {k: v for k, v in cur.items() if v}


def time_at(pts, E):
    """(time, exact) to reach error E on a curve; exact False marks an upper bound."""
    best, exact = None, False
    for (e0, t0), (e1, t1) in zip(pts, pts[1:]):
        if (e0 - E) * (e1 - E) <= 0 and e0 != e1:
            f = (math.log(E) - math.log(e0)) / (math.log(e1) - math.log(e0))
            t = math.exp(math.log(t0) + f * (math.log(t1) - math.log(t0)))
            if best is None or t < best:
                best, exact = t, True
    below = [t for e, t in pts if e <= E]
    if below and (best is None or min(below) < best):
        # a point at or below E that is cheaper than any bracket: exact only if a bracket
        # exists (then the point lies on the curve's way down), else an upper bound
        best, exact = min(below), best is not None
    return best, exact


def label(key):
    _, tool, mode, meth = key
    if tool == "appell":
        return f"Appell {mode} {meth}"
    if tool == "appell_body":
        return f"Appell body {mode} {meth}"
    if tool == "appell_body_c":
        return f"Appell body compiled {mode} {meth}"
    if tool == "hand":
        return f"limit (hand ODE) {meth}"
    if tool == "sympy_scipy":
        return f"SymPy+SciPy {meth}"
    if tool == "simbody_disk_check":
        return f"Simbody {meth} (NoSlip1D disk, energy not kept)"
    return f"Simbody {meth}"


def best_of(curves, problem, tools, E):
    """Cheapest curve among tools at error E: (time, exact, key) or None."""
    best = None
    for key, pts in curves.items():
        if key[0] != problem or key[1] not in tools:
            continue
        t, ex = time_at(pts, E)
        if t is not None and (best is None or t < best[0]):
            best = (t, ex, key)
    return best


def fmt_t(v):
    if v is None:
        return "-"
    t, ex = v[0], v[1]
    s = f"{1e3 * t:.3g} ms" if t < 1 else f"{t:.3g} s"
    return s if ex else "<=" + s


def fmt_r(a, b):
    if a is None or b is None:
        return "-"
    r = a[0] / b[0]
    s = f"{r:.3g}"
    return s if (a[1] and b[1]) else s + "*"


def ratios(curves, have_sympy, have_simbody):
    rows, md = [], []
    md.append("| problem | error | Appell best | time | limit best | time | Appell/limit | "
              "SymPy+SciPy best | time | Appell/SymPy | Simbody best | time | "
              "Appell/Simbody |")
    md.append("|" + "---|" * 13)
    for p in PROBLEMS:
        for E in LEVELS:
            ours = best_of(curves, p, ("appell",), E)
            lim = best_of(curves, p, ("hand",), E)
            sp = best_of(curves, p, ("sympy_scipy",), E)
            sb = best_of(curves, p, ("simbody",), E)
            row = {"problem": p, "error": f"{E:.0e}"}
            for name, v in (("appell", ours), ("limit", lim), ("sympy", sp), ("simbody", sb)):
                row[name + "_curve"] = label(v[2]) if v else ""
                row[name + "_s"] = f"{v[0]:.4e}" if v else ""
                row[name + "_exact"] = (1 if v[1] else 0) if v else ""
            for name, v in (("limit", lim), ("sympy", sp), ("simbody", sb)):
                row["appell_over_" + name] = f"{ours[0] / v[0]:.4g}" if ours and v else ""
            rows.append(row)
            if E not in SHOW:
                continue
            sp_txt = ("absent", "", "") if not have_sympy else (
                label(sp[2]).replace("SymPy+SciPy ", "") if sp else "-", fmt_t(sp),
                fmt_r(ours, sp))
            if p.startswith("turntable") and have_simbody:
                sb_txt = (label(sb[2]).replace("Simbody ", "") if sb else "-", fmt_t(sb),
                          fmt_r(ours, sb))
            elif p.startswith("turntable"):
                sb_txt = ("absent", "", "")
            else:
                sb_txt = ("n/a", "", "")
            md.append(f"| {p} | {E:.0e} | "
                      f"{label(ours[2]).replace('Appell ', '') if ours else '-'} | "
                      f"{fmt_t(ours)} | "
                      f"{label(lim[2]).replace('limit (hand ODE) ', '') if lim else '-'} | "
                      f"{fmt_t(lim)} | {fmt_r(ours, lim)} | "
                      f"{sp_txt[0]} | {sp_txt[1]} | {sp_txt[2]} | "
                      f"{sb_txt[0]} | {sb_txt[1]} | {sb_txt[2]} |")
    return rows, md


# Steppers of the same order on both sides: dopri5 (5(4)) against RungeKuttaFeldberg (4(5)),
# bs3 (3(2)) against RungeKutta3 (3(2)).
SAME_ORDER = (("dopri5", "rkfeldberg"), ("bs3", "rk3"))


def body_ratios(curves):
    """Appell's ball built from bodies against Simbody's (both body models), at equal achieved
    error: each side's best stepper, and steppers of the same order; when bench_wp --compiled
    ran, also the ball with compiled kinematics (orientation free) against Simbody."""
    comp = any(k[1] == "appell_body_c" for k in curves)
    symp = any(k[1] == "sympy_scipy" and k[0].startswith("turntable") for k in curves)
    ccols = " Appell body compiled best (orientation free) | time | Simbody / compiled |"
    md = ["| problem | error | Appell body best (orientation free) | time | Appell body best "
          "(all controlled) | time | Simbody best | time | Simbody / Appell body | "
          + " | ".join(f"Simbody {b} / Appell {a}" for a, b in SAME_ORDER) + " |"
          + (ccols if comp else "")
          + (" SymPy+SciPy best | time | SymPy / Appell body |" if symp else "")
          + (" SymPy / compiled |" if symp and comp else ""),
          "|" + "---|" * (9 + len(SAME_ORDER) + (3 if comp else 0) + (3 if symp else 0)
                          + (1 if symp and comp else 0))]
    allr, allc, alls, allsc = [], [], [], []
    for p in ("turntable", "turntable_var"):
        for E in LEVELS:
            def best(mode=None, meth=None, tool="appell_body"):
                b = None
                for key, pts in curves.items():
                    if key[0] != p or key[1] != tool or (mode and key[2] != mode) or \
                       (meth and key[3] != meth):
                        continue
                    t, ex = time_at(pts, E)
                    if t is not None and (b is None or t < b[0]):
                        b = (t, ex, key)
                return b
            free, full = best("minimal_free"), best("minimal")
            sb = best(tool="simbody")
            if free and sb:
                allr.append(sb[0] / free[0])
            same = [fmt_r(best(tool="simbody", meth=b), best("minimal_free", a))
                    for a, b in SAME_ORDER]
            md.append(f"| {p} | {E:.0e} | {label(free[2])[12:] if free else '-'} | "
                      f"{fmt_t(free)} | {label(full[2])[12:] if full else '-'} | "
                      f"{fmt_t(full)} | {label(sb[2])[8:] if sb else '-'} | {fmt_t(sb)} | "
                      f"{fmt_r(sb, free)} | " + " | ".join(same) + " |")
            if comp:
                c = best("minimal_free", tool="appell_body_c")
                if c and sb:
                    allc.append(sb[0] / c[0])
                md[-1] += (f" {label(c[2])[21:] if c else '-'} | {fmt_t(c)} | "
                           f"{fmt_r(sb, c)} |")
            if symp:
                sp = best(tool="sympy_scipy")
                if sp and free:
                    alls.append(sp[0] / free[0])
                md[-1] += (f" {label(sp[2])[12:] if sp else '-'} | {fmt_t(sp)} | "
                           f"{fmt_r(sp, free)} |")
                if comp:
                    if sp and c:
                        allsc.append(sp[0] / c[0])
                    md[-1] += f" {fmt_r(sp, c)} |"
    return md, allr, allc, alls, allsc


def overhead(curves):
    """Appell (each mode) / hand-reduced ODE under the same stepper at equal error."""
    rows, per = [], {}
    for p in PROBLEMS:
        for mode in ("minimal", "projected"):
            for m in STEPPERS:
                a = curves.get((p, "appell", mode, m))
                h = curves.get((p, "hand", "reduced", m))
                if not a or not h:
                    continue
                for E in LEVELS:
                    ta, ea = time_at(a, E)
                    th, eh = time_at(h, E)
                    if ta is None or th is None:
                        continue
                    r = ta / th
                    rows.append({"problem": p, "mode": mode, "method": m, "error": f"{E:.0e}",
                                 "appell_s": f"{ta:.4e}", "hand_s": f"{th:.4e}",
                                 "ratio": f"{r:.4g}", "exact": int(ea and eh)})
                    per.setdefault((p, mode, m), []).append(r)
    md = ["| problem | mode | " + " | ".join(STEPPERS) + " |",
          "|---|---|" + "---|" * len(STEPPERS)]
    for p in PROBLEMS:
        for mode in ("minimal", "projected"):
            cells = []
            for m in STEPPERS:
                v = per.get((p, mode, m))
                cells.append(f"{statistics.median(v):.1f} ({min(v):.1f}-{max(v):.1f})" if v
                             else "-")
            md.append(f"| {p} | {mode} | " + " | ".join(cells) + " |")
    allr = [r for v in per.values() for r in v]
    return rows, md, allr


def per_eval(rows_all):
    """Median µs per right-hand-side evaluation (runs with > 200 evaluations) per tool."""
    acc = {}
    for r in rows_all:
        if int(r["status"]) != 0 or int(r["rhs_evals"]) < 200:
            continue
        tool = r["tool"] if r["tool"] != "appell" else "appell " + r["mode"]
        acc.setdefault((r["problem"], tool), []).append(float(r["us_per_eval"]))
    tools = ["appell minimal", "appell projected", "appell dae", "hand", "sympy_scipy",
             "simbody", "appell_body"] + (["appell_body_c"] if any(
                 r["tool"] == "appell_body_c" for r in rows_all) else [])
    md = ["| problem | " + " | ".join(tools) + " |", "|---|" + "---|" * len(tools)]
    for p in PROBLEMS:
        cells = [f"{statistics.median(acc[(p, t)]):.2f}" if (p, t) in acc else "-"
                 for t in tools]
        md.append(f"| {p} | " + " | ".join(cells) + " |")
    return md


def write_csv(path, rows):
    if not rows:
        return
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)


def style(key, idx):
    _, tool, mode, meth = key
    if tool == "appell":
        dt = {"minimal": 1, "projected": 2, "dae": 1}[mode]
        return f"lt {COLOR.get(meth, 8)} dt {dt} lw {2.5 if mode == 'dae' else 1.5}"
    if tool in ("appell_body", "appell_body_c"):
        pt = 7 if tool == "appell_body" else 13
        dt = 1 if mode == 'minimal_free' else 5
        return f"lt {COLOR.get(meth, 8)} dt {dt} lw 3 pt {pt} ps 0.6"
    if tool == "hand":
        return f"lt {COLOR.get(meth, 8)} dt 3 lw 1 pt 6 ps 0.5"
    if tool == "sympy_scipy":
        return ("lc rgb '#000000' dt 1 lw 3 pt 5 ps 0.8" if meth == "DOP853"
                else "lc rgb '#777777' dt 1 lw 3 pt 5 ps 0.8")
    grey = {"rkmerson": "#556b2f", "rkfeldberg": "#9acd32", "rk3": "#bdb76b",
            "cpodes": "#808000"}
    return f"lc rgb '{grey.get(meth, '#556b2f')}' dt 4 lw 3 pt 9 ps 0.9"


def plots(out, curves, gp_common):
    tmp = os.path.join(out, "tmp")
    os.makedirs(tmp, exist_ok=True)
    order = {"appell": 0, "hand": 1, "sympy_scipy": 2, "simbody": 3}
    made = []
    for p in PROBLEMS:
        keys = sorted((k for k in curves if k[0] == p),
                      key=lambda k: (order.get(k[1], 9), MODE_ORDER.get(k[2], 9),
                                     STEPPERS.index(k[3]) if k[3] in STEPPERS else 99, k[3]))
        if not keys:
            continue
        dat = os.path.join(tmp, f"wp_{p}.dat")
        with open(dat, "w") as f:
            for k in keys:
                f.write(f"# {label(k)}\n")
                for e, t in curves[k]:
                    f.write(f"{t:.6e} {e:.6e}\n")
                f.write("\n\n")
        for term, ext in (("pngcairo size 1400,900 font ',10'", "png"),
                          ("svg size 1400,900 font 'sans,10'", "svg")):
            cmds = [f"load '{gp_common}'", f"set terminal {term}",
                    f"set output '{os.path.join(out, f'wp_{p}.{ext}')}'",
                    f"set title \"{TITLES[p]}\""]
            plot = [f"'{dat}' index {i} using 1:2 with linespoints {style(k, i)} "
                    f"title \"{label(k)}\"" for i, k in enumerate(keys)]
            cmds.append("plot " + ", \\\n  ".join(plot))
            cmds.append("unset output")
            r = subprocess.run(["gnuplot"], input="\n".join(cmds) + "\n", text=True,
                               capture_output=True)
            if r.returncode != 0:
                print(f"report: gnuplot failed for {p}: {r.stderr.strip()}", file=sys.stderr)
                break
        else:
            made.append(p)
    return made


def main():
    if len(sys.argv) < 2:
        print(__doc__, file=sys.stderr)
        return 2
    out = sys.argv[1]
    rows = read_rows(os.path.join(out, "wp_appell.csv"))
    if not rows:
        print(f"report: no {out}/wp_appell.csv", file=sys.stderr)
        return 1
    rows += read_rows(os.path.join(out, "wp_appell_compiled.csv"))
    sp = read_rows(os.path.join(out, "wp_sympy.csv"))
    sb = read_rows(os.path.join(out, "wp_simbody.csv"))
    curves = curves_of(rows + sp + sb)
    rrows, rmd = ratios(curves, bool(sp), bool(sb))
    orows, omd, allr = overhead(curves)
    write_csv(os.path.join(out, "ratios.csv"), rrows)
    write_csv(os.path.join(out, "overhead.csv"), orows)
    md = ["## Best curve of each tool at equal achieved error", "",
          "Time = CPU time of one run to reach the error (interpolated in log-log between "
          "sweep points). `<=`: upper bound (the loosest tolerance already overshoots); `*`: "
          "ratio involving such a bound.", ""] + rmd
    if sb:
        bmd, ballr, ballc, balls, ballsc = body_ratios(curves)
        md += ["", "## Body-built models: Appell's ball against Simbody's ball", "",
               "Both sides build the ball on the turntable from bodies (Appell: "
               "tests/bodysys.c; Simbody: bench/peers/simbody_turntable.cc). Appell with its "
               "orientation left out of the error control (appell run's default) and with "
               "every coordinate controlled. Ratios > 1: Appell is faster.", ""] + bmd
        if ballr:
            md += ["", f"Simbody / Appell body (orientation free), best against best, over "
                   f"{len(ballr)} levels: {min(ballr):.0f} ... {max(ballr):.0f}, median "
                   f"{statistics.median(ballr):.0f}."]
        if ballc:
            md += ["", f"Simbody / Appell body compiled (orientation free), best against best, "
                   f"over {len(ballc)} levels: {min(ballc):.0f} ... {max(ballc):.0f}, median "
                   f"{statistics.median(ballc):.0f}."]
        if balls:
            md += ["", f"SymPy+SciPy (KanesMethod on a RigidBody ball, solve_ivp) / Appell body "
                   f"(orientation free), best against best, over {len(balls)} levels: "
                   f"{min(balls):.0f} ... {max(balls):.0f}, median "
                   f"{statistics.median(balls):.0f}."]
        if ballsc:
            md += ["", f"SymPy+SciPy / Appell body compiled (orientation free), best against "
                   f"best, over {len(ballsc)} levels: {min(ballsc):.0f} ... {max(ballsc):.0f}, "
                   f"median {statistics.median(ballsc):.0f}."]
    md += ["", "## Appell / hand-reduced ODE under the same stepper",
           "", "Median (min-max) over the error levels 1e-4 ... 1e-10 that both reach.", ""]
    md += omd
    if allr:
        md += ["", f"Over all {len(allr)} (problem, mode, stepper, level) pairs: median "
               f"{statistics.median(allr):.1f}, min {min(allr):.1f}, max {max(allr):.1f}."]
    md += ["", "## Cost per right-hand-side evaluation (µs, median over runs with > 200 "
           "evaluations; includes the stepper's own work per evaluation)", ""]
    md += per_eval(rows + sp + sb)
    build = read_rows(os.path.join(out, "sympy_build.csv"))
    if build:
        md += ["", "## SymPy model building and one evaluation of its right-hand side", "",
               "| problem | KanesMethod + kanes_equations (s) | lambdify (s) | "
               "rhs call (µs, min-max) | state |", "|---|---|---|---|---|"]
        for b in build:
            md.append(f"| {b['problem']} | {float(b['kane_s']):.3f} | "
                      f"{float(b['lambdify_s']):.3f} | {float(b['rhs_us']):.1f} "
                      f"({float(b['rhs_lo_us']):.1f}-{float(b['rhs_hi_us']):.1f}) | "
                      f"{b['state_size']} |")
    if sb:
        md += ["", "## Simbody constraint drift at the output times (largest over the run)",
               "", "| problem | integrator | accuracy | error | |qErr| | |uErr| | "
               "no-slip residual |", "|---|---|---|---|---|---|---|"]
        for r in sb:
            if int(r["status"]) == 0:
                md.append(f"| {r['problem']} | {r['method']} | {r['tol']} | "
                          f"{float(r['err']):.1e} | {float(r['qerr']):.1e} | "
                          f"{float(r['uerr']):.1e} | {float(r['residual']):.1e} |")
    with open(os.path.join(out, "summary.md"), "w") as f:
        f.write("\n".join(md) + "\n")
    print("\n".join(md))
    if "--no-plots" not in sys.argv:
        if shutil.which("gnuplot"):
            gp = os.path.join(os.path.dirname(os.path.abspath(__file__)), "wp.gp")
            made = plots(out, curves, gp)
            print(f"\nreport: plots for {', '.join(made)} in {out}")
        else:
            print("report: gnuplot not found; no plots", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
