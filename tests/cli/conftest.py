"""Helpers for the CLI tests: run the real ``gait`` command in other processes on copies of trials.

Every CLI test works on a copy of a bundled sample trial (or of a shared C3D file)
under pytest's tmp_path; nothing is ever written into ``sample_trials/``. The commands run in
runner processes that call ``gaitcli.cli.main`` (what the console script calls) once per job and
are kept for the session, so that gaitcli is imported once per runner, not once per command
(:class:`Runner`, :func:`gait_many`; :func:`gait` with ``fresh`` starts a new process where a test
needs one). The expensive runs (a full ``gait filter`` takes a few seconds: the stage and the plots)
are made once per session and several at a time; under pytest-xdist the first worker to need them
makes them and the others read what it recorded (:func:`build_once`).
"""

from __future__ import annotations

import atexit
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
import tempfile
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
#: the muscle stage's summary.json keys (README.md's outputs table)
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


def gait(*args, cwd: Path, timeout_s: float = 180.0, fresh: bool = False) -> Result:
    """Run ``gait ARGS`` in ``cwd``: in one of this test process's runner processes (:func:`gait_many`), or with
    ``fresh`` in a new ``python -m gaitcli`` process (the installed command's code, imports included): for a
    test that times the run to aim a signal at a later one, itself a new process."""
    args = tuple(str(a) for a in args)
    if not fresh:
        return gait_many({"run": (args, cwd)}, timeout_s=timeout_s, workers=1)["run"]
    done = subprocess.run([sys.executable, "-m", "gaitcli", *args], cwd=cwd, env=ENV, capture_output=True,
                          text=True, timeout=timeout_s)
    return Result(args, done.returncode, done.stdout, done.stderr, Path(cwd))


#: an interpreter that imports gaitcli once and then runs ``gait`` invocations one after another (one JSON line
#: in, one out), each in its working folder with its own stdout/stderr, as the console script does
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


class Runner:
    """One runner process. :func:`gait_many` keeps its runners for the whole session (:data:`_IDLE`): their
    imports (2 s of CPU) and caches (a prediction's compiled NLP) serve every later job they take. A test may
    hold its own, to signal it during a job (:meth:`send`, then :meth:`receive`)."""

    def __init__(self) -> None:
        self.log = tempfile.TemporaryFile("w+")  # what the process itself prints to stderr (not a job's)
        self.proc = subprocess.Popen([sys.executable, "-c", _RUNNER], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                     stderr=self.log, env=ENV, text=True)

    def send(self, args, cwd: Path) -> None:
        """Start ``gait ARGS`` in ``cwd``."""
        self.args, self.cwd = tuple(str(a) for a in args), Path(cwd)
        self.proc.stdin.write(json.dumps([list(self.args), str(cwd)]) + "\n")
        self.proc.stdin.flush()

    def receive(self, timeout_s: float = 600.0) -> Result:
        """The sent job's Result; past ``timeout_s`` the process is killed (and this runner is spent)."""
        timer = threading.Timer(timeout_s, self.proc.kill)
        timer.start()
        try:
            line = self.proc.stdout.readline()
        finally:
            timer.cancel()
        if not line:
            self.proc.kill()
            self.log.seek(0)
            raise RuntimeError(f"the gait runner process died running gait {' '.join(self.args)}:\n{self.log.read()}")
        code, stdout, stderr = json.loads(line)
        return Result(self.args, code, stdout, stderr, self.cwd)

    def run(self, args, cwd: Path, timeout_s: float = 600.0) -> Result:
        """``gait ARGS`` in ``cwd``, to its end."""
        self.send(args, cwd)
        return self.receive(timeout_s)

    def close(self) -> None:
        if self.proc.poll() is None:
            self.proc.stdin.close()
            try:
                self.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        for stream in (self.proc.stdin, self.proc.stdout, self.log):
            stream.close()


#: the idle runners of this test process (an xdist worker), started on first need, closed at exit
_IDLE: queue.LifoQueue = queue.LifoQueue()


@atexit.register
def _close_runners() -> None:
    while not _IDLE.empty():
        _IDLE.get_nowait().close()


def _runner_loop(todo: queue.Queue, done: dict, timeout_s: float) -> None:
    """Take an idle runner (or start one), run jobs off ``todo`` until it is empty, put each Result into
    ``done``; then give the runner back, unless it died."""
    try:
        runner = _IDLE.get_nowait()
    except queue.Empty:
        runner = Runner()
    while True:
        try:
            key, (args, cwd) = todo.get_nowait()
        except queue.Empty:
            break
        done[key] = runner.run(args, cwd, timeout_s)
    _IDLE.put(runner)


def gait_many(jobs: dict, *, timeout_s: float = 600.0, workers: int = WORKERS) -> dict:
    """Run several ``gait`` invocations: ``{key: (args, cwd)}`` → ``{key: Result}``.

    ``workers`` runner processes (each importing gaitcli once per session, :class:`Runner`) take the next job
    when done with one (put the longest first); with ``workers=1`` the jobs run in the order given, one after
    the other. ``timeout_s`` bounds each job.
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


def _stop_a_prediction(root: Path) -> dict:
    return gait("predict", "--nodes", "6", "--max-iterations", "2", "-o", "pr", cwd=root).to_json()


@pytest.fixture(scope="session")
def stopped_prediction(tmp_path_factory) -> tuple[Path, Result]:
    """``gait predict --nodes 6 --max-iterations 2 -o pr``: the default prediction stopped after two IPOPT
    iterations (exit 3, every output written), made once per session for the predict and report tests (a
    prediction's first IPOPT solver takes most of its 10–20 s). Returns (its ``pr`` folder, the run); copy the
    folder before writing into it."""
    root, record = build_once(tmp_path_factory, "stopped_prediction", _stop_a_prediction)
    return root / "pr", Result.from_json(record)


def _synth_emg(root: Path) -> dict:
    return gait("synth", root / "trial", "--emg", cwd=root).to_json()


@pytest.fixture(scope="session")
def synth_emg(tmp_path_factory) -> tuple[Path, Result]:
    """``gait synth trial --emg``: the default synthetic walk with its 16 EMG channels, made once per session for
    test_emg.py and test_hostile_inputs.py (its truth activations are two EID solves, 2–4 s). Returns (the trial
    folder, the run); copy the folder before writing into it."""
    root, record = build_once(tmp_path_factory, "synth_emg", _synth_emg)
    return root / "trial", Result.from_json(record)


# ------------------------------------------------------------------ a real Dask scheduler and workers

def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture(scope="module")
def dask_cluster(request):
    """``dask scheduler`` and ``dask worker`` (single-threaded worker processes under their nannies: the test
    module's ``DASK_WORKERS``, default two) as separate processes on 127.0.0.1; the scheduler lets a task's
    worker die once (allowed-failures 1)."""
    workers = getattr(request.module, "DASK_WORKERS", 2)
    port = _free_port()
    address = f"tcp://127.0.0.1:{port}"
    env = {**ENV, "DASK_DISTRIBUTED__SCHEDULER__ALLOWED_FAILURES": "1"}
    dask = [sys.executable, "-m", "distributed.cli.dask_scheduler"]
    scheduler = subprocess.Popen(dask + ["--host", "127.0.0.1", "--port", str(port), "--no-dashboard"], env=env,
                                 stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    worker = subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker", address, "--nworkers", str(workers),
                               "--nthreads", "1", "--no-dashboard"], env=env, stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL, start_new_session=True)
    from distributed import Client

    client = Client(address, timeout="30s")
    client.wait_for_workers(workers, timeout=60)
    try:
        yield address, client
    finally:
        client.close()
        for proc in (worker, scheduler):
            _signal_group(proc, signal.SIGTERM)
        for proc in (worker, scheduler):
            try:
                proc.wait(20)
            except subprocess.TimeoutExpired:
                _signal_group(proc, signal.SIGKILL)
                proc.wait()


def _signal_group(proc: subprocess.Popen, signum: int) -> None:
    """``signum`` to the process group ``proc`` leads; nothing when the group has ended already (a test killed
    a worker and its nanny followed)."""
    try:
        os.killpg(proc.pid, signum)
    except ProcessLookupError:
        pass


#: ``gait idyn`` with both exports, as the stair-session tests run it
EXPORTS = ("--no-plots", "--export", "c3d", "--export", "opensim")
#: the stair session's measurements as its README lists them, typed into a subject.yaml (no .vsk beside it)
STAIR_TYPED = {"mass_kg": 85.0, "stature_m": 1.679, "sex": "male", "marker_set": "plug_in_gait",
               "hip_joint_centre": "davis", "knee_width_mm": [139, 144], "ankle_width_mm": [89, 85],
               "leg_length_m": (0.866 + 0.877) / 2}


def _stair_sessions(pig: Path, root: Path) -> dict:
    """``pig``: Movement_trial.c3d, Static_trial.c3d and Test.vsk alone, idyn with both exports; ``typed``: the
    C3Ds with :data:`STAIR_TYPED` as subject.yaml, idyn."""
    import yaml

    folders = {"pig": root / "pig", "typed": root / "typed"}
    for folder in folders.values():
        folder.mkdir()
        shutil.copy(pig / "Movement_trial.c3d", folder / "trial.c3d")  # links out of the folder are refused
        shutil.copy(pig / "Static_trial.c3d", folder / "static.c3d")
    shutil.copy(pig / "Test.vsk", folders["pig"] / "Test.vsk")
    (folders["typed"] / "subject.yaml").write_text(yaml.safe_dump(STAIR_TYPED))
    runs = gait_many({"pig": (("idyn", folders["pig"], *EXPORTS), root),
                      "typed": (("idyn", "--no-plots", folders["typed"]), root)}, workers=2)
    return {k: r.to_json() for k, r in runs.items()}


@pytest.fixture(scope="session")
def stair_sessions(shared_pig_dir, tmp_path_factory):
    """../shared/data/pig run once per test session (:func:`_stair_sessions`): (root, {"pig": Result, "typed":
    Result}); the outputs in ``root/pig/gait_out`` and ``root/typed/gait_out``."""
    root, record = build_once(tmp_path_factory, "cli_stair_sessions", lambda root: _stair_sessions(shared_pig_dir,
                                                                                                   root))
    return root, {k: Result.from_json(v) for k, v in record.items()}



# ------------------------------------------------------------------ a page opened in headless Chromium

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
#: injected into a copy of a page (whose own Content-Security-Policy forbids scripts): on load, each image's
#: natural size and every fetch the page made (data: URIs make none), into an attribute --dump-dom prints
CHECK = ("<script>addEventListener('load', () => { document.body.setAttribute('data-check', JSON.stringify({"
         "images: [...document.images].map(i => [i.naturalWidth, i.naturalHeight]), "
         "requests: performance.getEntriesByType('resource').map(e => e.name)})); });</script>")


def in_chromium(page: Path, tmp_path: Path) -> dict:
    """``page`` loaded in headless Chromium: {"images": [[width, height], ...], "requests": [url, ...]}."""
    import html as htmlmod
    import re

    text = re.sub(r'<meta http-equiv="Content-Security-Policy"[^>]*>', "", page.read_text(encoding="utf-8"))
    probe = tmp_path / f"probe_{page.parent.name}.html"
    probe.write_text(text.replace("</body>", CHECK + "</body>"), encoding="utf-8")
    done = subprocess.run([CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--virtual-time-budget=10000",
                           "--dump-dom", probe.as_uri()], capture_output=True, text=True, timeout=120)
    found = re.search(r'data-check="([^"]*)"', done.stdout)
    assert found, done.stderr[-2000:]
    return json.loads(htmlmod.unescape(found[1]))
