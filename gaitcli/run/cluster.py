"""A Dask client for the work that spreads over a cluster (``gait batch``, study grids and starts on
``--scheduler``): a local cluster of single-threaded worker processes, or an existing cluster by address."""

from __future__ import annotations

import logging
import warnings
from collections.abc import Iterator
from contextlib import contextmanager

from gaitcli.errors import InputError

#: how often a task may be on a worker that dies before it counts as failed (1: retried once)
ALLOWED_WORKER_DEATHS = 1


@contextmanager
def dask_client(workers: int, scheduler: str | None) -> Iterator:
    """A Dask client: on a local cluster of ``workers`` single-threaded worker processes, or on the cluster at
    ``scheduler``."""
    try:
        import dask
        from distributed import Client, LocalCluster
    except ImportError:
        raise InputError(None, "--scheduler" if scheduler else "--workers",
                         "needs Dask's distributed scheduler (expected: pip install 'gaitcli[dist]')") from None

    if scheduler is not None:
        try:
            client = Client(scheduler, timeout="10s")
        except (OSError, TimeoutError) as exc:
            raise InputError(None, "--scheduler", f"cannot reach the Dask scheduler at {scheduler} ({exc})") from None
        try:
            yield client
        finally:
            client.close()
        return
    with dask.config.set({"distributed.scheduler.allowed-failures": ALLOWED_WORKER_DEATHS,
                          "distributed.worker.daemon": False}):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # distributed's port and memory notices are not the lab's business
            # CRITICAL only: a worker's heartbeat racing the scheduler's shutdown is logged at ERROR with a
            # traceback (seen in CI on a loaded machine, the batch itself fine); a task's own failure comes back
            # through its future and a dead worker through the batch's retry, both reported by the batch
            cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                   dashboard_address="127.0.0.1:0", silence_logs=logging.CRITICAL)
        try:
            with Client(cluster) as client:
                yield client
        finally:
            cluster.close()
