"""What a worker process of a local Dask cluster does first (:func:`gaitcli.run.cluster.workers`): it ends with
the process that started the cluster and leaves interrupts to it, as the process pool's workers do. A module
of its own, imported only where Dask is installed: the worker finds the plugin's class here by name."""

from __future__ import annotations

from distributed import WorkerPlugin

from gaitcli.core.interrupts import as_worker


class AsWorker(WorkerPlugin):
    """:func:`gaitcli.core.interrupts.as_worker` at each worker's start (in its main thread)."""

    name = "gaitcli-as-worker"

    def __init__(self, parent_pid: int):
        self.parent_pid = parent_pid

    def setup(self, worker) -> None:
        as_worker(self.parent_pid)
