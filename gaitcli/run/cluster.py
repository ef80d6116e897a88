"""The one way gait runs work in parallel: ``gait batch``'s trials, a study's cases and ``gait predict --starts``.

:func:`workers` gives a :class:`Workers`, a ``concurrent.futures`` executor on

- the Dask cluster at ``scheduler`` (its workers may be other machines'),
- this process, for one worker (no other process to start or stop),
- a local Dask cluster of single-threaded worker processes, where Dask's distributed scheduler is installed
  (``pip install 'gaitcli[dist]'``),
- else the standard library's process pool (forked where the platform allows);

and :func:`completed` runs a graph of tasks on it, each once the tasks it needs are done. Local worker
processes end with their parent and leave interrupts to it (:func:`gaitcli.core.interrupts.as_worker`). On
Ctrl-C or SIGTERM the parent ends them at once, so that nothing is written after the signal: Dask's by
SIGKILL (a task runs in a thread of the worker, which no signal unwinds), the pool's by SIGTERM, which
unwinds the task and its atomic writes, then SIGKILL after :data:`STOP_GRACE_S`. A write that a kill cuts
short leaves a hidden ``.part`` file, which the caller removes (:func:`gaitcli.io.atomic.remove_stale`). A
remote cluster's tasks are cancelled; one already running there runs to its end.
"""

from __future__ import annotations

import gc
import logging
import multiprocessing
import os
import time
import warnings
from collections.abc import Callable, Hashable, Iterator, Mapping, Sequence
from concurrent.futures import FIRST_COMPLETED, Executor, Future, ProcessPoolExecutor, wait
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any

from gaitcli.core.interrupts import as_worker, interrupts_deferred
from gaitcli.errors import InputError

#: how often a task may be on a worker that dies before it counts as failed (1: retried once; Dask only)
ALLOWED_WORKER_DEATHS = 1
#: how long the pool's workers get to unwind (remove their temporary folders) before they are killed, s
STOP_GRACE_S = 1.0
#: s, the longest the main thread waits on the workers at a time: Python runs a signal's handler in the main
#: thread, and a SIGTERM the kernel delivers to another thread (Dask's event loop, a queue feeder) does not
#: wake a main thread blocked in an untimed wait: one such SIGTERM was lost, the study running on
SIGNAL_POLL_S = 0.2


class InProcess(Executor):
    """An executor that runs each task in this process as it is submitted (one worker)."""

    def submit(self, fn, /, *args, **kwargs) -> Future:
        future: Future = Future()
        try:
            value = fn(*args, **kwargs)
        except Exception as exc:  # the task's failure is its future's; an interrupt is the run's
            future.set_exception(exc)
        else:
            future.set_result(value)
        return future


@dataclass
class Workers:
    """Where tasks run: ``executor`` (``submit(fn, *args)`` → a ``concurrent.futures.Future``), how many tasks
    run at once (``size``), what it is (``kind``: "remote", "this process", "dask", "processes") and the
    Dask dashboard's address when one was asked for."""

    executor: Executor
    size: int
    kind: str
    dashboard: str | None = None

    def submit(self, fn: Callable, /, *args) -> Future:
        return self.executor.submit(fn, *args)


@dataclass(frozen=True)
class Task:
    """One task of :func:`completed`: ``fn(*args, *results of needs)``."""

    fn: Callable
    args: tuple = ()
    needs: tuple[Hashable, ...] = field(default=())


def completed(pool: Workers, tasks: Mapping[Hashable, Task], *, in_flight: int | None = None,
              ) -> Iterator[tuple[Hashable, Future]]:
    """Run ``tasks`` on ``pool``, each once the tasks it ``needs`` are done (their results its last arguments),
    at most ``in_flight`` at once (default: every one that is ready), in the mapping's order where they are
    ready together; yields (key, future) as each ends. A task whose need failed is not run: its future holds
    that failure."""
    waiting = dict(tasks)
    users = {key: sum(key in t.needs for t in tasks.values()) for key in tasks}
    results: dict[Hashable, Any] = {}
    failed: dict[Hashable, BaseException] = {}
    pending: dict[Future, Hashable] = {}
    # in this process a task runs as it is submitted: one at a time, so that each is reported as it ends
    limit = 1 if isinstance(pool.executor, InProcess) else (in_flight or len(tasks) or 1)

    def submit_ready() -> list[tuple[Hashable, Future]]:
        skipped = []
        for key in list(waiting):
            if len(pending) >= limit:
                break
            task = waiting[key]
            lost = next((failed[n] for n in task.needs if n in failed), None)
            if lost is not None:
                del waiting[key]
                future: Future = Future()
                future.set_exception(lost)
                failed[key] = lost
                skipped.append((key, future))
            elif all(n in results for n in task.needs):
                del waiting[key]
                pending[pool.submit(task.fn, *task.args, *(results[n] for n in task.needs))] = key
                for n in task.needs:  # a result no task still waits for is let go
                    users[n] -= 1
                    if not users[n]:
                        del results[n]
        return skipped

    yield from submit_ready()
    while pending:
        done: set = set()
        while not done:  # in short waits: a signal the kernel gave another thread runs its handler here
            done, _ = wait(list(pending), timeout=SIGNAL_POLL_S, return_when=FIRST_COMPLETED)
        for future in sorted(done, key=lambda f: list(pending).index(f)):
            key = pending.pop(future)
            if future.exception() is not None:
                failed[key] = future.exception()
            elif users[key]:
                results[key] = future.result()
            yield key, future
        yield from submit_ready()
        while waiting and not pending:  # only tasks whose needs failed are left
            skipped = submit_ready()
            if not skipped:
                raise RuntimeError(f"tasks that need tasks not given: {sorted(map(str, waiting))}")
            yield from skipped


def dask_installed() -> bool:
    """Whether Dask's distributed scheduler can be imported (the ``dist`` extra)."""
    try:
        import distributed  # noqa: F401
    except ImportError:
        return False
    return True


@contextmanager
def workers(count: int | None = None, scheduler: str | None = None, *, dashboard: bool = False,
            dask: bool | None = None) -> Iterator[Workers]:
    """:class:`Workers` for ``count`` tasks at once (default: one per CPU), or on the Dask cluster at
    ``scheduler`` (module docstring). ``dashboard``: a local Dask cluster serves its dashboard; ``dask``: local
    workers of Dask (True) or of the process pool (False) rather than by what is installed. On an interrupt or
    an error in the block every local worker is ended and the exception goes on."""
    if scheduler is not None:
        with _remote(scheduler) as pool:
            yield pool
        return
    count = max(1, count or os.cpu_count() or 1)
    if count == 1:
        yield Workers(InProcess(), 1, "this process")
        return
    before = set(multiprocessing.active_children())
    if dask_installed() if dask is None else dask:
        with _local_dask(count, dashboard, before) as pool:
            yield pool
        return
    method = "fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn"
    executor = ProcessPoolExecutor(max_workers=count, mp_context=multiprocessing.get_context(method),
                                   initializer=as_worker, initargs=(os.getpid(),))
    try:
        yield Workers(executor, count, "processes")
    except BaseException:
        _stop_processes(executor, before)
        raise
    executor.shutdown(wait=True)


def _started_since(before: set) -> list:
    """The multiprocessing children of this process started since ``before`` (the workers)."""
    return [p for p in multiprocessing.active_children() if p not in before]


def _stop_processes(executor: ProcessPoolExecutor, before: set) -> None:
    """End the pool's workers now: SIGTERM before the task queue closes (an idle worker reading a closed queue
    dies of EOFError, loudly), the queued tasks cancelled, SIGKILL for any still running after the grace."""
    processes = _started_since(before)
    # the pool's manager thread, which shutdown(wait=False) lets go on: joined below, once the workers are gone,
    # so that it has closed its wake-up pipe before the interpreter's exit hook writes to it (CPython's
    # concurrent.futures at exit: "Exception ignored … Bad file descriptor")
    manager = getattr(executor, "_executor_manager_thread", None)
    for process in processes:
        process.terminate()
    executor.shutdown(wait=False, cancel_futures=True)
    deadline = time.monotonic() + STOP_GRACE_S
    for process in processes:
        process.join(max(0.0, deadline - time.monotonic()))
        if process.is_alive():
            process.kill()
            process.join(1.0)
    if manager is not None:
        manager.join(STOP_GRACE_S)


@contextmanager
def _remote(scheduler: str) -> Iterator[Workers]:
    try:
        from distributed import Client
    except ImportError:
        raise InputError(None, "--scheduler", "needs Dask's distributed scheduler (expected: pip install "
                                               "'gaitcli[dist]')") from None
    failure = None
    try:
        client = Client(scheduler, timeout="10s")
    except ValueError as exc:  # distributed's own message names the schemes it knows
        failure = f"got {scheduler!r}: {exc} (expected an address such as tcp://HOST:8786)"
    except (OSError, TimeoutError) as exc:
        failure = f"cannot reach the Dask scheduler at {scheduler} ({exc})"
    if failure is not None:
        # the half-made client keeps its IO-loop thread running until the collector finds it (its traceback's
        # frames hold it in a cycle); found later, in a C3D reader forked meanwhile where that thread is gone, its
        # close waits out its 20 s timeout before the read (a process that goes on: gaitcli.api, a test runner)
        gc.collect()
        raise InputError(None, "--scheduler", failure)
    executor = client.get_executor(pure=False)
    try:
        services = client.scheduler_info().get("services", {})
        size = max(1, sum(w.get("nthreads", 1) for w in client.scheduler_info().get("workers", {}).values()))
        yield Workers(executor, size, "remote", client.dashboard_link if "dashboard" in services else None)
    except BaseException:
        executor.shutdown(wait=False)  # cancels what has not started
        raise
    finally:
        client.close()


@contextmanager
def _local_dask(count: int, dashboard: bool, before: set) -> Iterator[Workers]:
    """A local Dask cluster of ``count`` single-threaded worker processes (non-daemonic: a trial's C3D is read
    in a child of its worker), each ending with this process (:mod:`gaitcli.run.dask_workers`)."""
    import dask
    from distributed import Client, LocalCluster

    from gaitcli.run.dask_workers import AsWorker

    settings = {"distributed.scheduler.allowed-failures": ALLOWED_WORKER_DEATHS, "distributed.worker.daemon": False}
    with dask.config.set(settings):
        with interrupts_deferred(), warnings.catch_warnings():
            warnings.simplefilter("ignore")  # distributed's port and memory notices are not the lab's business
            # CRITICAL only: a worker's heartbeat racing the scheduler's shutdown is logged at ERROR with a
            # traceback; a task's own failure comes back through its future, a dead worker through the retry.
            # No workers yet: the scheduler starts at once, the workers in the background (scale), so that
            # an interrupt meets a cluster it can stop
            cluster = LocalCluster(n_workers=0, threads_per_worker=1, processes=True, silence_logs=logging.CRITICAL,
                                   dashboard_address="127.0.0.1:0" if dashboard else None)
            client = Client(cluster)
            client.register_plugin(AsWorker(os.getpid()))
            cluster.scale(count)
        try:
            services = client.scheduler_info().get("services", {})
            yield Workers(client.get_executor(pure=False), count, "dask",
                          client.dashboard_link if "dashboard" in services else None)
        except BaseException:
            _stop_dask(cluster, client, before)
            raise
        client.close()
        cluster.close()


def _stop_dask(cluster, client, before: set) -> None:
    """End a local cluster now: no nanny restarts its worker, every worker process is killed, then the
    cluster closes (quickly: nothing is left to wait for; a close that does not end in time is abandoned:
    its workers are gone). distributed's own loggers are silenced first: the comms its killed workers
    leave closed are logged with a traceback, which is no news to a lab that pressed Ctrl-C."""
    logging.getLogger("distributed").setLevel(logging.CRITICAL)
    for nanny in list(cluster.workers.values()):
        nanny.close_gracefully()
    for process in _started_since(before):
        process.kill()
    for close in (client.close, cluster.close):
        try:
            close(timeout=STOP_GRACE_S)
        except Exception:  # noqa: BLE001 (distributed's TimeoutError, or a comm already gone)
            pass
    for process in _started_since(before):  # one a nanny started in between
        process.kill()
        process.join(STOP_GRACE_S)
    # a close that timed out would be retried at exit by distributed, which waits up to 10 s there for the
    # workers just killed: the interrupted command would hang that long
    from distributed.deploy.spec import SpecCluster
    SpecCluster._instances.discard(cluster)


def map_in_order(pool: Workers, fn: Callable, items: Sequence, *, on_done: Callable[[int, Any], None] | None = None,
                 ) -> list:
    """``[fn(item) for item in items]`` on ``pool``; ``on_done(index, result)`` as each ends."""
    out: list = [None] * len(items)
    for k, future in completed(pool, {k: Task(fn, (item,)) for k, item in enumerate(items)}):
        out[k] = future.result()
        if on_done is not None:
            on_done(k, out[k])
    return out
