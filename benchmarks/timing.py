"""Shared helpers of the benchmark scripts (run them from the repository root as ``python benchmarks/bench_*.py``).

Import this module before numpy (every script does so first): it limits BLAS/OpenMP to one thread
(``OMP_NUM_THREADS=1`` etc., inherited by the ``gait`` processes the scripts start) and selects
matplotlib's Agg backend. :func:`one_core` also pins the process (and its children) to one core.

Helpers: :func:`prediction_options` (IPOPT options added to the predictions'),
:func:`solver_libraries` (the line saying which native libraries IPOPT's MUMPS ran on),
:func:`median_s` (median wall time of repeated calls), :func:`copy_sample` (a bundled sample
trial without its outputs), :func:`sample_outputs` (run stages on such a copy through
``gaitcli.run.pipeline.run_stages``), :func:`sample_legs` (one leg's muscle-stage inputs from a sample's
idyn.h5), :func:`gait_argv`/:func:`time_gait` (the ``gait`` command in a new
process), :func:`write_stage` (a stage's writer into a fresh folder, plus ``summary.json``, as the
pipeline does), :class:`Stopwatch` (time calls of named functions without editing gaitcli) and
:func:`figure_times` (the time of each PNG a figure function draws).
"""

from __future__ import annotations

import os
import shutil
import statistics
import subprocess
import sys
import time
from contextlib import contextmanager
from pathlib import Path

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")
os.environ.setdefault("MPLBACKEND", "Agg")

REPO = Path(__file__).resolve().parents[1]
if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))


@contextmanager
def prediction_options(extra: dict):
    """Inside the block every prediction's IPOPT solver (``gaitcli.predict.solve.ipopt_options``) also gets the
    options ``extra`` (CasADi's names)."""
    from gaitcli.predict import solve

    plain = solve.ipopt_options
    solve.ipopt_options = lambda settings, warm: {**plain(settings, warm), **extra}
    try:
        yield
    finally:
        solve.ipopt_options = plain


def one_core() -> None:
    """Pin this process (and the processes it starts) to one core, where the OS allows it: the core numbered
    ``BENCH_CORE`` if set, else the lowest allowed. Two benchmarks run side by side need different cores
    (``BENCH_CORE=1 python benchmarks/...``): on the same one each runs at half speed."""
    if hasattr(os, "sched_setaffinity"):
        allowed = os.sched_getaffinity(0)
        chosen = int(os.environ.get("BENCH_CORE", min(allowed)))
        if chosen not in allowed:
            raise SystemExit(f"BENCH_CORE={chosen}: not one of this process's cores {sorted(allowed)}")
        os.sched_setaffinity(0, {chosen})


def solver_libraries() -> str:
    """"solver libraries: …": what ``gaitcli.core.native.prepare_solvers`` did in this process (call it after the
    solves) and which OpenBLAS MUMPS is bound to; ``GAITCLI_NATIVE=casadi`` runs with CasADi's own."""
    from gaitcli.core import native

    done = native.prepare_solvers()
    return (f"solver libraries: MUMPS on {native.solver_libraries()}"
            + (f" ({'; '.join(done)})" if done else f" (as CasADi sets them up; {native.SWITCH}="
                                                    f"{os.environ.get(native.SWITCH, '')})"))


def median_s(func, repeat: int):
    """Median wall time (s) of ``repeat`` calls of ``func`` and the last call's return value."""
    times, value = [], None
    for _ in range(max(1, repeat)):
        start = time.perf_counter()
        value = func()
        times.append(time.perf_counter() - start)
    return statistics.median(times), value


def median_of(values):
    """Median of each key over a list of dicts of numbers (keys of the first dict)."""
    return {key: statistics.median(v[key] for v in values) for key in values[0]}


def copy_sample(name: str, dest: Path) -> Path:
    """A copy of the bundled sample trial ``name`` in ``dest`` (without earlier outputs or the synthetic truth)."""
    from gaitcli.resources import sample_trial

    shutil.copytree(sample_trial(name), dest, ignore=shutil.ignore_patterns("gait_out", "truth"))
    return Path(dest)


def sample_outputs(tmp: Path, stages=("idyn",), *, sample: str = "normal", plots: bool = False, cfg=None):
    """Run ``stages`` (and what they need) on a copy of a sample trial in ``tmp``.

    Returns (trial folder, {stage: HDF5 path}) for every stage written or reused; outputs go to the
    copy's ``gait_out``, as ``gait`` writes them.
    """
    from gaitcli.core.registry import stage
    from gaitcli.run.config import configure
    from gaitcli.run.pipeline import run_stages

    folder = copy_sample(sample, Path(tmp) / sample)
    outcomes = run_stages(folder, stages, cfg or configure(None), plots=plots)
    return folder, {o.stage: o.folder / stage(o.stage).h5_name for o in outcomes}


def sample_legs(tmp: Path, side: str = "r", phases=("cycle",), *, sample: str = "normal"):
    """The muscle stage's inputs for one leg of a sample trial: (subject, {phase: LegAnalysis}).

    The filter and idyn stages run once on a copy in ``tmp``; the legs come from idyn.h5 read back
    (``stage("idyn").read``, the hand-off ``gait muscles`` gets) by ``muscles.interval.prepare_leg``.
    """
    from gaitcli.core.registry import stage
    from gaitcli.muscles.interval import prepare_leg
    from gaitcli.run.trial import open_trial

    folder, h5 = sample_outputs(tmp, ("idyn",), sample=sample)
    export = stage("idyn").read(h5["idyn"])
    subject = open_trial(folder).subject
    return subject, {phase: prepare_leg(export, side, phase, stature_m=subject.stature_m, sex=subject.sex,
                                        source=h5["idyn"]) for phase in phases}


def stage_attrs(trial_folder: Path, name: str, cfg=None) -> dict:
    """The HDF5 root attributes the pipeline gives stage ``name`` of this trial (provenance, stage key)."""
    from gaitcli.run.config import configure
    from gaitcli.run.pipeline import TrialRun

    return TrialRun(trial_folder, None, cfg or configure(None)).attrs(name)


def write_stage(name: str, folder: Path, result, attrs: dict) -> dict:
    """Stage ``name``'s writer into a fresh ``folder`` (written whole, as the pipeline does) plus summary.json."""
    from gaitcli.core.registry import stage
    from gaitcli.io.outputs import stage_folder, write_json

    with stage_folder(folder) as tmp:
        summary = stage(name).write(tmp, result, attrs)
        write_json(tmp / "summary.json", summary)
    return summary


def gait_argv(*args) -> list[str]:
    """The command line of ``gait ARGS``: the console script beside this Python, else ``python -m gaitcli``."""
    script = Path(sys.executable).with_name("gait")
    if script.is_file():
        return [str(script), *map(str, args)]
    return [sys.executable, "-m", "gaitcli", *map(str, args)]


def run_gait(*args) -> subprocess.CompletedProcess:
    """Run ``gait ARGS`` in a new process (one thread, output captured); raises if it fails."""
    return subprocess.run(gait_argv(*args), check=True, capture_output=True, text=True)


def time_gait(*args, repeat: int = 3, before=None) -> float:
    """Median wall time (s) of ``gait ARGS`` in a new process; ``before()`` runs untimed before each run."""
    times = []
    for _ in range(max(1, repeat)):
        if before is not None:
            before()
        start = time.perf_counter()
        run_gait(*args)
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def python_s(code: str, repeat: int = 3) -> float:
    """Median wall time (s) of ``python -c CODE`` in a new process (interpreter start-up included)."""
    def run():
        subprocess.run([sys.executable, "-c", code], check=True, capture_output=True)
    return median_s(run, repeat)[0]


class Stopwatch:
    """Accumulated wall time of calls to functions replaced by timing wrappers for the duration of a ``with``.

    ``watch.wrap(owner, "name", label)`` replaces the attribute ``owner.name`` (of a module or a class);
    ``watch.seconds[label]`` and ``watch.calls[label]`` accumulate. ``label`` may be a function of the
    call's arguments (one label per kind of call). Nested wrapped calls count in both labels.
    """

    def __init__(self):
        self.seconds: dict[str, float] = {}
        self.calls: dict[str, int] = {}
        self._restore = []

    def wrap(self, owner, name: str, label=None):
        label = label or name
        original = getattr(owner, name)
        raw = vars(owner).get(name, original) if isinstance(owner, type) else original  # classmethods stay so

        def timed(*args, **kwargs):
            key = label(*args, **kwargs) if callable(label) else label
            start = time.perf_counter()
            try:
                return original(*args, **kwargs)
            finally:
                self.seconds[key] = self.seconds.get(key, 0.0) + time.perf_counter() - start
                self.calls[key] = self.calls.get(key, 0) + 1

        setattr(owner, name, timed)
        self._restore.append((owner, name, raw))
        return self

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        for owner, name, raw in reversed(self._restore):
            setattr(owner, name, raw)
        self._restore.clear()


@contextmanager
def _saves(marks: list):
    """Record (name, start, end) of each ``report.plots.save`` call (one per PNG)."""
    from gaitcli.report import plots

    original = plots.save

    def save(fig, path):
        start = time.perf_counter()
        try:
            return original(fig, path)
        finally:
            marks.append((Path(path).name, start, time.perf_counter()))

    plots.save = save
    try:
        yield
    finally:
        plots.save = original


def figure_times(figures, h5_path: Path, folder: Path, title: str = "") -> dict[str, tuple[float, float]]:
    """One call of ``figures(h5_path, folder, title=...)``: {png name: (seconds, of which saving)}.

    A figure's time runs from the end of the previous figure (the first: from the call, so it includes
    reading the HDF5 file) to the end of its ``savefig``; "saving" is the ``save`` call alone (the PNG
    render and write).
    """
    marks = []
    start = time.perf_counter()
    with _saves(marks):
        figures(h5_path, folder, title=title)
    out, previous = {}, start
    for name, begin, end in marks:
        out[name] = (end - previous, end - begin)
        previous = end
    return out
