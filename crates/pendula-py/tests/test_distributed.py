"""pendula.distributed on a real Dask cluster: a LocalCluster of two worker processes on
loopback, started and stopped here. Results equal the local calls byte for byte, also when a
worker process dies in the middle of the run."""

import math
import os
import signal
import threading
import time

import pytest

distributed = pytest.importorskip("distributed")

import pendula  # noqa: E402
import pendula.distributed  # noqa: E402


@pytest.fixture(scope="module")
def client():
    cluster = distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=None
    )
    c = distributed.Client(cluster)
    yield c
    c.close()
    cluster.close()


def test_a_distributed_fractal_is_the_local_one(client):
    kw = dict(theta1=(-3, 3, 48), theta2=(-2.5, 2.5, 37), t_max=8)
    local = pendula.fractal(**kw)
    remote = pendula.distributed.fractal(client, chunks=7, **kw)
    for name in ("flip_time", "flip_time_half_step", "converged"):
        assert getattr(remote, name).tobytes() == getattr(local, name).tobytes(), name
    assert remote.forbidden_by_energy == local.forbidden_by_energy > 0
    with pytest.raises(pendula.UnsuitableMethodError):
        pendula.distributed.fractal(client, method="verlet", **kw)


def test_a_distributed_sweep_is_the_local_one(client):
    args = ("double", ["theta1=-3:3:40", "theta2=-2:2:30"])
    kw = dict(dt=0.01, steps=400, until="flip", record=("final", "flip-time"))
    local = pendula.sweep(*args, **kw)
    remote = pendula.distributed.sweep(client, *args, chunks=5, **kw)
    assert remote.data.tobytes() == local.data.tobytes()
    assert remote.description["fingerprint"] == local.description["fingerprint"]


def test_sweep_array_is_lazy_and_the_local_sweep_block_by_block(client, tmp_path):
    import dask
    import dask.array as da

    grid = {"theta1": (-3, 3, 29), "theta2": (-2, 2, 17)}
    kw = dict(dt=0.01, steps=300, record=("final", "energy-error"))
    local = pendula.sweep("double", grid, **kw)
    a = pendula.distributed.sweep_array("double", grid, rows=4, **kw)
    assert isinstance(a, da.Array) and a.shape == local.data.shape == (17, 29, 5)
    assert a.chunks[0] == (4, 4, 4, 4, 1) and a.dtype == "float64"
    # Nothing is computed until asked: a slice's graph holds only the blocks it touches.
    (sliced,) = dask.optimize(a[5:7])
    assert sum(str(k).find("pendula-sweep") >= 0 for k in dict(sliced.__dask_graph__())) == 1
    # On the cluster (the client is the default scheduler): whole, sliced, and as .npy shards.
    assert a.compute().tobytes() == local.data.tobytes()
    assert sliced.compute().tobytes() == local.data[5:7].tobytes()
    da.to_npy_stack(tmp_path / "stack", a)
    assert sorted(p.name for p in (tmp_path / "stack").iterdir()) == ["0.npy", "1.npy", "2.npy", "3.npy", "4.npy", "info"]
    assert da.from_npy_stack(tmp_path / "stack").compute().tobytes() == local.data.tobytes()
    # A one-axis grid, and bad input refused before any block runs.
    one = pendula.distributed.sweep_array("pendulum", {"theta": (0, 1, 10)}, steps=5, rows=3)
    assert one.compute().tobytes() == pendula.sweep("pendulum", {"theta": (0, 1, 10)}, steps=5).data.tobytes()
    with pytest.raises(pendula.UnknownNameError, match="theta9"):
        pendula.distributed.sweep_array("double", {"theta9": (0, 1, 4)})
    with pytest.raises(pendula.InvalidValueError, match="rows"):
        pendula.distributed.sweep_array("double", grid, rows=0)
    with pytest.raises(pendula.InvalidValueError, match="shard"):
        pendula.distributed.sweep_array("double", grid, shard=(1, 2))


def test_a_worker_that_dies_mid_run_changes_no_bit(client):
    kw = dict(theta1=(-math.pi, math.pi, 160), theta2=(-math.pi, math.pi, 120), t_max=20)
    local = pendula.fractal(**kw)
    out = {}
    run = threading.Thread(target=lambda: out.setdefault("f", pendula.distributed.fractal(client, chunks=24, **kw)))
    run.start()
    # Once work is under way, one worker process is killed (SIGKILL); its nanny starts a new
    # one and Dask computes the lost parts again.
    deadline = time.time() + 30
    while not any(client.processing().values()) and time.time() < deadline:
        time.sleep(0.02)
    time.sleep(0.3)
    victim = next(iter(client.scheduler_info()["workers"]))
    pid = client.run(os.getpid, workers=[victim])[victim]
    assert run.is_alive(), "the run ended before a worker could be killed: make it longer"
    os.kill(pid, signal.SIGKILL)
    run.join(120)
    assert not run.is_alive()
    assert out["f"].flip_time.tobytes() == local.flip_time.tobytes()
    assert out["f"].converged.tobytes() == local.converged.tobytes()
