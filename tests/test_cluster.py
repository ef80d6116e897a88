"""The one way gait runs work in parallel (gaitcli/run/cluster.py): a graph of tasks run in the order of what they
need, on this process, the process pool or a local Dask cluster; an interrupt ends every worker at once and a
parent killed outright leaves none behind."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from gaitcli.run.cluster import InProcess, Task, Workers, completed, dask_installed, map_in_order, workers

BACKENDS = [pytest.param(False, id="processes"),
            pytest.param(True, id="dask", marks=pytest.mark.skipif(not dask_installed(), reason="no dask installed"))]


def _add(*values):
    return sum(values)


def _fail(*values):
    raise ValueError("bad case")


def test_tasks_run_after_what_they_need_with_its_results_as_their_last_arguments():
    # a chain a → b → c beside d; b also needs d: the order is the mapping's where tasks are ready together
    tasks = {"a": Task(_add, (1,)), "d": Task(_add, (10,)), "b": Task(_add, (100,), ("a", "d")),
             "c": Task(_add, (1000,), ("b",))}
    with workers(1) as here:
        done = [(key, future.result()) for key, future in completed(here, tasks)]
    assert done == [("a", 1), ("d", 10), ("b", 111), ("c", 1111)]


@pytest.mark.parametrize("dask", BACKENDS)
def test_other_processes_run_tasks_after_what_they_need(dask):
    """The same chain on two worker processes (a study's prosthesis case waits for its normal case's future)."""
    tasks = {"a": Task(_add, (1,)), "d": Task(_add, (10,)), "b": Task(_add, (100,), ("a", "d")),
             "c": Task(_add, (1000,), ("b",))}
    with workers(2, dask=dask) as pool:
        done = dict((key, future.result()) for key, future in completed(pool, tasks))
    assert done == {"a": 1, "d": 10, "b": 111, "c": 1111}


def test_a_failed_task_fails_the_tasks_that_need_it_without_running_them():
    calls = []

    def counted(*values):
        calls.append(values)
        return sum(values)

    tasks = {"a": Task(_fail, (1,)), "b": Task(counted, (2,), ("a",)), "c": Task(counted, (3,))}
    with workers(1) as here:
        outcome = {key: future.exception() for key, future in completed(here, tasks)}
    assert isinstance(outcome["a"], ValueError) and outcome["b"] is outcome["a"] and outcome["c"] is None
    assert calls == [(3,)]


def test_no_more_than_in_flight_tasks_run_at_once():
    running, most = [0], [0]

    def slow(k):
        running[0] += 1
        most[0] = max(most[0], running[0])
        time.sleep(0.05)
        running[0] -= 1
        return k

    with ThreadPoolExecutor(4) as executor:
        pool = Workers(executor, 4, "threads")
        keys = [key for key, _ in completed(pool, {k: Task(slow, (k,)) for k in range(8)}, in_flight=2)]
    assert sorted(keys) == list(range(8)) and most[0] == 2


def test_one_worker_is_this_process():
    with workers(1) as here:
        assert isinstance(here.executor, InProcess) and here.size == 1
        assert map_in_order(here, os.getpid, [()] * 0) == []
        assert here.submit(os.getpid).result() == os.getpid()


@pytest.mark.skipif(not dask_installed(), reason="no dask installed")
def test_a_scheduler_not_reached_leaves_no_thread_behind():
    """distributed's half-made client runs its IO loop in a thread until collected; left running, a C3D reader
    forked later found the client and waited 20 s to close it (a gait runner's every later read)."""
    import threading

    from gaitcli.errors import InputError

    before = set(threading.enumerate())
    with pytest.raises(InputError, match="--scheduler.*unknown address scheme"):
        with workers(scheduler="nonsense://x"):
            pass
    assert set(threading.enumerate()) <= before


@pytest.mark.parametrize("dask", BACKENDS)
def test_workers_run_tasks_in_other_processes(dask):
    with workers(2, dask=dask) as pool:
        pids = map_in_order(pool, _pid_after, [0.2, 0.2, 0.2])
    assert os.getpid() not in pids and len(set(pids)) <= 2


def _pid_after(delay_s: float) -> int:
    time.sleep(delay_s)
    return os.getpid()


#: a parent with two workers busy for a minute, which prints their pids once both run a task (each task leaves
#: a file named by its process's pid as it starts)
PARENT = textwrap.dedent("""
    import multiprocessing, os, sys, time
    from pathlib import Path
    from gaitcli.core.interrupts import terminate_as_interrupt
    from gaitcli.run.cluster import workers

    def busy(folder):
        (Path(folder) / f"{{os.getpid()}}.running").touch()
        time.sleep(60)

    if __name__ == "__main__":  # not again in a worker that Dask spawns
        with terminate_as_interrupt():
            try:
                with workers(2, dask={dask}) as pool:
                    futures = [pool.submit(busy, os.getcwd()) for _ in range(4)]
                    deadline = time.monotonic() + 60
                    while len(list(Path.cwd().glob("*.running"))) < 2 and time.monotonic() < deadline:
                        time.sleep(0.02)
                    print(" ".join(str(p.pid) for p in multiprocessing.active_children()), flush=True)
                    time.sleep(60)
            except KeyboardInterrupt:
                sys.exit(130)
""")


def _start_parent(tmp_path: Path, dask: bool) -> tuple[subprocess.Popen, list[int]]:
    script = tmp_path / "parent.py"
    script.write_text(PARENT.format(dask=dask))
    parent = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                              text=True, cwd=tmp_path)
    return parent, [int(p) for p in parent.stdout.readline().split()]


def _alive(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except FileNotFoundError:
        return False


def _gone(pids: list[int], timeout_s: float = 10.0) -> bool:
    deadline = time.monotonic() + timeout_s
    while any(_alive(p) for p in pids) and time.monotonic() < deadline:
        time.sleep(0.05)
    return not any(_alive(p) for p in pids)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc; PR_SET_PDEATHSIG is Linux's")
@pytest.mark.parametrize("dask", BACKENDS)
def test_sigterm_ends_the_workers_at_once(tmp_path, dask):
    parent, pids = _start_parent(tmp_path, dask)
    assert len(pids) >= 2, parent.communicate()[1]
    parent.send_signal(signal.SIGTERM)
    # the parent ends long before its workers' 60-s tasks would (the communicate's limit), and the two queued
    # tasks never start
    _, stderr = parent.communicate(timeout=30)
    assert parent.returncode == 130 and "Traceback" not in stderr, stderr
    assert _gone(pids)
    assert len(list(tmp_path.glob("*.running"))) == 2


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc; PR_SET_PDEATHSIG is Linux's")
@pytest.mark.parametrize("dask", BACKENDS)
def test_workers_end_when_their_parent_is_killed(tmp_path, dask):
    """A parent killed outright (SIGKILL: no chance to stop its workers) leaves no worker solving the rest of the
    queue: the kernel ends them with it."""
    parent, pids = _start_parent(tmp_path, dask)
    assert len(pids) >= 2, parent.communicate()[1]
    os.kill(parent.pid, signal.SIGKILL)
    parent.communicate(timeout=10)
    assert _gone(pids)
