"""Appell: dynamics of mechanical systems with nonholonomic constraints, from Python.

    import appell
    model = appell.load("examples/scenes/rolling_disk.yaml", set={"bodies.disk.mass": 2})
    sim = appell.Simulation(model, rtol=1e-10)
    res = sim.run(t_end=5, dt=0.01)
    res.t, res.q, res.v, res["disk.tilt"]

    res.status, res.message, res.events          # "ok" here; a failure's e.result says why

    run = appell.read_run("disk.csv")           # appell run --out disk.csv: rows + run record
    run.status, run.message, run.record["steps"]

    table = appell.sweep("examples/scenes/rolling_disk.yaml",
                         grid={"initial.disk.tilt": "70*deg:89*deg:20"}, jobs=2)

    lin = appell.linearize(model, speed=3)      # operating point, A, B, eigenvalues
    lin.A, lin.B, lin.eigenvalues, lin.state_names
    sw = appell.linearize(model, sweep=np.linspace(0, 5, 101))
    sw.eigenvalues, sw.points                    # tracked eigenvalues, characteristic speeds

The integration runs in C (the appell library) with the GIL released. docs/python.md
describes the package; docs/sweeps.md the sweeps (threads, shards, Dask); docs/linearize.md
the linearization.
"""

import json as _json
import math as _math
import os as _os
import re as _re
from collections.abc import Mapping

from . import _appell, _view
from ._appell import Error, Model, SceneError
from ._sweep import Table, sweep

__all__ = ["Error", "SceneError", "Model", "Simulation", "Result", "Table", "load", "loads",
           "sweep", "methods", "constant", "version", "linearize", "Linearization",
           "LinearSweep", "read_run"]

version = _appell.version


def _format_value(v):
    """A scene override value: numbers so that they read back to the same double."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return v
    if isinstance(v, int):
        return str(v)
    try:
        x = float(v)
    except (TypeError, ValueError):
        raise TypeError(f"override value {v!r}: expected a number or a str") from None
    if not _math.isfinite(x):
        raise ValueError(f"override value {v!r} is not finite")
    return repr(x)


def _sets(set):
    """{path: value} or ["path=value", ...] -> a tuple of "path=value"."""
    if set is None:
        return ()
    if isinstance(set, dict):
        return tuple(f"{path}={_format_value(v)}" for path, v in set.items())
    if isinstance(set, str):
        return (set,)
    return tuple(set)


def load(path, set=None, wheels=None, wheel_shape="disk"):
    """Read, validate and compile a scene file; set overrides its values by key path
    ({"bodies.disk.mass": 2} or ["bodies.disk.mass=2"]). Bad input raises SceneError with
    .filename, .line and .column.

    A URDF file (name ending in .urdf) is converted as `appell import` does (docs/urdf.md):
    wheels names the links that roll on the ground, wheel_shape is "disk" or "torus"; its
    errors carry the URDF's .line (.column None)."""
    path = _os.fspath(path)
    if str(path).lower().endswith(".urdf"):
        if wheel_shape not in ("disk", "torus"):
            raise ValueError(f"wheel_shape {wheel_shape!r}: expected 'disk' or 'torus'")
        if isinstance(wheels, str):
            wheels = wheels.split(",")
        text = _appell.urdf(path, () if wheels is None else tuple(wheels),
                            wheel_shape == "torus")
        return _appell.loads(text, f"{path} (imported scene)", _sets(set))
    if wheels is not None:
        raise ValueError("wheels= is for URDF files (.urdf); a scene names its own wheels")
    return _appell.load(path, _sets(set))


def loads(text, name="scene", set=None):
    """load() from the text of a scene; name stands for the file name in messages."""
    return _appell.loads(text, name, _sets(set))


def methods():
    """The steppers on offer: a list of dicts (name, summary, order, adaptive)."""
    return _appell.methods()


def constant(text):
    """The value of a constant expression of the scene grammar, e.g. constant("70*deg")."""
    return _appell.constant(text)


class Result:
    """Rows of a run: res.t, res.q (rows x n), res.v (rows x k), res["disk.tilt"] (any output
    column of the scene, as in appell run's CSV), res.columns, res.table (rows x columns).

    How the run ended, as in appell run's run record (docs/cli.md "The run record"):
    res.status   "ok" (reached t_end), "event" (a stop event ended it), "failed" (the
                 Error's e.result) or "interrupted" (Ctrl-C: the KeyboardInterrupt's
                 e.result); None for a CSV read without a record
    res.message  what stopped it ("" or the run's warning when it ran to the end)
    res.events   the events of the run: dicts with name, t, action, direction, state
    res.record   the run record (a dict) when read by appell.read_run, else None"""

    def __init__(self, columns, table, q, v, coordinate_names=(), speed_names=(),
                 status="ok", message="", events=(), record=None):
        self.columns = tuple(columns)
        self.table = table
        self.q = q
        self.v = v
        self.coordinate_names = tuple(coordinate_names)
        self.speed_names = tuple(speed_names)
        self.status = status
        self.message = message
        self.events = list(events)
        self.record = record
        self._index = {name: i for i, name in enumerate(self.columns)}

    @property
    def t(self):
        return self.table[:, 0]

    def __getitem__(self, name):
        i = self._index.get(name)
        if i is not None:
            return self.table[:, i]
        for names, arr in ((self.coordinate_names, self.q), (self.speed_names, self.v)):
            if name in names:
                return arr[:, names.index(name)]
        raise KeyError(f"no column {name!r}; the columns are {', '.join(self.columns)}")

    def __contains__(self, name):
        return name in self._index or name in self.coordinate_names or name in self.speed_names

    def keys(self):
        return self.columns

    def __len__(self):
        return self.table.shape[0]

    def __repr__(self):
        return (f"<appell.Result: {len(self)} rows x {len(self.columns)} columns, "
                f"status {self.status}>")

    def view(self, path, plots=(), forces=False, title=None):
        """Write the 3-D viewer page of this run (docs/viewer.md) to path; returns path."""
        return _view.view(self, path, plots, forces, title)

    def _repr_html_(self):
        return _view.repr_html(self)


def _run_events(sim):
    """The events a Simulation recorded (docs/python.md "Events"): dicts with name, t,
    direction, action, q and v."""
    return list(sim.events)


def read_run(path):
    """The rows and the run record of `appell run --out PATH`: path names the CSV (its record
    is PATH.run.json beside it) or the record itself. Returns a Result with the CSV's columns
    (q and v are None), status, message and events from the record, and .record the whole
    record as a dict (docs/cli.md "The run record"); without a record, status and record are
    None."""
    import numpy as np
    path = _os.fspath(path)
    csv = path[:-len(".run.json")] if path.endswith(".run.json") else path
    record = None
    try:
        with open(csv + ".run.json", encoding="utf-8") as f:
            record = _json.load(f)
    except FileNotFoundError:
        pass
    with open(csv, encoding="utf-8") as f:
        columns = f.readline().strip().split(",")
        table = np.loadtxt(f, delimiter=",", ndmin=2).reshape(-1, len(columns))
    rec = record or {}
    return Result(columns, table, None, None, status=rec.get("status"),
                  message=rec.get("message", ""), events=rec.get("events", ()), record=record)


def _event_sets(events):
    """Simulation(events=[{name, when, direction, action}, ...]) -> overrides
    "events.NAME={...}" (JSON is YAML flow syntax), checked by the scene's parser."""
    if isinstance(events, (str, bytes, Mapping)) or not hasattr(events, "__iter__"):
        raise TypeError(f"events must be a list of dicts, got {type(events).__name__}")
    sets = []
    for i, ev in enumerate(events):
        if not isinstance(ev, Mapping):
            raise TypeError(f"events[{i}] must be a dict, got {type(ev).__name__}")
        body = dict(ev)
        name = body.pop("name", None)
        if not isinstance(name, str) or not _re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", name):
            raise ValueError(f"events[{i}]: name must be a word of letters, digits and _ "
                             f"(not starting with a digit), got {name!r}")
        for key, v in body.items():
            if not isinstance(key, str) or isinstance(v, bool) or not isinstance(v, (str, int, float)):
                raise TypeError(f"events[{i}] ({name}): {key!r} must be a string or a number, "
                                f"got {type(v).__name__}")
            if isinstance(v, str) and "\0" in v:
                raise ValueError(f"events[{i}] ({name}): {key!r} contains a NUL character")
        sets.append(f"events.{name}={_json.dumps(body, allow_nan=False)}")
    return tuple(sets)


class Simulation(_appell.Simulation):
    """Simulation(model, mode=None, method=None, rtol=None, atol=None, h_fixed=None,
    h_init=None, h_max=None, max_steps=None, t0=None, q0=None, v0=None, events=None, accuracy=None,
    error_estimate=False)

    One run of a Model from its initial state (or q0, v0), with the scene's settings unless
    given here. run() records rows; advance() integrates without recording; state, stats,
    warning and report tell where it is. Simulations of one Model may run in parallel
    threads (the GIL is released while integrating).

    events adds events to the scene's own (docs/python.md "Events"): a list of dicts with the
    keys of a scene's events: entry and its name, e.g. {"name": "lean", "when":
    "hinge.angle - 60*deg", "direction": "rising", "action": "stop"} (or "kind": "collide",
    "lift_off", "joint_range" with body, constraint, joint, min, max). One with the name of
    a scene event replaces it. The simulation then runs a copy of the model loaded with these
    events (sim.model is that copy); a bad entry raises SceneError naming it.

    accuracy (a global error on the output channels, docs/accuracy.md): the method and
    tolerances are picked by a pilot over the scene's t_end and output interval (the choice in
    .pick). error_estimate=True: every run() estimates its global error."""

    def __new__(cls, model, *args, events=None, accuracy=None, error_estimate=False, **kw):
        if events is not None:
            if not isinstance(model, Model):
                raise TypeError(f"model must be an appell.Model, got {type(model).__name__}")
            sets = _event_sets(events)
            if sets:
                text, name, old = model.source
                model = loads(text, name=name, set=tuple(old) + sets)
        pick = None
        if accuracy is not None:
            probe = super().__new__(cls, model, *args, **kw)   # the initial state and settings
            t0, q0, v0 = probe.state
            ms = model.settings
            pick = _appell._pick(model, float(accuracy), probe.settings, t0, q0, v0,
                                 ms["t_end"], ms["interval"])
            kw.update(method=pick["method"], rtol=pick["rtol"], atol=pick["atol"])
        self = super().__new__(cls, model, *args, **kw)
        self.pick, self.error_estimate = pick, bool(error_estimate)
        return self

    def run(self, t_end=None, dt=None, controller=None, period=None, error_estimate=None):
        """Integrate from the current time to t_end (default: the scene's), recording a row
        every dt (default: the scene's output interval), the last at t_end exactly; the first
        row is the current state. Returns a Result. On failure raises Error with .result, the
        rows up to where the run stopped (status "failed"); Ctrl-C raises KeyboardInterrupt
        with .result the same way (status "interrupted"). With error_estimate (default: the
        Simulation's), Result.error_estimate holds the estimated global error (docs/accuracy.md).

        controller: f(t, state) -> inputs, called every period seconds of simulated time
        (default: dt) from the current time on, the scene's inputs: held at its result until
        the next call (zero-order hold; docs/control.md). state is a dict of every coordinate,
        speed and output column by name, plus "q" and "v" arrays; the result is a dict by
        input name (the others keep their values) or one value per input. An exception raised
        by f stops the run and propagates with .result, the rows up to there. The inputs keep
        their last values after the run."""
        if controller is None:
            return self._run_rows(t_end, dt, error_estimate)
        if period is None:
            period = dt if dt is not None else self.model.settings["interval"]
        handle = _appell._set_controller(self, controller, float(period))
        try:
            return self._run_rows(t_end, dt, error_estimate)
        except Error as e:
            raised = _appell._controller_error(handle)
            if raised is None:
                raise
            try:
                raised.result = getattr(e, "result", None)
            except AttributeError:
                pass
            raise raised from None
        finally:
            _appell._set_controller(self, None, 0.0)

    def step(self, dt):
        """Advance by dt without recording (the inputs held as they are); for loops that
        compute the inputs themselves: sim.set_inputs(...); sim.step(0.01)."""
        self.advance(self.t + dt)

    def set_inputs(self, values=None, **named):
        """Set the scene's inputs from now on, held until changed (docs/control.md): a dict by
        input name, one value per input, or keywords for names that are identifiers."""
        _appell._set_inputs(self, named if values is None else values)

    @property
    def inputs(self):
        """The input values in force, a dict by name (the scene's inputs: section)."""
        return _appell._inputs(self)

    def _run_rows(self, t_end, dt, error_estimate):
        m = self.model
        start = self.state
        try:
            columns, table, q, v = self._run(t_end, dt)
        except BaseException as e:
            partial = getattr(e, "partial", None)
            if partial is not None:
                failed = isinstance(e, Error)
                message = (str(e) if failed else
                           f"interrupted by {type(e).__name__} at t = {self.t:.10g}")
                e.result = Result(*partial, m.coordinate_names, m.speed_names,
                                  status="failed" if failed else "interrupted",
                                  message=message, events=_run_events(self))
            raise
        events = _run_events(self)
        stop = events[-1] if events and events[-1]["action"] == "stop" else None
        stopped = stop is not None and len(table) > 0 and stop["t"] == table[-1, 0]
        res = Result(columns, table, q, v, m.coordinate_names, m.speed_names,
                     status="event" if stopped else "ok",
                     message=(f"stopped by event '{stop['name']}' at t = {stop['t']:.10g}"
                              if stopped else self.warning), events=events)
        res.model = m   # for res.view() (_view.py)
        res.pick = self.pick
        res.error_estimate = None
        if (self.error_estimate if error_estimate is None else error_estimate) and len(table) > 1:
            res.error_estimate = _appell._error_estimate(m, self.settings, start[0], start[1],
                                                         start[2], table)
        return res


class Linearization:
    """The linearization of a Model at one operating point (appell.linearize), as NumPy arrays:

    speed          the speed parameter (None without one); t, q, v: the operating point
    state_names    the states x = (independent chart coordinates, independent speeds)
    cyclic         (nx) bool: cyclic coordinates (dropped from the eigenvalues by default)
    A, A_error     (nx x nx) the state matrix dF/dx and the error estimate of each entry
    B, input_names (nx x nu) the input matrix for generalized forces on the named speeds
    rates          (nx) F at the point (non-zero only in cyclic rows for a steady motion)
    subsystem      the states of the eigenvalue problem; A_sub its matrix
    eigenvalues    (complex), largest real part first, with rcond (reciprocal condition
                   numbers), rcondv (of the eigenvectors), error (bound) and eigenvectors
                   (column j for eigenvalue j)."""

    def __init__(self, d):
        self.__dict__.update(d)

    def index(self, name):
        """The index of a state by name (ValueError if none)."""
        try:
            return self.state_names.index(name)
        except ValueError:
            raise ValueError(f"no state {name!r}; the states are "
                             f"{', '.join(self.state_names)}") from None

    def block(self, rows, cols=None, matrix="A"):
        """The sub-matrix of A (or "B", "A_error") on the named states (cols: rows when
        None; for B, cols are input names)."""
        M = getattr(self, matrix)
        r = [self.index(n) for n in rows]
        if matrix == "B":
            names = self.input_names
            c = [names.index(n) for n in (cols if cols is not None else names)]
        else:
            c = [self.index(n) for n in (cols if cols is not None else rows)]
        return M[_np_ix(r, c)]

    def __repr__(self):
        return (f"<appell.Linearization: {len(self.state_names)} states, "
                f"{len(self.eigenvalues)} eigenvalues of {', '.join(self.subsystem)}>")


class LinearSweep:
    """Eigenvalues over the speed (appell.linearize(..., sweep=speeds)):

    p            (count) the speeds
    subsystem    the states of the eigenvalue problem
    eigenvalues  (count x n) complex; column j follows one eigenvalue by continuity
    points       characteristic speeds, dicts: kind ('crossing': a real part crosses zero;
                 'meeting': two real eigenvalues meet), p, p_err (the root finder's
                 bracket), value (the eigenvalue there), index (its column), rising (a
                 crossing: the real part goes from - to +; a meeting: the pair becomes
                 complex as the speed grows)."""

    def __init__(self, d):
        self.__dict__.update(d)

    def __repr__(self):
        return (f"<appell.LinearSweep: {len(self.p)} speeds x {self.eigenvalues.shape[1]} "
                f"eigenvalues, {len(self.points)} characteristic points>")


def _np_ix(r, c):
    import numpy as np
    return np.ix_(r, c)


def linearize(model, speed=None, about=None, free=None, inputs=None, states=None,
              keep_cyclic=False, sweep=None, ptol=None, set=None):
    """Linearize a model (a Model, or a scene path loaded with the overrides set) about its
    operating point, as `appell linearize` does, with the scene's linearize: section
    (docs/linearize.md) unless overridden here:

    speed        the speed parameter (needs linearize.speed; default: the scene's own rates)
    about        "steady" or "equilibrium"
    free         state variables Newton may move; inputs: speeds receiving a generalized
                 force (columns of B); states: the subsystem of the eigenvalues
    keep_cyclic  keep the cyclic coordinates in the eigenvalue problem
    sweep        speeds (ascending): returns a LinearSweep with the eigenvalues tracked and
                 the characteristic speeds located to ptol (default 1e-14 of the largest)

    Returns a Linearization (or a LinearSweep). Failures raise Error (no operating point,
    a subsystem that is not closed, an unknown state name ...)."""
    if not isinstance(model, Model):
        model = load(model, set=set)
    elif set is not None:
        text, name, sets = model.source
        model = loads(text, name=name, set=sets + _sets(set))
    tup = (lambda x: None if x is None else ((x,) if isinstance(x, str) else tuple(x)))
    d = _appell.linearize(model, speed, about, tup(free), tup(inputs), tup(states),
                          bool(keep_cyclic), sweep, 0.0 if ptol is None else float(ptol))
    return LinearSweep(d) if sweep is not None else Linearization(d)
