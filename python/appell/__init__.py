"""Appell: dynamics of mechanical systems with nonholonomic constraints, from Python.

    import appell
    model = appell.load("examples/scenes/rolling_disk.yaml", set={"bodies.disk.mass": 2})
    sim = appell.Simulation(model, rtol=1e-10)
    res = sim.run(t_end=5, dt=0.01)
    res.t, res.q, res.v, res["disk.tilt"]

    table = appell.sweep("examples/scenes/rolling_disk.yaml",
                         grid={"initial.disk.tilt": "70*deg:89*deg:20"}, jobs=2)

The integration runs in C (the appell library) with the GIL released. docs/python.md
describes the package; docs/sweeps.md the sweeps (threads, shards, Dask).
"""

import math as _math
import os as _os

from . import _appell
from ._appell import Error, Model, SceneError
from ._sweep import Table, sweep

__all__ = ["Error", "SceneError", "Model", "Simulation", "Result", "Table", "load", "loads",
           "sweep", "methods", "constant", "version"]

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


def load(path, set=None):
    """Read, validate and compile a scene file; set overrides its values by key path
    ({"bodies.disk.mass": 2} or ["bodies.disk.mass=2"]). Bad input raises SceneError with
    .filename, .line and .column."""
    return _appell.load(_os.fspath(path), _sets(set))


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
    column of the scene, as in appell run's CSV), res.columns, res.table (rows x columns)."""

    def __init__(self, columns, table, q, v, coordinate_names=(), speed_names=()):
        self.columns = tuple(columns)
        self.table = table
        self.q = q
        self.v = v
        self.coordinate_names = tuple(coordinate_names)
        self.speed_names = tuple(speed_names)
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
        return f"<appell.Result: {len(self)} rows x {len(self.columns)} columns>"


class Simulation(_appell.Simulation):
    """Simulation(model, mode=None, method=None, rtol=None, atol=None, h_fixed=None,
    h_init=None, h_max=None, max_steps=None, t0=None, q0=None, v0=None)

    One run of a Model from its initial state (or q0, v0), with the scene's settings unless
    given here. run() records rows; advance() integrates without recording; state, stats,
    warning and report tell where it is. Simulations of one Model may run in parallel
    threads (the GIL is released while integrating)."""

    def run(self, t_end=None, dt=None):
        """Integrate from the current time to t_end (default: the scene's), recording a row
        every dt (default: the scene's output interval), the last at t_end exactly; the first
        row is the current state. Returns a Result. On failure raises Error with .result, the
        rows up to where the run stopped."""
        m = self.model
        try:
            columns, table, q, v = self._run(t_end, dt)
        except Error as e:
            partial = getattr(e, "partial", None)
            if partial is not None:
                e.result = Result(*partial, m.coordinate_names, m.speed_names)
            raise
        return Result(columns, table, q, v, m.coordinate_names, m.speed_names)
