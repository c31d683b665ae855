"""The Whipple bicycle at 3 m/s, below its weave speed (the weave pair 1.71 +- 2.32j is
unstable there), held upright by an LQR steer-torque controller computed from the
linearization and run on the nonlinear model in the loop, sampled every 1 ms (zero-order hold).

    python3 examples/python/bicycle_lqr.py [--speed 3] [--period 0.001] [--lean 0.005]

1. appell.linearize gives A and B about upright straight running; B's column is the scene's
   input, the steer torque T_delta on front_frame.angle_dot (the inputs: the load sets).
2. K = R^-1 B^T P with P from the Riccati equation (SciPy's solve_continuous_are when SciPy is
   installed, else the stable invariant subspace of the Hamiltonian matrix, in NumPy).
3. The nonlinear run from a small lean: sim.run(controller=f, period=T), f(t, state) = -K x
   with x = (lean, steer, roll rate, steer rate) measured from the state.
4. The measured decay rate: the run's state projected on the closed loop's slowest mode
   (its left eigenvector w: w^T x(t) = c exp(lambda t) for the linear system) gives lambda from
   two times; predicted: the eigenvalues of the sampled closed loop
   Phi - Gamma K (Phi = e^{A T}, Gamma = int_0^T e^{A s} ds B), log(mu) / T, and of A - B K."""

import argparse
import math

import numpy as np

import appell

STATES = ("rear_frame.tilt", "front_frame.angle", "rear_frame.wx", "front_frame.angle_dot")
INPUTS = "[front_frame.angle_dot]"     # the steer torque T_delta (N m), the column of B


def load_bicycle(scene, lean, speed):
    sets = {"inputs": INPUTS, "initial.rear_frame.tilt": f"90*deg + {lean!r}",
            "initial.rear_frame.tilt_rate": 0, "initial.rear_wheel.rate": f"{speed!r}/0.3"}
    return appell.load(scene, set=sets)


def riccati(A, B, Q, R):
    """P of A^T P + P A - P B R^-1 B^T P + Q = 0 (stabilizing solution)."""
    try:
        from scipy.linalg import solve_continuous_are
        return solve_continuous_are(A, B, Q, R)
    except ImportError:
        pass
    n = A.shape[0]
    H = np.block([[A, -B @ np.linalg.solve(R, B.T)], [-Q, -A.T]])
    w, V = np.linalg.eig(H)
    U = V[:, w.real < 0]                 # the stable invariant subspace (n columns)
    P = np.real(U[n:] @ np.linalg.inv(U[:n]))
    return 0.5 * (P + P.T)


def expm(M, terms=30):
    """e^M by scaling and squaring of its Taylor series (M small here: |A T| ~ 0.01)."""
    s = max(0, int(math.ceil(math.log2(max(np.abs(M).sum(axis=1).max(), 1e-300)))) + 1)
    X = M / 2.0**s
    E, term = np.eye(M.shape[0]), np.eye(M.shape[0])
    for j in range(1, terms):
        term = term @ X / j
        E = E + term
    for _ in range(s):
        E = E @ E
    return E


def design(bike, speed, period):
    """A, B (the four lean/steer states), K, and the closed-loop eigenvalues: continuous
    (A - B K) and sampled with zero-order hold."""
    lin = appell.linearize(bike, speed=speed, inputs=("front_frame.angle_dot",))
    A, B = lin.block(STATES), lin.block(STATES, matrix="B")
    Q = np.diag([1 / 0.01**2, 1 / 0.02**2, 1 / 0.1**2, 1 / 0.2**2])   # lean 0.01 rad, ...
    R = np.array([[1 / 2.0**2]])                                       # steer torque 2 N m
    K = np.linalg.solve(R, B.T @ riccati(A, B, Q, R))
    n, m = B.shape
    E = expm(np.block([[A, B], [np.zeros((m, n + m))]]) * period)
    Phi, Gamma = E[:n, :n], E[:n, n:]
    Md = Phi - Gamma @ K                    # x_{j+1} = Md x_j: the sampled closed loop
    mu = np.linalg.eigvals(Md)
    return {"A": A, "B": B, "K": K, "Md": Md, "open": np.linalg.eigvals(A),
            "continuous": np.linalg.eigvals(A - B @ K),
            "sampled": np.log(mu.astype(complex)) / period}


def measured_state(s):
    """x = (lean, steer, roll rate, steer rate) of the linearization from the nonlinear state:
    the lean is the Z-X-Z tilt minus 90 deg; the roll rate is the rear frame's angular velocity
    along its heading (the linearization's speeds are taken in the heading frame)."""
    h = s["rear_frame.heading"]
    roll_rate = s["rear_frame.wx"] * math.cos(h) + s["rear_frame.wy"] * math.sin(h)
    return np.array([s["rear_frame.tilt"] - math.pi / 2, s["front_frame.angle"], roll_rate,
                     s["front_frame.angle_dot"]])


def run(scene, speed=3.0, period=0.001, lean=0.005, t_end=4.0):
    bike = load_bicycle(scene, lean, speed)
    d = design(bike, speed, period)
    K = d["K"]

    def controller(t, state):
        x = measured_state(state)
        return -K @ x                       # one value per input: the steer torque

    sim = appell.Simulation(bike)
    res = sim.run(t_end, 0.01, controller=controller, period=period)
    X = np.array([measured_state({c: res[c][i] for c in
                                  ("rear_frame.heading", "rear_frame.wx", "rear_frame.wy",
                                   "rear_frame.tilt", "front_frame.angle",
                                   "front_frame.angle_dot")}) for i in range(len(res))])
    # The slowest mode of the sampled closed loop (largest |mu|), from its left eigenvector w:
    # w^T x_j = c mu^j exactly for the linear sampled system, at the instants j T (the rows
    # at 1 s and 2 s are instants); its rate log|mu| / T is the prediction.
    mu, W = np.linalg.eig(d["Md"].T)
    i = int(np.argmax(np.abs(mu)))
    z = X @ W[:, i]
    t = res.t
    a, b = np.searchsorted(t, 1.0 - 1e-9), np.searchsorted(t, 2.0 - 1e-9)
    rate = np.log(np.abs(z[b]) / np.abs(z[a])) / (t[b] - t[a])
    return d, res, X, rate, np.log(abs(mu[i])) / period


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--scene", default=str(__import__("pathlib").Path(__file__).resolve()
                                          .parents[1] / "scenes" / "bicycle.yaml"))
    p.add_argument("--speed", type=float, default=3.0)
    p.add_argument("--period", type=float, default=0.001)
    p.add_argument("--lean", type=float, default=0.005)
    a = p.parse_args()
    d, res, X, rate, lam = run(a.scene, a.speed, a.period, a.lean)
    print(f"open loop at {a.speed} m/s: {np.round(np.sort_complex(d['open']), 4)}")
    print(f"K = {np.round(d['K'], 3)} (steer torque per lean, steer, roll rate, steer rate)")
    print(f"closed loop A - B K:      {np.round(np.sort_complex(d['continuous']), 4)}")
    print(f"closed loop, ZOH {a.period} s: {np.round(np.sort_complex(d['sampled']), 4)}")
    slow = d["continuous"][np.argmax(d["continuous"].real)].real
    print(f"slowest mode's decay rate: predicted {lam:.6f} (sampled), {slow:.6f} (A - B K); "
          f"measured {rate:.6f} on the nonlinear run")
    print(f"lean: {X[0, 0]:.4g} rad at t = 0, largest after 2 s {np.abs(X[200:, 0]).max():.3g}, "
          f"at {res.t[-1]:.1f} s {X[-1, 0]:.3g}")


if __name__ == "__main__":
    main()
