"""Sweeps on a Dask cluster: a LocalCluster of 2 worker processes gives the table of the local
run; killing a worker in the middle of a sweep loses no run (Dask reschedules its chunks)."""

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
