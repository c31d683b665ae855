"""appell.sweep: many runs of one scene over grids and random samples, on threads or on a
Dask cluster (docs/sweeps.md).

The plan (grids, random samples, seed) is built in C exactly as `appell sweep` builds it, so a
sweep gives the same runs with the same values from the command line, from Python and from any
slice of it. Locally the runs go to the C thread pool (jobs threads, GIL released); with a Dask
client the runs are cut into chunks, each chunk runs on a worker (appell._sweep._run_chunk)
and the table is put together in run order. Dask reschedules the chunks of a worker that dies,
and a chunk's rows depend only on the plan and the run indices, so no run is lost or changed.
"""

import math
import os
from collections.abc import Mapping

import numpy as np

from . import _appell

_FIXED = ("t", "steps", "rhs_evals", "err_fails", "max_residual", "energy_drift")


class Table(dict):
    """The result of a sweep: column name -> NumPy array, in the order of `appell sweep`'s CSV:
    run, the parameters, status, outcome ("ok", "event" or "failed", as in a run record),
    events (the events of the run, "NAME@T;..."), t, steps, rhs_evals, err_fails,
    max_residual, energy_drift, NAME@end, CHANNEL@T, message. .runs is the plan's size, .paths
    the parameters' paths, .scene the scene file (to_csv never overwrites it), .plan the
    sweep's identity (16 hex digits: a hash of the scene, the overrides and the plan, in every
    row of the CSV, so that `appell sweep --merge` joins only shards of one sweep)."""

    runs = 0
    paths = ()
    scene = None
    plan = ""

    @property
    def columns(self):
        return tuple(self.keys())

    @property
    def failed(self):
        """Indices (rows) of the runs that failed (not those a stop event ended)."""
        return np.nonzero((self["status"] != 0) & (self["status"] != _STOPPED))[0]

    def to_csv(self, path):
        """Write the table as `appell sweep --out` does (same bytes for the same runs), by the
        same rules (docs/cli.md "Output files and signals"): a regular file appears complete
        or not at all, a FIFO or a device is written in place, a symbolic link is followed, a
        directory and the scene file are refused (OSError: IsADirectoryError,
        FileExistsError, ...), and a failed write leaves nothing behind."""
        cols = [c for c in self.columns if c != "run"]
        lines = [",".join(["run", "runs", "plan"] + cols)]
        text = "\n".join(lines + [_row(self, i, cols) for i in range(len(self["run"]))]) + "\n"
        keep = () if self.scene is None else (self.scene,)
        _appell.write_file(os.fspath(path), text.encode(), keep=keep)


def _g17(x):
    x = float(x)
    if math.isnan(x):
        return "nan"
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    return "%.17g" % x


def _row(table, i, cols):
    cells = [str(int(table["run"][i])), str(table.runs), table.plan]
    for c in cols:
        x = table[c][i]
        if c in ("message", "events"):
            cells.append('"' + (x or "").replace('"', '""').replace("\n", " ") + '"')
        elif c == "status":
            cells.append(str(int(x)))
        elif isinstance(x, str):
            cells.append(x)
        else:
            cells.append(_g17(x))
    return ",".join(cells)


def _format_number(x):
    if isinstance(x, str):
        return x
    x = float(x)
    if not math.isfinite(x):
        raise ValueError(f"grid value {x!r} is not finite")
    return repr(x)


def _grid_spec(path, values):
    """{path: "A:B:N" | "V1,V2" | sequence} -> "path=..." for the C plan."""
    if isinstance(values, str):
        return f"{path}={values}"
    items = list(np.asarray(values).ravel()) if isinstance(values, np.ndarray) else list(values)
    if not items:
        raise ValueError(f"grid {path!r}: no values")
    return f"{path}=" + ",".join(_format_number(v) for v in items)


def _random_spec(path, dist):
    """{path: "normal(MU,SIGMA)" | ("normal", mu, sigma) | ("uniform", a, b)}."""
    if isinstance(dist, str):
        return f"{path}={dist}"
    kind, a, b = dist
    return f"{path}={kind}({_format_number(a)},{_format_number(b)})"


def _source(scene, set):
    from . import _sets
    if isinstance(scene, _appell.Model):
        text, name, sets = scene.source
        return bytes(text), name, tuple(sets) + _sets(set)
    path = os.fspath(scene)
    with open(path, "rb") as f:
        return f.read(), path, _sets(set)


def _assemble(parts, first):
    """One Table from the run_plan results of consecutive slices starting at run first."""
    p0 = parts[0]
    out = Table()
    out.runs, out.paths, out.plan = p0["runs"], p0["paths"], p0["plan"]
    count = sum(len(p["status"]) for p in parts)
    out["run"] = np.arange(first, first + count, dtype=np.int64)
    for r, path in enumerate(p0["paths"]):
        if any(p["params"][1][r] is not None for p in parts):
            out[path] = np.array(sum((p["params"][1][r] or [_g17(x) for x in p["params"][0][:, r]]
                                      for p in parts), []), dtype=object)
        else:
            out[path] = np.concatenate([p["params"][0][:, r] for p in parts])
    out["status"] = np.concatenate([p["status"] for p in parts])
    out["outcome"] = np.array([_outcome(s) for s in out["status"]], dtype=object)
    out["events"] = np.array(_run_events(parts, len(out["status"])), dtype=object)
    values = np.concatenate([p["values"] for p in parts])
    for j, name in enumerate(p0["columns"]):
        col = values[:, j]
        out[name] = col.astype(np.int64) if name in _FIXED[1:4] and np.all(np.isfinite(col)) else col
    out["message"] = np.array(sum((p["messages"] for p in parts), []), dtype=object)
    return out


_STOPPED = 2   # AP_STOPPED (include/appell/status.h): a stop event ended the run


def _outcome(status):
    """A run's outcome word from its status, as appell sweep writes it (tools/runrecord.c)."""
    return "ok" if status == 0 else "event" if status == _STOPPED else "failed"


def _run_events(parts, count):
    """Each run's events as "NAME@T;..." (the sweep's events column, from the batch: the last
    64 events of the run, T with 17 significant digits)."""
    out = sum((list(p.get("events", [None] * len(p["status"]))) for p in parts), [])
    return [e or "" for e in out[:count]]


MAX_SAMPLES = 10 ** 9   # as a grid's N: `appell sweep --samples` keeps the same limit


def _whole(x):
    return not isinstance(x, bool) and isinstance(x, (int, np.integer))


def _check_args(grid, random, samples, seed, shard, chunk_size, client):
    """TypeError / ValueError naming the argument, before anything runs."""
    for name, value in (("grid", grid), ("random", random)):
        if value is not None and not isinstance(value, Mapping):
            raise TypeError(f"{name} must be a dict {{path: values}}, got {type(value).__name__}")
    if samples is not None and not _whole(samples):
        raise TypeError(f"samples must be a whole number, got {samples!r}")
    if samples is not None and not 1 <= samples <= MAX_SAMPLES:
        raise ValueError(f"samples must be from 1 to 10**9 (random draws per grid point), got "
                         f"{samples!r}")
    if not _whole(seed) or not 0 <= seed < 2 ** 64:
        raise ValueError(f"seed must be a whole number from 0 to 2**64 - 1, got {seed!r}")
    if shard is not None and (not isinstance(shard, (tuple, list)) or len(shard) != 2
                              or not all(_whole(x) for x in shard)):
        raise TypeError(f"shard must be a pair (i, n) of whole numbers, got {shard!r}")
    if chunk_size is not None and (not _whole(chunk_size) or chunk_size < 1):
        raise ValueError(f"chunk_size must be a whole number >= 1, got {chunk_size!r}")
    if chunk_size is not None and client is None:
        raise ValueError("chunk_size needs a Dask client (client=...)")


def _check_checkpoint(checkpoint, client):
    if checkpoint is None:
        return None
    if client is None:
        raise ValueError("checkpoint needs a Dask client (client=...); appell sweep --resume "
                         "resumes a local sweep")
    try:
        return os.fspath(checkpoint)
    except TypeError:
        raise TypeError(f"checkpoint must be a path, got {type(checkpoint).__name__}") from None


def _channels(channels):
    if isinstance(channels, str):
        return (channels,)
    try:
        out = tuple(channels)
    except TypeError:
        raise TypeError(f"channels must be a str or a sequence of str, got "
                        f"{type(channels).__name__}") from None
    for c in out:
        if not isinstance(c, str):
            raise TypeError(f"channels: {c!r} is not a str")
    return out


def _times(times):
    if times is None:
        return ()
    try:
        return tuple(float(t) for t in np.ravel(times))
    except (TypeError, ValueError):
        raise TypeError(f"times must be numbers (seconds), got {times!r}") from None


def sweep(scene, grid=None, random=None, samples=None, seed=1, set=None, channels=(),
          times=None, final_state=True, jobs=1, shard=None, client=None, chunk_size=None,
          progress=None, checkpoint=None):
    """Run a scene once per point of a grid or random sample of its values; returns a Table.

    scene      a scene file's path or a Model (its text and overrides are used)
    grid       {path: "A:B:N" (N values from A to B) | "V1,V2,..." | a sequence of values}
    random     {path: "normal(MU,SIGMA)" | "uniform(A,B)"}, `samples` draws per grid point
    seed       seed of the random values (the same seed gives the same values anywhere)
    set        overrides applied to every run, as in appell.load
    channels   output columns to sample at `times` (default: t_end)
    jobs       threads (0: one per processor); with a Dask client, chunks run on the workers
    shard      (i, n): only the i-th of n equal slices of the runs (1 <= i <= n)
    client     a dask.distributed.Client: run chunks of chunk_size runs on its workers
    progress   callable(done, total), called about every 0.2 s
    checkpoint with a client: a directory where each finished chunk is kept; the same call
               after an interruption (a lost client, Ctrl-C) runs only the runs not kept
               there and returns the same table; the directory is removed at the end
    A failed run is a row with its status (non-zero) and message.
    """
    if isinstance(jobs, bool) or not isinstance(jobs, (int, np.integer)) or jobs < 0:
        raise ValueError(f"jobs must be a whole number >= 0 (0: one per processor), got {jobs!r}")
    _check_args(grid, random, samples, seed, shard, chunk_size, client)
    checkpoint = _check_checkpoint(checkpoint, client)
    text, name, sets = _source(scene, set)
    grids = tuple(_grid_spec(p, v) for p, v in (grid or {}).items())
    randoms = tuple(_random_spec(p, v) for p, v in (random or {}).items())
    n_samples = int(samples or 0)
    runs, _ = _appell.plan_info(grids, randoms, n_samples, int(seed))
    first, count = 0, runs
    if shard is not None:
        i, n = shard
        if not 1 <= i <= n:
            raise ValueError(f"shard {shard!r}: need 1 <= i <= n")
        first = runs // n * (i - 1) + runs % n * (i - 1) // n
        count = runs // n * i + runs % n * i // n - first
    args = dict(text=text, name=name, sets=sets, grids=grids, randoms=randoms,
                samples=n_samples, seed=int(seed),
                channels=_channels(channels), times=_times(times),
                final_state=bool(final_state))
    if client is None:
        part = _appell.run_plan(first=first, count=count, jobs=int(jobs),
                                progress=progress, **args)
        table = _assemble([part], first)
    else:
        from ._dask import run_on_dask
        # The plan checked here, as a local sweep checks it, before any chunk goes to a
        # worker (the chunks skip the check): a misspelt path raises instead of failing
        # every run.
        head = _appell.run_plan(first=first, count=0, jobs=1, check=True, **args)
        identity = {"plan": head["plan"], "first": first, "count": count,
                    "columns": list(head["columns"])}
        table = _assemble(run_on_dask(client, args, first, count, chunk_size, progress,
                                      checkpoint, identity), first)
    table.scene = name if os.path.isfile(name) else None
    return table


def _run_chunk(args, first, count):
    """A Dask task: runs first .. first + count - 1 of the plan in one worker thread."""
    return _appell.run_plan(first=first, count=count, jobs=1, check=False, **args)
