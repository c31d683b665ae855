"""Sweeps on a Dask cluster (appell.sweep(..., client=Client(...)); docs/sweeps.md).

The runs first .. first + count - 1 are cut into chunks of chunk_size consecutive runs; each
chunk is one task, appell._sweep._run_chunk, whose arguments carry the scene's text and the
plan's specs (a few kilobytes), so any worker can run any chunk and no shared file system is
needed. When a worker dies, the scheduler gives its unfinished chunks to another worker (up to
distributed's allowed-failures, 3 by default); a chunk's rows depend only on the plan and the
run indices, so a chunk run twice gives the same rows. The parts are put back in run order.
"""

import math

from ._sweep import _run_chunk


def chunks(first, count, chunk_size):
    """[(start, n), ...] covering first .. first + count - 1."""
    return [(s, min(chunk_size, first + count - s)) for s in range(first, first + count, chunk_size)]


def run_on_dask(client, args, first, count, chunk_size=None, progress=None):
    """The run_plan results of every chunk, in run order."""
    from distributed import as_completed

    if count == 0:
        return [_run_chunk(args, first, 0)]
    if chunk_size is None:
        workers = max(1, len(client.scheduler_info().get("workers", {})))
        chunk_size = max(1, math.ceil(count / (8 * workers)))
    parts = chunks(first, count, int(chunk_size))
    futures = [client.submit(_run_chunk, args, s, n, pure=False) for s, n in parts]
    index = {f.key: k for k, f in enumerate(futures)}
    results = [None] * len(parts)
    done = 0
    try:
        for fut in as_completed(futures):
            k = index[fut.key]
            results[k] = fut.result()
            done += parts[k][1]
            if progress is not None:
                progress(done, count)
    except BaseException:
        client.cancel(futures)
        raise
    return results
