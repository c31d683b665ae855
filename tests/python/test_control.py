"""Controllers in the loop from Python (docs/control.md): the zero-order hold against the exact
discrete solution of a double integrator, the inputs API and its errors, and the two examples
(the bicycle's LQR decay rate against the sampled closed loop's eigenvalue; the diff-drive
robot's cross-track error)."""

import importlib.util
import math

import numpy as np
import pytest

import appell
from conftest import SOURCE, SCENES

CART = """
name: cart
bodies: {cart: {mass: 2, inertia: [0.1, 0.1, 0.1]}}
joints: {cart: {kind: prismatic, axis: x}}
initial: {cart: {position: 1}}
inputs: [cart.pos_dot]
simulation: {t_end: 3, rtol: 1e-10, atol: 1e-12}
output: {interval: 0.05, channels: [coordinates, speeds, energy]}
"""
KP, KD, T, M = 4.0, 1.5, 0.05, 2.0


def example(name):
    spec = importlib.util.spec_from_file_location(name, SOURCE / "examples" / "python" /
                                                  f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_zoh_matches_discrete_solution():
    """m x'' = u, u_j = -kp x_j - kd v_j held over [jT, (j+1)T): exact recursion; the
    stepper's tolerance (rtol 1e-10) on states of size 1 allows 1e-8."""
    sim = appell.Simulation(appell.loads(CART))
    times = []

    def f(t, s):
        times.append(t)
        assert s["cart.pos"] == s["q"][0] and s["cart.pos_dot"] == s["v"][0]
        assert "energy" in s and s["t"] == t
        return {"cart.pos_dot": -KP * s["cart.pos"] - KD * s["cart.pos_dot"]}

    res = sim.run(3.0, T, controller=f, period=T)
    x, v = 1.0, 0.0
    for j in range(1, 61):
        u = -KP * x - KD * v
        x, v = x + T * v + T * T * u / (2 * M), v + T * u / M
        assert res["cart.pos"][j] == pytest.approx(x, abs=1e-8)
        assert res["cart.pos_dot"][j] == pytest.approx(v, abs=1e-8)
    assert np.allclose(times, np.arange(61) * T, rtol=0, atol=1e-12)
    assert sim.inputs["cart.pos_dot"] == pytest.approx(-KP * x - KD * v, abs=1e-7)


def test_set_inputs_and_step():
    """A constant force F from rest: x = F t^2 / (2 m); then none: uniform motion."""
    sim = appell.Simulation(appell.loads(CART), q0=[0.0])
    sim.set_inputs({"cart.pos_dot": 3.0})
    sim.step(1.0)
    assert sim.state[1][0] == pytest.approx(3.0 / (2 * M), abs=1e-10)
    sim.set_inputs(0.0)                                   # a lone input: a number will do
    sim.step(1.0)
    assert sim.state[1][0] == pytest.approx(3.0 / (2 * M) + 3.0 / M, abs=1e-10)
    assert sim.inputs == {"cart.pos_dot": 0.0}


def test_linearizer_uses_the_scene_inputs():
    """B's column is the scene's input: dv'/dtau = 1/m, with or without a linearize: section."""
    for extra in ("linearize: {about: equilibrium}\n", ""):
        lin = appell.linearize(appell.loads(CART + extra), about="equilibrium")
        assert lin.input_names == ("cart.pos_dot",)
        assert lin.block(["cart.pos_dot"], matrix="B")[0, 0] == pytest.approx(1 / M, rel=1e-14)


def test_controller_errors():
    sim = appell.Simulation(appell.loads(CART))

    def boom(t, s):
        if t > 0.2:
            raise ZeroDivisionError("boom")
        return [0.0]

    with pytest.raises(ZeroDivisionError, match="boom") as e:
        sim.run(1.0, T, controller=boom, period=T)
    assert e.value.result.status == "failed" and e.value.result.t[-1] == pytest.approx(0.2)
    with pytest.raises(appell.Error, match=r"input 'cart.pos_dot' = nan at t = "):
        sim.run(2.0, T, controller=lambda t, s: [math.nan], period=T)
    sim = appell.Simulation(appell.loads(CART))
    with pytest.raises(KeyError, match="no input 'nope'"):
        sim.run(1.0, T, controller=lambda t, s: {"nope": 1.0}, period=T)
    with pytest.raises(ValueError, match="expected 1 values"):
        sim.set_inputs([1.0, 2.0])
    with pytest.raises(appell.Error, match="period"):
        sim.run(1.0, T, controller=lambda t, s: [0.0], period=0.0)
    with pytest.raises(appell.SceneError, match="did you mean 'cart.pos_dot'"):
        appell.loads(CART.replace("inputs: [cart.pos_dot]", "inputs: [cart.pos_dto]"))
    plain = appell.Simulation(appell.loads(CART.replace("inputs: [cart.pos_dot]\n", "")))
    with pytest.raises(ValueError, match="declares no inputs"):
        plain.run(1.0, T, controller=lambda t, s: [0.0])


def test_bicycle_lqr_decay_rate():
    """The Whipple bicycle at 3 m/s (weave unstable) under LQR steer torque, sampled every
    1 ms: the slowest mode's decay rate measured on the nonlinear run equals the sampled
    linear closed loop's log|mu| / T up to the nonlinear terms, which for the bicycle's odd
    lean/steer dynamics shift it by O(lean^2) relatively: lean 0.005 allows 2 lean^2 = 5e-5
    (measured 3.4e-5; with lean 0.0005, 3e-7)."""
    ex = example("bicycle_lqr")
    lean = 0.005
    d, res, X, rate, predicted = ex.run(str(SCENES / "bicycle.yaml"), 3.0, 0.001, lean)
    assert max(d["open"].real) > 1.5                      # the weave: unstable at 3 m/s
    assert max(d["continuous"].real) < -3.9               # stabilized
    assert rate == pytest.approx(predicted, rel=2 * lean**2)
    assert abs(X[-1, 0]) < 1e-7                           # the lean settled (from 0.005)
    # The ZOH's shift from A - B K is O(T): 1.3e-3 of the rate at T = 1 ms.
    slow = max(d["continuous"].real)
    assert abs(predicted - slow) < 2e-3 * abs(slow)


def test_diff_drive_pure_pursuit():
    """From 0.3 m off the wavy road, the cross-track error stays below 5 mm after 10 s
    (measured 1.2 mm) and the robot moves on along it at about 0.5 m/s."""
    ex = example("diff_drive_pursuit")
    res, err = ex.run(str(SCENES / "diff_drive_servo.yaml"), 30.0, 0.01)
    assert err[0] > 0.25
    assert err[res.t >= 10].max() < 0.005
    assert res["chassis.x"][-1] > 12.0


FLY = """
name: fly
bodies: {fly: {mass: 1, inertia: [0.1, 0.1, 0.2]}}
joints: {fly: {kind: revolute, axis: z}}
effects: {spin: {kind: motor, joint: fly, rate: 1, kd: 0.5}}
initial: {fly: {rate: 1}}
inputs: [spin.setpoint]
simulation: {t_end: 2, rtol: 1e-10, atol: 1e-12}
output: {interval: 0.05, channels: [coordinates, speeds]}
"""


def test_motor_setpoint_input():
    """A rate motor's set-point as the input: it starts at the motor's rate; held by a
    controller s_j = 3 - w_j / 2, the rate follows w_{j+1} = s_j + (w_j - s_j) exp(-kd T / I);
    the linearizer's B for it is d(w')/ds = kd / I (an angle motor's: kp / I)."""
    sim = appell.Simulation(appell.loads(FLY))
    assert sim.inputs == {"spin.setpoint": 1.0}
    res = sim.run(2.0, T, controller=lambda t, s: {"spin.setpoint": 3 - s["fly.angle_dot"] / 2},
                  period=T)
    w, E = 1.0, math.exp(-0.5 / 0.2 * T)
    for j in range(1, 41):
        sp = 3 - w / 2
        w = sp + (w - sp) * E
        assert res["fly.angle_dot"][j] == pytest.approx(w, abs=1e-8)
    lin = appell.linearize(appell.loads(FLY), free=["fly.angle_dot"])
    assert lin.input_names == ("spin.setpoint",)
    assert lin.block(["fly.angle_dot"], matrix="B")[0, 0] == pytest.approx(0.5 / 0.2, rel=1e-14)
    servo = FLY.replace("rate: 1, kd: 0.5", "angle: 0, kp: 4, kd: 0.5").replace("rate: 1}", "rate: 0}")
    lin = appell.linearize(appell.loads(servo), about="equilibrium")
    assert lin.block(["fly.angle_dot"], matrix="B")[0, 0] == pytest.approx(4 / 0.2, rel=1e-14)
    with pytest.raises(appell.SceneError, match="MOTOR.setpoint"):
        appell.loads(FLY.replace("[spin.setpoint]", "[spin.setpont]"))
