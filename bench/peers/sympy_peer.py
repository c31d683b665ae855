#!/usr/bin/python3
"""What Python users do today: SymPy physics.mechanics (KanesMethod with the nonholonomic
constraints) + SciPy solve_ivp, on the problems bench_wp describes.

Each problem is modelled the way the SymPy documentation teaches: coordinates q, generalized
speeds u chosen so that the no-slip / no-sideways-velocity rows name single speeds (which
KanesMethod then takes as dependent), kinematic differential equations, bodies and loads,
kanes_equations(); then mass_matrix_full and forcing_full are lambdified (cse=True) and the
right-hand side solves M(q, u, t) y' = F(q, u, t) with numpy.linalg.solve. The state is
(q, u) with every speed, dependent ones included; the velocity constraints are not enforced
after t = 0 (only their time derivative is), so the script reports their drift.

Per problem it measures
  * the model-building time: KanesMethod + kanes_equations, and lambdify, in CPU seconds;
  * the cost of one right-hand-side evaluation (median of 31 blocks, min, max, in µs);
  * a work-precision sweep: solve_ivp with DOP853 and RK45 at rtol = atol = 1e-2 ... 1e-12,
    t_eval = the output times, recording the largest position error against the exact values
    bench_wp wrote, CPU time (time.process_time, median of repeats for runs under 50 ms),
    right-hand-side evaluations and the largest velocity-constraint residual.
A curve stops going tighter once a run costs more than --budget seconds.

Usage: /usr/bin/python3 sympy_peer.py PROBLEMS_FILE --csv WP.csv --build-csv BUILD.csv
       [--budget S] [--quick] [--problems a,b]
Run with OPENBLAS_NUM_THREADS=1 (numpy's BLAS).
"""
import argparse
import math
import sys
import time

import numpy as np
import scipy
import sympy as sm
import sympy.physics.mechanics as me
from scipy.integrate import solve_ivp


def read_problems(path):
    probs = {}
    with open(path) as f:
        for line in f:
            if not line.strip() or line.startswith("#"):
                continue
            w = line.split()
            p = probs.setdefault(w[0], {"name": w[0], "param": {}, "exact": []})
            key, vals = w[1], w[2:]
            if key == "T":
                p["T"] = float(vals[0])
            elif key in ("nout", "npos"):
                p[key] = int(vals[0])
            elif key == "param":
                for i in range(0, len(vals), 2):
                    p["param"][vals[i]] = float(vals[i + 1])
            elif key in ("q0", "v0", "euler"):
                p[key] = [float(v) for v in vals]
            elif key == "exact":
                p["exact"].append([float(v) for v in vals])
    return probs


# ---- models ------------------------------------------------------------------------------
# Each returns (kane, q, u, velocity constraints, parameter symbols, initial state function).

t = me.dynamicsymbols._t


def planar_blade(name, with_offset):
    """Knife edge (with_offset False) or Chaplygin sleigh (True): contact point P at (x, y),
    heading th; u1 along the blade, u2 sideways (= 0 by the constraint), u3 = th'."""
    x, y, th = me.dynamicsymbols("x y th")
    u1, u2, u3 = me.dynamicsymbols("u1 u2 u3")
    m, J, G, a, I = sm.symbols("m J G a I")
    N = me.ReferenceFrame("N")
    B = N.orientnew("B", "Axis", [th, N.z])
    B.set_ang_vel(N, u3 * N.z)
    O = me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", x * N.x + y * N.y)
    P.set_vel(N, u1 * B.x + u2 * B.y)
    kd = [x.diff(t) - (u1 * sm.cos(th) - u2 * sm.sin(th)),
          y.diff(t) - (u1 * sm.sin(th) + u2 * sm.cos(th)),
          th.diff(t) - u3]
    if with_offset:                       # sleigh: centre of mass a ahead of P, inertia I
        C = P.locatenew("C", a * B.x)
        C.v2pt_theory(P, N, B)
        body = me.RigidBody("sleigh", C, B, m, (me.inertia(B, 0, 0, I), C))
        loads = []
        syms = [m, I, a]
    else:                                 # knife: mass at P, inertia J, gravity down slope
        body = me.RigidBody("blade", P, B, m, (me.inertia(B, 0, 0, J), P))
        loads = [(P, m * G * N.x)]
        syms = [m, J, G]
    vc = [u2]
    kane = me.KanesMethod(N, q_ind=[x, y, th], u_ind=[u1, u3], kd_eqs=kd,
                          u_dependent=[u2], velocity_constraints=vc)
    kane.kanes_equations([body], loads)

    def initial(q0, v0):
        c, s = math.cos(q0[2]), math.sin(q0[2])
        return [q0[0], q0[1], q0[2], v0[0] * c + v0[1] * s, -v0[0] * s + v0[1] * c, v0[2]]

    return kane, [x, y, th], [u1, u2, u3], vc, syms, initial


def turntable():
    """Ball on a turntable: centre (x, y), angular velocity (wx, wy, wz) = (u3, u4, u5) in N;
    the a_i integrate the angular-velocity components (Appell's math-level form). No-slip at
    the contact relative to the table rotating at Omega(t) = Omega0 + dOmega t."""
    q = me.dynamicsymbols("x y a1 a2 a3")
    u = me.dynamicsymbols("u1:6")
    m, R, kI, W0, dW = sm.symbols("m R kI Omega0 dOmega")
    N = me.ReferenceFrame("N")
    B = me.ReferenceFrame("B")
    B.set_ang_vel(N, u[2] * N.x + u[3] * N.y + u[4] * N.z)
    O = me.Point("O")
    O.set_vel(N, 0)
    C = O.locatenew("C", q[0] * N.x + q[1] * N.y)
    C.set_vel(N, u[0] * N.x + u[1] * N.y)
    In = kI * m * R**2
    ball = me.RigidBody("ball", C, B, m, (me.inertia(N, In, In, In), C))
    Om = W0 + dW * t
    vc = [u[0] - R * u[3] + Om * q[1], u[1] + R * u[2] - Om * q[0]]
    kd = [q[i].diff(t) - u[i] for i in range(5)]
    kane = me.KanesMethod(N, q_ind=list(q), u_ind=list(u[2:]), kd_eqs=kd,
                          u_dependent=list(u[:2]), velocity_constraints=vc)
    kane.kanes_equations([ball], [])

    def initial(q0, v0):
        return list(q0) + list(v0)

    return kane, list(q), list(u), vc, [m, R, kI, W0, dW], initial


def rotating_line():
    """Bead at p = (X, Y, Z); speeds along d (the line), n1 and n2 (its normals), which turn
    about N.z at w; the rows n_i . p' + n_i' . p = 0 make u2, u3 dependent."""
    q = me.dynamicsymbols("X Y Z")
    u = me.dynamicsymbols("u1:4")
    m, g, al, w = sm.symbols("m g alpha w")
    N = me.ReferenceFrame("N")
    L = N.orientnew("L", "Axis", [w * t, N.z])
    d = sm.sin(al) * L.x + sm.cos(al) * L.z
    n1 = L.y
    n2 = sm.cos(al) * L.x - sm.sin(al) * L.z
    O = me.Point("O")
    O.set_vel(N, 0)
    p = q[0] * N.x + q[1] * N.y + q[2] * N.z
    P = O.locatenew("P", p)
    vel = u[0] * d + u[1] * n1 + u[2] * n2
    P.set_vel(N, vel)
    kd = [q[i].diff(t) - vel.dot(e) for i, e in enumerate((N.x, N.y, N.z))]
    vc = [u[1] + n1.diff(t, N).dot(p), u[2] + n2.diff(t, N).dot(p)]
    kane = me.KanesMethod(N, q_ind=list(q), u_ind=[u[0]], kd_eqs=kd,
                          u_dependent=[u[1], u[2]], velocity_constraints=vc)
    kane.kanes_equations([me.Particle("bead", P, m)], [(P, -m * g * N.z)])

    return kane, list(q), list(u), vc, [m, g, al, w], None   # initial state: see build()


def rolling_disk():
    """Thin uniform disk rolling on the plane (bench_wp's frames): heading psi, lean th from
    upright, spin phi; lean frame L (L.y the disk axis, C - P = r L.z); u1, u2, u3 the disk's
    angular velocity in L; u4, u5 the centre's horizontal velocity along Y.x, Y.y, which the
    two rolling rows make dependent."""
    psi, th, phi, x, y = me.dynamicsymbols("psi th phi x y")
    u = me.dynamicsymbols("u1:6")
    m, r, g = sm.symbols("m r g")
    N = me.ReferenceFrame("N")
    Y = N.orientnew("Y", "Axis", [psi, N.z])
    L = Y.orientnew("L", "Axis", [th, Y.x])
    D = L.orientnew("D", "Axis", [phi, L.y])
    D.set_ang_vel(N, u[0] * L.x + u[1] * L.y + u[2] * L.z)
    O = me.Point("O")
    O.set_vel(N, 0)
    C = O.locatenew("C", x * N.x + y * N.y + r * sm.cos(th) * N.z)
    C.set_vel(N, u[3] * Y.x + u[4] * Y.y - r * sm.sin(th) * u[0] * N.z)
    kd = [psi.diff(t) - u[2] / sm.cos(th), th.diff(t) - u[0],
          phi.diff(t) - (u[1] - u[2] * sm.tan(th)),
          x.diff(t) - (u[3] * sm.cos(psi) - u[4] * sm.sin(psi)),
          y.diff(t) - (u[3] * sm.sin(psi) + u[4] * sm.cos(psi))]
    vc = [u[3] - r * u[1], u[4] + r * u[0] * sm.cos(th)]
    A, Cax = m * r**2 / 4, m * r**2 / 2
    disk = me.RigidBody("disk", C, D, m, (me.inertia(L, A, Cax, A), C))
    kane = me.KanesMethod(N, q_ind=[psi, th, phi, x, y], u_ind=list(u[:3]), kd_eqs=kd,
                          u_dependent=list(u[3:]), velocity_constraints=vc)
    kane.kanes_equations([disk], [(C, -m * g * N.z)])
    return kane, [psi, th, phi, x, y], list(u), vc, [m, r, g], None


def build(name, prm, prob):
    """Build the model, lambdify it; return the numeric pieces and the build times."""
    t0 = time.process_time()
    if name == "knife_edge":
        kane, q, u, vc, syms, initial = planar_blade(name, False)
        vals = [prm["m"], prm["J"], prm["grav"] * math.sin(prm["alpha"])]
    elif name == "sleigh":
        kane, q, u, vc, syms, initial = planar_blade(name, True)
        vals = [prm["m"], prm["I"], prm["a"]]
    elif name.startswith("turntable"):
        kane, q, u, vc, syms, initial = turntable()
        vals = [prm["m"], prm["R"], prm["kI"], prm["Omega0"], prm["dOmega"]]
    elif name == "rolling_disk":
        kane, q, u, vc, syms, initial = rolling_disk()
        vals = [prm["m"], prm["r"], prm["grav"]]
        eu, r = prob["euler"], prm["r"]

        def initial(q0, v0):   # from x, y, psi, theta, w1, w2, w3 (bench_wp's disk_hand)
            return [eu[2], eu[3], 0.0, eu[0], eu[1], eu[4], eu[5], eu[6], r * eu[5],
                    -r * eu[4] * math.cos(eu[3])]
    else:
        kane, q, u, vc, syms, initial = rotating_line()
        vals = [prm["m"], prm["grav"], prm["alpha"], prm["w"]]
        al, w = prm["alpha"], prm["w"]

        def initial(q0, v0):   # speeds along d, n1, n2 at t = 0 (the line in the xz plane)
            d = (math.sin(al), 0.0, math.cos(al))
            n1 = (0.0, 1.0, 0.0)
            n2 = (math.cos(al), 0.0, -math.sin(al))
            dot = lambda e: sum(e[i] * v0[i] for i in range(3))
            return list(q0) + [dot(d), dot(n1), dot(n2)]
    M, F = kane.mass_matrix_full, kane.forcing_full
    t_kane = time.process_time() - t0
    # The state follows KanesMethod's own order (independent speeds first), which is the
    # order of the rows and columns of M and F.
    order = [(q + u).index(s) for s in list(kane.q) + list(kane.u)]
    # positions compared: x, y (and Z) among the coordinates, in state order
    pos_names = {"rolling_disk": ["x", "y"]}.get(name)
    pos_idx = ([list(kane.q).index(me.dynamicsymbols(n)) for n in pos_names] if pos_names
               else [list(kane.q).index(s) for s in q[:3]])
    t0 = time.process_time()
    args = [t] + list(kane.q) + list(kane.u) + syms
    mf = sm.lambdify(args, [M, F], modules="numpy", cse=True)
    vcf = sm.lambdify(args, vc, modules="numpy", cse=True)
    t_lamb = time.process_time() - t0
    prmv = tuple(vals)

    def rhs(tt, y):
        Mn, Fn = mf(tt, *y, *prmv)
        return np.linalg.solve(Mn, Fn).ravel()

    def residual(tt, y):
        return max(abs(float(r)) for r in vcf(tt, *y, *prmv))

    def initial_ordered(q0, v0):
        y = initial(q0, v0)
        return [y[i] for i in order]

    return rhs, residual, initial_ordered, t_kane, t_lamb, len(q) + len(u), pos_idx


def median_blocks(fn, blocks=31, reps=200):
    for _ in range(reps):
        fn()
    ts = []
    for _ in range(blocks):
        t0 = time.process_time()
        for _ in range(reps):
            fn()
        ts.append((time.process_time() - t0) / reps)
    ts.sort()
    return ts[len(ts) // 2], ts[0], ts[-1]


def one_run(rhs, residual, y0, prob, method, tol, pos_idx):
    T = prob["T"]
    tev = [e[0] for e in prob["exact"]]
    sol = solve_ivp(rhs, (0.0, T), y0, method=method, t_eval=tev, rtol=tol, atol=tol)
    npos = prob["npos"]
    if not sol.success or sol.y.shape[1] != len(tev):
        return False, math.inf, sol.nfev, 0.0, sol.message
    err = 0.0
    res = 0.0
    for i, e in enumerate(prob["exact"]):
        for c in range(npos):
            err = max(err, abs(sol.y[pos_idx[c], i] - e[1 + c]))
        res = max(res, residual(tev[i], sol.y[:, i]))
    if not math.isfinite(err):
        err = math.inf
    return True, err, sol.nfev, res, ""


def measure(rhs, residual, y0, prob, method, tol, pos_idx):
    t0 = time.process_time()
    ok, err, nfev, res, msg = one_run(rhs, residual, y0, prob, method, tol, pos_idx)
    ts = [time.process_time() - t0]
    first = 0
    if ok and ts[0] < 0.05:
        reps = min(15, max(3, int(0.15 / max(ts[0], 1e-9))))
        first = 1
        for _ in range(reps):
            t0 = time.process_time()
            one_run(rhs, residual, y0, prob, method, tol, pos_idx)
            ts.append(time.process_time() - t0)
    tt = sorted(ts[first:])
    return ok, err, nfev, res, msg, tt[len(tt) // 2], tt[0], tt[-1], len(tt)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("problems")
    ap.add_argument("--csv", required=True)
    ap.add_argument("--build-csv", required=True)
    ap.add_argument("--budget", type=float, default=1.5)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--problems", dest="only", default=None)
    a = ap.parse_args()
    probs = read_problems(a.problems)
    print(f"SymPy {sm.__version__}, SciPy {scipy.__version__}, NumPy {np.__version__}, "
          f"Python {sys.version.split()[0]} ({sys.executable})", flush=True)
    out = open(a.csv, "w")
    out.write("problem,tool,mode,method,tol,h,status,err,cpu_s,cpu_lo,cpu_hi,reps,steps,"
              "rhs_evals,err_fails,us_per_eval,residual\n")
    bout = open(a.build_csv, "w")
    bout.write("problem,kane_s,lambdify_s,rhs_us,rhs_lo_us,rhs_hi_us,state_size\n")
    for name, prob in probs.items():
        if a.only and name not in a.only.split(","):
            continue
        rhs, residual, initial, t_kane, t_lamb, ny, pos_idx = build(name, prob["param"], prob)
        y0 = np.array(initial(prob["q0"], prob["v0"]), dtype=float)
        med, lo, hi = median_blocks(lambda: rhs(0.3, y0))
        print(f"{name}: KanesMethod + kanes_equations {t_kane:.2f} s, lambdify {t_lamb:.2f} s, "
              f"rhs {1e6 * med:.1f} us ({1e6 * lo:.1f} .. {1e6 * hi:.1f}), state {ny}",
              flush=True)
        bout.write(f"{name},{t_kane:.4f},{t_lamb:.4f},{1e6 * med:.3f},{1e6 * lo:.3f},"
                   f"{1e6 * hi:.3f},{ny}\n")
        bout.flush()
        for method in ("DOP853", "RK45"):
            for i in range(0, 11, 3 if a.quick else 1):
                tol = 10.0 ** (-2 - i)
                ok, err, nfev, res, msg, cpu, clo, chi, reps = measure(
                    rhs, residual, y0, prob, method, tol, pos_idx)
                print(f"  {name:13s} sympy+scipy {method:7s} {tol:8.1e} {err:8.2e} "
                      f"{cpu:9.3e} s {reps:3d} {nfev:8d} evals "
                      f"{1e6 * cpu / max(nfev, 1):7.2f} us/eval drift {res:.1e}"
                      + ("" if ok else f"  FAILED: {msg}"), flush=True)
                out.write(f"{name},sympy_scipy,kane,{method},{tol:.3g},0,{0 if ok else -1},"
                          f"{err:.6e},{cpu:.6e},{clo:.6e},{chi:.6e},{reps},-1,{nfev},-1,"
                          f"{1e6 * cpu / max(nfev, 1):.4f},{res:.3e}\n")
                out.flush()
                if not ok or cpu > a.budget or err < 1e-13:
                    break
    out.close()
    bout.close()


if __name__ == "__main__":
    main()
