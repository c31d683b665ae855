"""Scene events from Python (docs/python.md "Events"): a run that a stop event ends returns its
rows up to the event, the last at the event time, and the events recorded; the times are the
pendulum's elliptic-integral ones (tests/test_scene_events.c derives them)."""

import math

import appell
from conftest import BAD, run_cli


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


def swing_times(a, b):
    """Release from rest at angle a: the time of the first passage through 0 (down) and
    through -b (b < a) on the first swing."""
    k, omega = math.sin(a / 2), math.sqrt(9.81 / 1.001)
    K = ell_f(math.pi / 2, k)
    return K / omega, (K + ell_f(math.asin(math.sin(b / 2) / k), k)) / omega, 4 * K / omega


def test_simulation_events_argument():
    m = appell.load(BAD / "pendulum_events.yaml")
    sim = appell.Simulation(m, events=[
        {"name": "up", "when": "hinge.angle + 0.4", "direction": "falling", "action": "stop"},
        {"name": "back", "when": "hinge.angle - 10", "action": "log"}])   # replaced: never fires
    res = sim.run()
    assert [e["name"] for e in res.events] == ["down", "up"]
    t_up = swing_times(0.5, 0.4)[1]
    assert abs(res.events[-1]["t"] - t_up) < 1e-9 * t_up
    assert res.status == "event" and res.t[-1] == res.events[-1]["t"]
    assert res.message == f"stopped by event 'up' at t = {res.t[-1]:.10g}"
    assert sim.model.source[2][-1].startswith("events.back=")
    assert appell.Simulation(m).run().events[-1]["name"] == "back"   # the model is unchanged


def test_simulation_events_refused():
    m = appell.load(BAD / "pendulum_events.yaml")
    for bad, kind, words in (("x", TypeError, "list of dicts"),
                             ([3], TypeError, "events[0] must be a dict"),
                             ([{"when": "t"}], ValueError, "name must be"),
                             ([{"name": "a.b", "when": "t"}], ValueError, "name must be"),
                             ([{"name": "a", "when": ["t"]}], TypeError, "'when'"),
                             ([{"name": "a", "wen": "t - 1"}], appell.SceneError, "did you mean 'when'"),
                             ([{"name": "a", "when": "hinge.angel"}], appell.SceneError,
                              "did you mean 'hinge.angle'")):
        try:
            appell.Simulation(m, events=bad)
        except kind as e:
            assert words in str(e), (bad, str(e))
        else:
            raise AssertionError(f"events={bad!r} accepted")


def test_sweep_runs_add_the_scene_events(tmp_path):
    scene = BAD / "pendulum_events.yaml"
    t = appell.sweep(scene, grid={"initial.hinge.angle": [0.2, 0.5, 0.8]})
    assert list(t["outcome"]) == ["ok", "event", "event"] and list(t["status"]) == [0, 2, 2]
    assert len(t.failed) == 0
    # 0.2 rad never reaches -0.25: "down" logged once a period until t_end = 5
    down, _, period = swing_times(0.2, 0.1)
    cells = [c.split("@") for c in t["events"][0].split(";")]
    assert [c[0] for c in cells] == ["down"] * 3 and t["t"][0] == 5
    for j, (_, tj) in enumerate(cells):
        assert abs(float(tj) - (down + j * period)) < 1e-9 * 5
    for row, a in ((1, 0.5), (2, 0.8)):
        down, back, _ = swing_times(a, 0.25)
        names = [c.split("@")[0] for c in t["events"][row].split(";")]
        times = [float(c.split("@")[1]) for c in t["events"][row].split(";")]
        assert names == ["down", "back"] and t["t"][row] == times[1]
        assert abs(times[0] - down) < 1e-9 * down and abs(times[1] - back) < 1e-9 * back
        assert abs(t["bob.angle@end"][row] + 0.25) < 1e-10
        assert t["message"][row] == f"stopped by event 'back' at t = {times[1]:.10g}"
    run_cli("sweep", scene, "--grid", "initial.hinge.angle=0.2,0.5,0.8", "--out",
            tmp_path / "cli.csv", "--quiet")
    t.to_csv(tmp_path / "py.csv")
    assert (tmp_path / "py.csv").read_bytes() == (tmp_path / "cli.csv").read_bytes()
