"""Sweeps on a Dask cluster (appell.sweep(..., client=Client(...)); docs/sweeps.md).

The runs first .. first + count - 1 are cut into chunks of chunk_size consecutive runs; each
chunk is one task, appell._sweep._run_chunk, whose arguments carry the scene's text and the
plan's specs (a few kilobytes), so any worker can run any chunk and no shared file system is
needed. When a worker dies, the scheduler gives its unfinished chunks to another worker (up to
distributed's allowed-failures, 3 by default); a chunk's rows depend only on the plan and the
run indices, so a chunk run twice gives the same rows. The parts are put back in run order.

With a checkpoint directory (sweep(..., checkpoint=DIR)) each finished chunk is written there
as it arrives (JSON, to a temporary file renamed over its name: a chunk file is whole or
absent), beside sweep.json, the sweep's identity (the plan's hash, first run and count). A
sweep stopped by a lost client, Ctrl-C or a killed scheduler is continued by the same call:
the chunks on file are read back, only the runs not on file are run (cut into chunks again),
and the table is the same as an uninterrupted sweep's; the directory is removed at the end.
A directory holding another sweep's checkpoint is refused.
"""

import json
import math
import os

import numpy as np

from ._sweep import _run_chunk

_IDENTITY = "sweep.json"


def chunks(first, count, chunk_size):
    """[(start, n), ...] covering first .. first + count - 1."""
    return [(s, min(chunk_size, first + count - s)) for s in range(first, first + count, chunk_size)]


# ---- the checkpoint ------------------------------------------------------------------------

def _write_atomic(path, text):
    tmp = f"{path}.tmp.{os.getpid()}"
    try:
        with open(tmp, "w", encoding="utf-8") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.remove(tmp)
        raise


def _encode(part):
    x, words = part["params"]
    return json.dumps({"paths": list(part["paths"]), "x": x.tolist(), "words": words,
                       "columns": list(part["columns"]), "values": part["values"].tolist(),
                       "status": part["status"].tolist(), "messages": part["messages"],
                       "events": part.get("events"), "runs": part["runs"],
                       "plan": part["plan"]})


def _decode(text, count, ncols):
    d = json.loads(text)
    x = np.array(d["x"], dtype=np.float64).reshape(count, -1)
    values = np.array(d["values"], dtype=np.float64).reshape(count, ncols)
    part = {"paths": tuple(d["paths"]), "params": (x, d["words"]), "columns": tuple(d["columns"]),
            "values": values, "status": np.array(d["status"], dtype=np.int32),
            "messages": d["messages"], "runs": d["runs"], "plan": d["plan"]}
    if d.get("events") is not None:
        part["events"] = d["events"]
    return part


def _open_checkpoint(path, identity):
    """The chunks on file {start: part} of the sweep identity (a dict); ValueError when path
    holds another sweep's checkpoint."""
    os.makedirs(path, exist_ok=True)
    ident = os.path.join(path, _IDENTITY)
    if not os.path.exists(ident):
        _write_atomic(ident, json.dumps(identity))
        return {}
    with open(ident, encoding="utf-8") as f:
        try:
            found = json.load(f)
        except ValueError:
            found = None
    if found != identity:
        raise ValueError(f"checkpoint {path}: it holds another sweep ({ident}: {found!r}, this "
                         f"sweep: {identity!r}); remove it or give another directory")
    parts = {}
    for name in os.listdir(path):
        stem, ext = os.path.splitext(name)
        if ext != ".json" or name == _IDENTITY or stem.count("-") != 1:
            continue
        start, n = (int(s) for s in stem.split("-"))
        with open(os.path.join(path, name), encoding="utf-8") as f:
            part = _decode(f.read(), n, len(identity["columns"]))
        if part["plan"] != identity["plan"] or len(part["status"]) != n:
            raise ValueError(f"checkpoint {path}: {name} is not a chunk of this sweep")
        parts[start] = part
    return parts


def _remove_checkpoint(path):
    for name in os.listdir(path):
        if name.endswith(".json"):
            os.remove(os.path.join(path, name))
    try:
        os.rmdir(path)
    except OSError:
        pass   # files of someone else's: left alone


def _gaps(first, count, parts):
    """The runs of first .. first + count - 1 not in parts, as [(start, n), ...]."""
    out, at = [], first
    for start in sorted(parts):
        if start > at:
            out.append((at, start - at))
        at = max(at, start + len(parts[start]["status"]))
    if at < first + count:
        out.append((at, first + count - at))
    return out


# ---- the sweep -----------------------------------------------------------------------------

def run_on_dask(client, args, first, count, chunk_size=None, progress=None, checkpoint=None,
                identity=None):
    """The run_plan results of every chunk, in run order; with checkpoint (a directory) and
    identity (a dict: plan, first, count, columns), chunks on file are reused and new ones
    written there; the directory is removed once every chunk is in."""
    from distributed import as_completed

    if count == 0:
        return [_run_chunk(args, first, 0)]
    if chunk_size is None:
        workers = max(1, len(client.scheduler_info().get("workers", {})))
        chunk_size = max(1, math.ceil(count / (8 * workers)))
    kept = _open_checkpoint(checkpoint, identity) if checkpoint is not None else {}
    parts = [c for s, n in _gaps(first, count, kept) for c in chunks(s, n, int(chunk_size))]
    futures = [client.submit(_run_chunk, args, s, n, pure=False) for s, n in parts]
    index = {f.key: k for k, f in enumerate(futures)}
    results = dict(kept)
    done = sum(len(p["status"]) for p in kept.values())
    try:
        for fut in as_completed(futures):
            k = index[fut.key]
            start, n = parts[k]
            results[start] = fut.result()
            if checkpoint is not None:
                _write_atomic(os.path.join(checkpoint, f"{start}-{n}.json"),
                              _encode(results[start]))
            done += n
            if progress is not None:
                progress(done, count)
    except BaseException:
        client.cancel(futures)
        raise
    if checkpoint is not None:
        _remove_checkpoint(checkpoint)
    return [results[s] for s in sorted(results)]
