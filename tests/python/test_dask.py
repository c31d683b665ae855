"""Sweeps on a Dask cluster: a LocalCluster of 2 worker processes gives the table of the local
run; killing a worker in the middle of a sweep loses no run (Dask reschedules its chunks); a
sweep whose client is lost resumes from its checkpoint with the same table."""

import os
import signal
import time

import numpy as np
import pytest

import appell

distributed = pytest.importorskip("distributed")


@pytest.fixture(scope="module")
def client():
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                       dashboard_address=None, silence_logs=40)
    c = distributed.Client(cluster)
    yield c
    c.close()
    cluster.close()


def _same(a, b):
    assert a.columns == b.columns and a.runs == b.runs
    for col in a.columns:
        if a[col].dtype == object:
            assert list(a[col]) == list(b[col]), col
        else:
            assert np.array_equal(a[col], b[col], equal_nan=True), col


def _args(t_end):
    return dict(grid={"initial.disk.tilt": "60*deg:89*deg:6", "bodies.disk.mass": [1, -1, 2]},
                random={"initial.disk.spin_rate": "uniform(-8,-4)"}, samples=2, seed=5,
                set={"simulation.t_end": t_end, "simulation.rtol": 1e-9},
                channels=["disk.tilt"], times=[0.5, t_end])


def test_dask_equals_local(client, disk):
    local = appell.sweep(disk, jobs=2, **_args(1.0))
    remote = appell.sweep(disk, client=client, chunk_size=5, **_args(1.0))
    _same(local, remote)
    assert len(local.failed) == 12   # mass -1: rows with the scene's message, on Dask too
    assert "must be positive" in remote["message"][local.failed[0]]


def test_a_bad_path_fails_before_any_chunk(client, disk):
    # The chunks skip the plan's check: every run came back as a failed row instead.
    with pytest.raises(appell.SceneError, match="did you mean 'mass'"):
        appell.sweep(disk, grid={"bodies.disk.mas": [1, 2]}, client=client)


def test_killed_worker_loses_no_run(client, disk):
    args = _args(20.0)                     # 36 runs of about 30 ms; chunks of 2 runs
    local = appell.sweep(disk, jobs=2, **args)
    pids = client.run(os.getpid)           # {worker address: process id}
    killed = {}

    def progress(done, total):
        if not killed and done > 0:        # first chunk back: the sweep is under way
            addr, pid = sorted(pids.items())[0]
            os.kill(pid, signal.SIGKILL)
            killed.update(addr=addr, pid=pid, done=done, total=total)

    remote = appell.sweep(disk, client=client, chunk_size=2, progress=progress, **args)
    assert killed and killed["done"] < killed["total"]
    _same(local, remote)
    # the scheduler took chunks back from the dead worker and ran them again elsewhere
    lost = client.run_on_scheduler(lambda dask_scheduler: [
        e[0] for e in dask_scheduler.transition_log
        if str(e[0]).startswith("_run_chunk") and e[1] == "processing" and e[2] == "released"
        and "worker-cleanup" in str(e[4])])
    assert len(lost) >= 1
    for _ in range(100):                   # the nanny starts a new worker process
        now = client.run(os.getpid)
        if len(now) == 2:
            break
        time.sleep(0.1)
    assert killed["pid"] not in client.run(os.getpid).values()


class _Lost(Exception):
    """The client lost in the middle of a sweep (raised from the progress callback)."""


def test_checkpoint_resumes_after_a_lost_client(client, disk, tmp_path):
    args = _args(1.0)                      # 36 runs, chunks of 4: 9 chunks
    local = appell.sweep(disk, jobs=2, **args)
    ck = tmp_path / "ck"
    seen = []

    def lose(done, total):
        seen.append(done)
        if len(seen) == 3:                 # three chunks on file, then the client is gone
            raise _Lost()

    with pytest.raises(_Lost):
        appell.sweep(disk, client=client, chunk_size=4, progress=lose, checkpoint=ck, **args)
    kept = sorted(p.name for p in ck.iterdir() if p.name != "sweep.json")
    assert len(kept) == 3 and all(p.endswith(".json") for p in kept)
    calls = []
    resumed = appell.sweep(disk, client=client, chunk_size=5, checkpoint=ck,
                           progress=lambda d, t: calls.append((d, t)), **args)
    _same(local, resumed)
    # only the 24 runs not on file ran again: the first report already counts the 12 kept
    assert calls[0][0] >= 12 + 1 and calls[-1] == (36, 36) and len(calls) <= 6
    assert not ck.exists()


def test_checkpoint_of_another_sweep_is_refused(client, disk, tmp_path):
    ck = tmp_path / "ck"
    args = _args(1.0)

    def stop(done, total):
        raise _Lost()

    with pytest.raises(_Lost):
        appell.sweep(disk, client=client, chunk_size=4, progress=stop, checkpoint=ck, **args)
    other = dict(args, seed=6)
    with pytest.raises(ValueError, match="holds another sweep"):
        appell.sweep(disk, client=client, checkpoint=ck, **other)
    with pytest.raises(ValueError, match="needs a Dask client"):
        appell.sweep(disk, checkpoint=ck, **args)
