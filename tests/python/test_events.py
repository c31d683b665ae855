"""Scene events from Python (docs/python.md "Events"): a run that a stop event ends returns its
rows up to the event, the last at the event time, and the events recorded; the times are the
pendulum's elliptic-integral ones (tests/test_scene_events.c derives them)."""

import math

import appell
from conftest import BAD


def ell_f(phi, k, n=2000):
    """F(phi, k) by the midpoint rule with n points (smooth integrand: error ~ 1e-13)."""
    h = phi / n
    return sum(h / math.sqrt(1 - (k * math.sin((i + 0.5) * h)) ** 2) for i in range(n))


def test_stop_event_ends_the_run():
    m = appell.load(BAD / "pendulum_events.yaml")
    res = appell.Simulation(m).run()
    names = [e["name"] for e in res.events]
    assert names == ["down", "back"]
    back = res.events[1]
    assert back["action"] == "stop" and back["direction"] == "falling"
    k, omega = math.sin(0.25), math.sqrt(9.81 / 1.001)
    t_back = (ell_f(math.pi / 2, k) + ell_f(math.asin(math.sin(0.125) / k), k)) / omega
    assert abs(back["t"] - t_back) < 1e-9 * t_back
    assert res.t[-1] == back["t"]
    assert abs(res["bob.angle"][-1] + 0.25) < 1e-10
    assert len(res) == 4   # rows at 0, 0.25, 0.5 and the event


def test_advance_stops_at_the_event():
    sim = appell.Simulation(appell.load(BAD / "pendulum_events.yaml"))
    sim.advance(5.0)
    assert sim.events[-1]["name"] == "back" and sim.t == sim.events[-1]["t"]
