"""Many trials at once (``gait batch``), on the workers of :func:`gaitcli.run.cluster.workers`.

:func:`find_trials` finds every trial below a lab folder (a folder with ``subject.yaml``, or each walk of such a
folder that is a session; ``gait_out`` and hidden folders are not searched). :func:`plan` decides, in this process
and before any worker starts, what is current: a trial whose every stage's output was made from the same inputs and
configuration is ``skipped`` (its key figures read from the outputs' ``summary.json``), and a trial that failed on
bad input (exit 2) in the previous batch with the same files and configuration (``batch_summary.csv``'s
``input_key``) keeps its failure without being run again. The rest become tasks (:func:`run_trial`), each calling
the pipeline's stage functions (:func:`gaitcli.run.pipeline.run_stages`), never the command line; a trial's failure
is its rows, never the batch's. A worker that dies mid-trial leaves only the hidden ``.part`` folder of the stage
it was writing (outputs appear whole or not at all, :mod:`gaitcli.io.atomic`); on a Dask cluster the scheduler runs
that trial once more on another worker and marks it failed after a second death
(``distributed.scheduler.allowed-failures: 1`` on a local cluster). Results stay on disk: this process holds one
row per trial × stage and at most a few tasks per worker in flight, so its memory does not grow with the number of
trials waiting.
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import os
import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field, fields, replace
from pathlib import Path

from gaitcli.core.registry import stage_names
from gaitcli.errors import GaitError, InputError
from gaitcli.io.atomic import atomic_path, check_output_file, remove_stale
from gaitcli.io.outputs import plain_text, spreadsheet_text
from gaitcli.run.cluster import Task, completed
from gaitcli.run.cluster import workers as cluster_workers
from gaitcli.run.config import PipelineConfig, to_yaml
from gaitcli.run.pipeline import needed_stages, trial_stages
from gaitcli.run.trial import holds_subject, is_walk, open_trial, output_root, session_walks, subject_vsk

BATCH_SUMMARY = "batch_summary.csv"
#: folders never searched for trials: outputs, and hidden or cache folders
NOT_SEARCHED = ("gait_out", "__pycache__")
#: summary.json figures copied into batch_summary.csv, per stage (keys as README.md's outputs table lists them)
KEY_FIGURES = {
    "filter": ("frames", "gaps_filled", "plates"),
    "idyn": ("speed_m_s", "stride_length_m", "period_s", "stance_right_pct", "stance_left_pct",
             "rms_residual_force_N", "rms_residual_moment_Nm", "mass_kg"),
    "muscles": ("method", "converged", "metabolic_cost_J", "cost_of_transport_J_per_m", "max_moment_error_Nm"),
    "predict": ("converged", "iterations", "objective", "cost_of_transport_J_per_m", "deviation"),
}
#: tasks in flight per worker: enough to keep every worker busy, few enough that the client stays small
TASKS_PER_WORKER = 2


@dataclass(frozen=True)
class BatchRow:
    """One trial × stage of a batch: ``status`` ok | unconverged | failed | skipped, the exit code a single-trial
    command would have given, the one-line ``reason`` of a failure, the stage's wall time (s; of the whole
    trial's attempt for a failure), the
    ``input_key`` of the trial's files and configuration, and the stage's key figures."""

    trial: str
    stage: str
    status: str
    exit_code: int = 0
    reason: str = ""
    wall_time_s: float = 0.0
    input_key: str = ""
    figures: dict = field(default_factory=dict)


@dataclass
class BatchResult:
    """Every row, and the counts per trial: a trial is failed if a stage failed, unconverged if one did not
    converge, skipped if every stage was current, else ok."""

    rows: list[BatchRow]
    elapsed_s: float = 0.0
    dashboard: str | None = None

    def trial_status(self) -> dict[str, str]:
        by_trial: dict[str, set[str]] = {}
        for row in self.rows:
            by_trial.setdefault(row.trial, set()).add(row.status)
        return {t: next(s for s in ("failed", "unconverged", "ok", "skipped") if s in states)
                for t, states in by_trial.items()}

    def counts(self) -> dict[str, int]:
        status = list(self.trial_status().values())
        return {s: status.count(s) for s in ("ok", "failed", "skipped", "unconverged")}

    def line(self) -> str:
        """``N ok, F failed, S skipped`` (and ``, U unconverged`` when there are any)."""
        c = self.counts()
        text = f"{c['ok']} ok, {c['failed']} failed, {c['skipped']} skipped"
        return text + (f", {c['unconverged']} unconverged" if c["unconverged"] else "")


def find_trials(lab_dir: str | Path) -> list[Path]:
    """Every trial at or below ``lab_dir``: each folder holding a ``subject.yaml`` or C3D files beside a ``.vsk``
    (a trial folder, :func:`gaitcli.run.trial.holds_subject`), or each walk of such a folder that is a session
    (:func:`gaitcli.run.trial.session_walks`); sorted. Outputs and hidden folders are not searched. A folder
    whose subject cannot be read counts as one trial (running it gives the reason). None found is an
    :class:`InputError`: a batch that runs nothing says why."""
    lab_dir = Path(lab_dir)
    found = []
    for folder in subject_folders(lab_dir):
        try:
            walks = session_walks(folder)
        except GaitError:
            walks = None
        found += walks if walks else [folder]
    if not found:
        raise InputError(lab_dir, None, "no trial or session folder in it (expected folders holding a subject.yaml, "
                                        "or C3D files beside the lab's Vicon .vsk)")
    return sorted(found)


def subject_folders(lab_dir: Path) -> list[Path]:
    """The folders at or below ``lab_dir`` that hold a subject (:func:`gaitcli.run.trial.holds_subject`), in
    search order; outputs and hidden folders are not searched."""
    if not Path(lab_dir).is_dir():
        raise InputError(lab_dir, None, "lab folder not found (expected a folder of trial folders)")
    folders = []
    for root, dirs, files in os.walk(lab_dir):
        dirs[:] = sorted(d for d in dirs if d not in NOT_SEARCHED and not d.startswith("."))
        if holds_subject(files):
            folders.append(Path(root))
    return folders


def vsk_subjects(lab_dir: Path) -> list[tuple[Path, Path]]:
    """(folder, its .vsk) for each folder below ``lab_dir`` whose subject is its Vicon subject file alone (no
    subject.yaml): what the console names before a batch or session runs."""
    return [(folder, vsk) for folder in subject_folders(lab_dir) if (vsk := subject_vsk(folder)) is not None]


def stages_of(cfg: PipelineConfig) -> tuple[str, ...]:
    """The pipeline's stages with whatever they need, in run order."""
    return needed_stages(cfg.stages)


def failure_rows(name: str, key: str, cfg: PipelineConfig, code: int, reason: str,
                 wall_s: float = 0.0) -> list[BatchRow]:
    """A failed trial's rows, one per stage of the pipeline."""
    return [BatchRow(name, s, "failed", code, reason, round(wall_s, 3), key) for s in stages_of(cfg)]


def input_key(ref: Path, cfg: PipelineConfig) -> str:
    """SHA-256 of a trial's files (names and contents; not its outputs) and the resolved configuration: every file
    of a trial folder; a walk's own C3D and the session's subject and static files."""
    digest = hashlib.sha256(to_yaml(cfg).encode())
    if is_walk(ref):
        try:
            files = open_trial(ref).input_files()
        except GaitError:  # the walk's run says why in its own rows
            files = [ref]
    else:
        files = [p for p in ref.iterdir() if p.is_file()]
    for path in sorted(files):
        digest.update(path.name.encode())
        try:
            with open(path, "rb") as f:
                for block in iter(lambda: f.read(1 << 20), b""):
                    digest.update(block)
        except OSError as exc:  # an unreadable file: the trial's run says so in its own row (exit 2)
            digest.update(f"unreadable: {exc.errno}".encode())
    return digest.hexdigest()


def _figures(stage: str, summary: dict | None) -> dict:
    summary = summary or {}
    return {k: summary[k] for k in KEY_FIGURES.get(stage, ()) if k in summary}


def stale_stages(folder: Path, name: str, cfg: PipelineConfig, key: str) -> tuple[tuple[str, ...], list[BatchRow]]:
    """The stages of a trial whose outputs are missing or were made from other inputs or configuration, and
    ``skipped`` rows for the others (their key figures from ``summary.json``). A trial that cannot be opened
    (bad subject.yaml, no trial file) has every stage stale: running it gives the reason."""
    from gaitcli.run.pipeline import TrialRun

    try:
        run = TrialRun(folder, None, cfg)
    except GaitError:
        return stages_of(cfg), []
    stale, rows = [], []
    for stage in needed_stages(trial_stages(folder, cfg)):
        path = run.fresh(stage)
        try:
            summary = None if path is None else json.loads((path.parent / "summary.json").read_text())
        except (OSError, ValueError):
            summary = None
        if summary is None:
            stale.append(stage)
        else:
            rows.append(BatchRow(name, stage, "skipped", input_key=key, figures=_figures(stage, summary)))
    return tuple(stale), rows


def run_trial(folder: str, name: str, cfg: PipelineConfig, key: str, stale: Sequence[str],
              plots: bool = True) -> list[BatchRow]:
    """The Dask task: run the ``stale`` stages on one trial (the fresh ones they need are read back); its rows
    (a failure is rows, not an exception)."""
    from gaitcli.run.pipeline import run_stages

    started = time.perf_counter()

    def failed(code: int, reason: str) -> list[BatchRow]:
        remove_stale_parts(Path(folder), cfg)
        return failure_rows(name, key, cfg, code, reason, time.perf_counter() - started)

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            outcomes = run_stages(Path(folder), stale, cfg, plots=plots, workers=1)  # one worker: this one
    except GaitError as exc:  # bad input (2), an unconverged optimization that raised (3)
        return failed(exc.exit_code, str(exc))
    except Exception as exc:  # an internal error in one trial is that trial's failure
        return failed(1, f"internal error: {type(exc).__name__}: {exc}")
    rows = []
    for o in outcomes:
        status = {"written": "ok", "reused": "skipped", "unconverged": "unconverged"}[o.status]
        summary = o.summary
        if summary is None and (o.folder / "summary.json").is_file():
            summary = json.loads((o.folder / "summary.json").read_text())
        rows.append(BatchRow(name, o.stage, status, 3 if status == "unconverged" else 0, o.message,
                             o.elapsed_s if status != "skipped" else 0.0, key, _figures(o.stage, summary)))
    return rows


def remove_stale_parts(ref: Path, cfg: PipelineConfig) -> None:
    """Remove what killed runs left of this trial's stage folders (hidden ``.part`` folders)."""
    from gaitcli.core.registry import stage

    out = output_root(ref)
    if out.is_dir():
        for name in stages_of(cfg):
            remove_stale(out / stage(name).output_folder(cfg.section(name)))


def read_summary(path: Path) -> dict[str, list[BatchRow]]:
    """The previous batch's rows by trial (empty when there is no readable ``batch_summary.csv``)."""
    if not path.is_file():
        return {}
    rows: dict[str, list[BatchRow]] = {}
    try:
        with open(path, newline="") as f:
            for r in csv.DictReader(f):
                row = BatchRow(plain_text(r["trial"]), r["stage"], r["status"], int(r["exit_code"] or 0),
                               plain_text(r["reason"]), float(r["wall_time_s"] or 0), r["input_key"])
                rows.setdefault(row.trial, []).append(row)
    except (KeyError, ValueError, csv.Error, OSError):  # UnicodeDecodeError is a ValueError
        return {}
    return rows


def write_summary(path: Path, rows: Sequence[BatchRow]) -> Path:
    """``batch_summary.csv``: one row per trial × stage, the key figures as columns (written atomically)."""
    figure_columns = list(dict.fromkeys(k for r in rows for k in r.figures))
    base = [f.name for f in fields(BatchRow) if f.name != "figures"]
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=base + figure_columns)
    writer.writeheader()
    for r in sorted(rows, key=lambda r: (r.trial, stage_names().index(r.stage) if r.stage in stage_names() else 99)):
        data = {k: v for k, v in asdict(r).items() if k != "figures"}
        row = {**data, **r.figures}
        writer.writerow({k: spreadsheet_text(v) if isinstance(v, str) else v for k, v in row.items()})
    with atomic_path(path) as tmp:
        tmp.write_text(buffer.getvalue())
    return path


def plan(lab_dir: Path, cfg: PipelineConfig, *, force: bool = False,
         summary_path: Path | None = None) -> tuple[list[BatchRow], list[tuple]]:
    """What is current (rows) and what must run (``(folder, name, key, stale stages)`` per trial), decided in the
    client; ``summary_path`` the previous batch's summary (default ``lab_dir/batch_summary.csv``)."""
    trials = find_trials(lab_dir)
    previous = {} if force else read_summary(summary_path or lab_dir / BATCH_SUMMARY)
    rows, todo = [], []
    for folder in trials:
        name = folder.relative_to(lab_dir).as_posix() if folder != lab_dir else "."
        key = input_key(folder, cfg)
        if force:
            try:
                todo.append((folder, name, key, trial_stages(folder, cfg)))
            except GaitError:  # running it gives the reason
                todo.append((folder, name, key, tuple(cfg.stages)))
            continue
        before = previous.get(name, [])
        if before and all(r.status == "failed" and r.exit_code == 2 and r.input_key == key for r in before):
            rows += [replace(r, wall_time_s=0.0) for r in before]  # the same bad input fails the same way
            continue
        stale, current = stale_stages(folder, name, cfg, key)
        if stale:
            todo.append((folder, name, key, stale))
        else:
            rows += current
    return rows, todo


def run_batch(lab_dir: str | Path, cfg: PipelineConfig, *, workers: int | None = None, scheduler: str | None = None,
              force: bool = False, plots: bool = True, on_rows: Callable[[list[BatchRow]], None] | None = None,
              on_start: Callable[[int, int, str | None], None] | None = None,
              summary_path: Path | None = None) -> BatchResult:
    """Run the pipeline over every trial below ``lab_dir`` (see the module docstring) and write
    ``batch_summary.csv`` there. An interrupt leaves the previous ``batch_summary.csv`` as it was.

    Parameters
    ----------
    lab_dir : str or Path
        The folder searched for trial folders (:func:`find_trials`).
    cfg : PipelineConfig
        The pipeline every trial runs.
    workers, scheduler
        How many local workers, or the address of a Dask scheduler (:func:`gaitcli.run.cluster.workers`).
    force : bool
        Run every trial, also those whose outputs are current.
    plots : bool
        Draw each stage's figures.
    on_rows : callable, optional
        ``on_rows(rows)`` with one trial's rows as it ends; first those of the trials decided without a run
        (current, or a kept failure).
    on_start : callable, optional
        ``on_start(total trials, trials to run, dashboard address or None)`` before any trial runs.
    summary_path : Path, optional
        Where ``batch_summary.csv`` goes (default: ``lab_dir``; a session's: its ``gait_out/session/``).

    Returns
    -------
    BatchResult
        Every row and the counts per trial.
    """
    started = time.perf_counter()
    lab_dir = Path(lab_dir).resolve()  # the workers may run in other folders
    summary_path = Path(summary_path) if summary_path is not None else lab_dir / BATCH_SUMMARY
    check_output_file(summary_path)  # before any trial runs
    rows, todo = plan(lab_dir, cfg, force=force, summary_path=summary_path)
    dashboard = None
    if on_rows is not None and rows:
        for name in dict.fromkeys(r.trial for r in rows):
            on_rows([r for r in rows if r.trial == name])
    if not todo:
        if on_start is not None:
            on_start(len({r.trial for r in rows}), 0, None)
    else:
        try:
            with cluster_workers(min(len(todo), workers or os.cpu_count() or 1), scheduler, dashboard=True) as pool:
                dashboard = pool.dashboard
                if on_start is not None:
                    on_start(len({r.trial for r in rows}) + len(todo), len(todo), dashboard)
                tasks = {item[0]: Task(run_trial, (str(item[0]), item[1], cfg, item[2], item[3], plots))
                         for item in todo}
                items = {item[0]: item for item in todo}
                for folder, future in completed(pool, tasks, in_flight=TASKS_PER_WORKER * pool.size):
                    _, name, key, _ = items.pop(folder)
                    got = _rows_of(future, folder, name, key, cfg)
                    rows += got
                    if on_rows is not None:
                        on_rows(got)
        except BaseException:
            for folder, *_ in todo:  # what a stopped worker was writing
                remove_stale_parts(Path(folder), cfg)
            raise
    summary_path.parent.mkdir(parents=True, exist_ok=True)
    write_summary(summary_path, rows)
    return BatchResult(rows, round(time.perf_counter() - started, 3), dashboard)


def _rows_of(future, folder: Path, name: str, key: str, cfg: PipelineConfig) -> list[BatchRow]:
    """A trial task's rows; a task that could not run is its trial's failure."""
    try:
        return future.result()
    except Exception as exc:
        remove_stale_parts(folder, cfg)
        if type(exc).__name__ == "KilledWorker":  # distributed's, after the retry its scheduler allows
            return failure_rows(name, key, cfg, 1, "the worker running this trial died twice (killed or out of "
                                                   "memory)")
        if type(exc).__name__ == "BrokenProcessPool":  # the standard library's pool, whose workers all end
            return failure_rows(name, key, cfg, 1, "a worker process died (killed or out of memory)")
        return failure_rows(name, key, cfg, 1, f"internal error: {type(exc).__name__}: {exc}")
