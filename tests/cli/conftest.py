"""Helpers for the CLI tests: run the real ``gait`` command in a subprocess on copies of trials.

Every CLI test works on a copy of a bundled sample trial (or of a shared C3D file)
under pytest's tmp_path; nothing is ever written into ``sample_trials/``. The
expensive runs (a full ``gait filter`` takes a few seconds: imports, the stage and
the plots) are made once per session and several at a time, since each one is a
separate process; under pytest-xdist the first worker to need them makes them and the
others read what it recorded (:func:`build_once`).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import queue
import shutil
import signal
import socket
import subprocess
import sys
import threading
import time
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import pytest

from gaitcli.resources import sample_trial

ENV = {**os.environ, "MPLBACKEND": "Agg", "PYTHONWARNINGS": "ignore::DeprecationWarning",
       "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
WORKERS = max(2, min(4, os.cpu_count() or 2))
#: the bundled sample trials (sample_trials/README.md)
SAMPLES = ("normal", "ankle_weight", "knee_orthosis", "ankle_fixed", "ski_boot")
FILTER_FILES = ("markers_filtered.csv", "grf.csv", "events.csv", "filter.h5", "summary.json")
#: the eight muscles of Table A.1 (Diss. appendix A.1), in the model's order
MUSCLES = ("iliopsoas", "rectus_femoris", "glutei", "hamstrings", "vasti", "gastrocnemius", "tibialis_anterior",
           "soleus")
MUSCLE_FILES = ("forces.csv", "activations.csv", "excitations.csv", "metabolics.csv", "muscles.h5", "summary.json")
#: DESIGN.md's summary.json keys of the muscle stage
MUSCLE_SUMMARY_KEYS = ("method", "nodes", "solve_time_s", "converged", "metabolic_cost_J",
                       "cost_of_transport_J_per_m", "min_excitation", "max_excitation", "max_moment_error_Nm")
MINIMAL_SUBJECT = "mass_kg: 70.0\nstature_m: 1.70\nsex: male\n"


@dataclass
class Result:
    """One finished ``gait`` invocation."""

    args: tuple[str, ...]
    returncode: int
    stdout: str
    stderr: str
    cwd: Path

    @property
    def stderr_lines(self) -> list[str]:
        return [line for line in self.stderr.splitlines() if line.strip()]

    def to_json(self) -> dict:
        return {**dataclasses.asdict(self), "args": list(self.args), "cwd": str(self.cwd)}

    @classmethod
    def from_json(cls, data: dict) -> Result:
        return cls(tuple(data["args"]), data["returncode"], data["stdout"], data["stderr"], Path(data["cwd"]))

    def describe(self) -> str:
        return (f"gait {' '.join(self.args)} (in {self.cwd}) -> {self.returncode}\n"
                f"stdout:\n{self.stdout}\nstderr:\n{self.stderr}")


def gait(*args, cwd: Path, timeout_s: float = 180.0) -> Result:
    """Run ``python -m gaitcli.cli ARGS`` (the installed ``gait`` command's code) in ``cwd``."""
    args = tuple(str(a) for a in args)
    done = subprocess.run([sys.executable, "-m", "gaitcli.cli", *args], cwd=cwd, env=ENV, capture_output=True,
                          text=True, timeout=timeout_s)
    return Result(args, done.returncode, done.stdout, done.stderr, Path(cwd))


#: a fresh interpreter that imports gaitcli once and then runs ``gait`` invocations one after another (one JSON
#: line in, one out), each in its working folder with its own stdout/stderr, as the console script does
_RUNNER = """
import contextlib, io, json, os, sys
from gaitcli.cli import main
for line in sys.stdin:
    args, cwd = json.loads(line)
    os.chdir(cwd)
    stdout, stderr = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(stderr):
        code = main(args)
    sys.__stdout__.write(json.dumps([code, stdout.getvalue(), stderr.getvalue()]) + "\\n")
    sys.__stdout__.flush()
"""


def _runner_loop(todo: queue.Queue, done: dict, timeout_s: float) -> None:
    """One runner process: take jobs off ``todo`` until it is empty, put each Result into ``done``."""
    proc = subprocess.Popen([sys.executable, "-c", _RUNNER], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, env=ENV, text=True)
    timer = threading.Timer(timeout_s, proc.kill)
    timer.start()
    try:
        while True:
            try:
                key, (args, cwd) = todo.get_nowait()
            except queue.Empty:
                break
            args = tuple(str(a) for a in args)
            proc.stdin.write(json.dumps([list(args), str(cwd)]) + "\n")
            proc.stdin.flush()
            line = proc.stdout.readline()
            if not line:
                raise RuntimeError(f"the gait runner process died running gait {' '.join(args)}:\n"
                                   f"{proc.stderr.read()}")
            code, stdout, stderr = json.loads(line)
            done[key] = Result(args, code, stdout, stderr, Path(cwd))
    finally:
        timer.cancel()
        proc.stdin.close()
        proc.wait()


def gait_many(jobs: dict, *, timeout_s: float = 600.0, workers: int = WORKERS) -> dict:
    """Run several ``gait`` invocations: ``{key: (args, cwd)}`` → ``{key: Result}``.

    ``workers`` processes each import gaitcli once and take the next job when done with one (put the
    longest first); with ``workers=1`` the jobs run in the order given, one after the other.
    """
    todo: queue.Queue = queue.Queue()
    for item in jobs.items():
        todo.put(item)
    done: dict = {}
    threads = [threading.Thread(target=_runner_loop, args=(todo, done, timeout_s))
               for _ in range(max(1, min(workers, len(jobs))))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    missing = [k for k in jobs if k not in done]
    if missing:
        raise RuntimeError(f"gait runs without a result: {missing}")
    return {key: done[key] for key in jobs}


def copy_sample(name: str, dest: Path) -> Path:
    """A copy of the bundled sample trial ``name`` (trial.c3d, static.c3d, subject.yaml, truth/) at ``dest``."""
    shutil.copytree(sample_trial(name), dest, ignore=shutil.ignore_patterns("gait_out", "__pycache__"))
    return dest


def snapshot(folder: Path) -> dict[str, str]:
    """Relative path → SHA-256 of every file below ``folder`` (and '<dir>' for every folder)."""
    out = {}
    for path in sorted(Path(folder).rglob("*")):
        if "__pycache__" in path.parts:
            continue
        rel = path.relative_to(folder).as_posix()
        out[rel] = "<dir>" if path.is_dir() else hashlib.sha256(path.read_bytes()).hexdigest()
    return out


@contextmanager
def _exclusive(lock: Path, timeout_s: float = 900.0):
    """Hold ``lock`` (a file created exclusively) for the duration; wait for another holder to finish."""
    start = time.monotonic()
    while True:
        try:
            fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
            break
        except FileExistsError:
            if time.monotonic() - start > timeout_s:
                raise TimeoutError(f"{lock} held for more than {timeout_s:g} s") from None
            time.sleep(0.05)
    try:
        yield
    finally:
        os.close(fd)
        lock.unlink()


def build_once(tmp_path_factory, name: str, build) -> tuple[Path, dict]:
    """Run ``build(root) -> JSON-able dict`` once per test session, shared by all xdist workers.

    Returns ``root`` (the folder ``build`` filled) and what ``build`` returned.
    """
    base = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        base = base.parent  # shared by the workers of one session
    root = base / name
    record = base / f"{name}.json"
    with _exclusive(base / f"{name}.lock"):
        if not record.is_file():
            if root.exists():
                shutil.rmtree(root)
            root.mkdir()
            record.write_text(json.dumps(build(root)))
    return root, json.loads(record.read_text())


# ------------------------------------------------------------------ a real Dask scheduler and workers

def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture(scope="module")
def dask_cluster():
    """``dask scheduler`` and ``dask worker`` (two single-threaded worker processes under their nannies) as
    separate processes on 127.0.0.1; the scheduler lets a task's worker die once (allowed-failures 1)."""
    port = _free_port()
    address = f"tcp://127.0.0.1:{port}"
    env = {**ENV, "DASK_DISTRIBUTED__SCHEDULER__ALLOWED_FAILURES": "1"}
    dask = [sys.executable, "-m", "distributed.cli.dask_scheduler"]
    scheduler = subprocess.Popen(dask + ["--host", "127.0.0.1", "--port", str(port), "--no-dashboard"], env=env,
                                 stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    worker = subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker", address, "--nworkers", "2",
                               "--nthreads", "1", "--no-dashboard"], env=env, stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL, start_new_session=True)
    from distributed import Client

    client = Client(address, timeout="30s")
    client.wait_for_workers(2, timeout=60)
    try:
        yield address, client
    finally:
        client.close()
        for proc in (worker, scheduler):
            os.killpg(proc.pid, signal.SIGTERM)
        for proc in (worker, scheduler):
            try:
                proc.wait(20)
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, signal.SIGKILL)
