"""Running registered stages on one trial: inputs → stage functions → writers, with reuse of fresh outputs.

:func:`run_stages` (and :func:`run_stage` for one) is what ``gait run``, every
trial command and a batch runner call; it prints nothing and returns a
:class:`StageOutcome` per stage. The trial is read once; every stage needed is
computed before anything is written, so bad input found by a later stage
leaves every output as it was. An earlier stage whose HDF5 output was made
from the same inputs and configuration is read back instead of run again.
Each stage's folder is written whole or not at all (``io.outputs.stage_folder``).
"""

from __future__ import annotations

import dataclasses
import json
import time
import warnings
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

from gaitcli.core.container import Trial
from gaitcli.core.recording import Recording
from gaitcli.core.registry import (
    Progress,
    ProgressCallback,
    StageContext,
    no_progress,
    requirements,
    stage,
    stage_names,
)
from gaitcli.errors import GaitWarning, InputError
from gaitcli.io.atomic import check_output_folder, check_replaceable
from gaitcli.io.h5 import file_attrs, provenance, read_result, record_datasets, write_h5
from gaitcli.io.outputs import stage_folder, write_json
from gaitcli.resources import sample_trial
from gaitcli.run.config import PipelineConfig, section_dict, to_yaml
from gaitcli.run.trial import TrialFolder, open_trial, sha256
from gaitcli.signal.stage import with_session_defaults

#: bump when a stage's output files change, so that older outputs count as stale
OUTPUT_FORMAT = 3  # 3: idyn.h5's gait_cycle table; filter.h5's lab marker labels and filter edge frames


@dataclass(frozen=True)
class StageOutcome:
    """What became of one stage: ``status`` is ``"written"``, ``"unconverged"`` (written, exit 3) or ``"reused"``
    (a fresh earlier output read back); ``summary`` its ``summary.json``; ``folder`` where its files are."""

    stage: str
    status: str
    folder: Path
    summary: dict | None = None
    converged: bool = True
    message: str = ""
    elapsed_s: float = 0.0

    @property
    def paths(self) -> tuple[Path, ...]:
        return tuple(sorted(p for p in self.folder.rglob("*") if p.is_file())) if self.folder.is_dir() else ()


def load_recording(trial: TrialFolder) -> Recording:
    """Read the dynamic trial (C3D or CSV) in model axes, lab labels renamed by the subject's marker set."""
    from gaitcli.io.c3d import read_c3d
    from gaitcli.io.tables import read_csv_trial

    if trial.trial_path.suffix.lower() == ".c3d":
        recording = read_c3d(trial.trial_path)
    else:
        recording = read_csv_trial(trial.trial_path, trial.forces_path)
    recording.marker_labels = trial.subject.markers.lab_labels(recording.markers.labels)
    recording.markers = trial.subject.markers.apply(recording.markers, source=trial.subject_path,
                                                    explicit=trial.subject.marker_map)
    recording.notes.extend(trial.subject.notes)
    return with_subject_measurements(recording, trial)


def with_subject_measurements(recording: Recording, trial: TrialFolder) -> Recording:
    """``recording`` with the subject's measurements (the trial folder's .vsk) merged over the subject data its
    file records: the stages read them as they read the C3D's ``PROCESSING`` group, after subject.yaml's keys."""
    recording.subject_metadata = {**recording.subject_metadata, **trial.subject.measurements}
    return recording


def load_static(trial: TrialFolder, lab_to_model) -> Recording | None:
    """The standing trial in the dynamic trial's model axes, labels renamed by the marker set; None without
    static.c3d."""
    from gaitcli.io.axes import apply_rotation
    from gaitcli.io.c3d import read_c3d

    if trial.static_path is None:
        return None
    with warnings.catch_warnings():  # a standing trial has no plates to speak of
        warnings.filterwarnings("ignore", message=".*force plate", category=GaitWarning)
        static = apply_rotation(read_c3d(trial.static_path, to_model_axes=False), lab_to_model)
    static.markers = trial.subject.markers.apply(static.markers, source=trial.subject_path,
                                                 explicit=trial.subject.marker_map)
    return with_subject_measurements(static, trial)


def session_config(cfg: PipelineConfig, trial: TrialFolder | None) -> PipelineConfig:
    """``cfg`` with the filter's ``auto`` settings replaced by what they stand for in ``trial``'s session (its
    subject's marker set), so that the outputs record, and freshness compares, what was used."""
    if trial is None or "filter" not in cfg.sections:
        return cfg
    return cfg.replace_section("filter", with_session_defaults(cfg.section("filter"), trial.subject.marker_set))


class TrialRun:
    """One run: its trial (None for stages that need none), output root, resolved configuration and the files
    named for it; freshness, provenance, inputs read once. Without a trial, stages that need one run on the
    bundled sample trial (``needs_trial``) and the output root is ./gait_out."""

    def __init__(self, trial: Path | None, out: Path | None, cfg: PipelineConfig, *,
                 files: dict[str, Path] | None = None, needs_trial: bool = True):
        bundled = trial is None
        self.trial = open_trial(sample_trial() if bundled else trial) if trial is not None or needs_trial else None
        if out is None:
            out = Path.cwd() / "gait_out" if bundled else self.trial.out_root
        self.out_root = Path(out)
        self.cfg = session_config(cfg, self.trial)
        self.files = {k: Path(v) for k, v in (files or {}).items() if v is not None}
        self.inputs = {p.name: sha256(p) for p in self.trial.input_files()} if self.trial is not None else {}
        self.read: dict[str, dict[str, str]] = {}  # per stage: the further files it read (StageContext.uses)
        self._recording: Recording | None = None

    @property
    def title(self) -> str:
        """The figures' title: the trial folder's name, and a walk's ("" without a trial)."""
        return self.trial.title if self.trial is not None else ""

    def recording(self) -> Recording:
        if self.trial is None:
            raise InputError(None, "trial", "this stage needs a trial folder (expected TRIAL)")
        if self._recording is None:
            self._recording = load_recording(self.trial)
        return self._recording

    def stage_key(self, name: str) -> str:
        """What a stage's output depends on: input hashes and the configuration of it and earlier stages (with a
        trial, its optional stages' too)."""
        optional = stage(name).optional if self.trial is not None else ()
        names = {s for n in (name, *optional) for s in requirements(n)}
        cfg = {s: section_dict(self.cfg, s) for s in stage_names() if s in names}
        return json.dumps({"inputs": self.inputs, "config": cfg, "format": OUTPUT_FORMAT}, sort_keys=True)

    def attrs(self, name: str, history: tuple[str, ...] = ()) -> dict:
        attrs = provenance(to_yaml(self.cfg), {**self.inputs, **self.read.get(name, {})}, history)
        attrs["stage_key"] = self.stage_key(name)
        attrs["trial"] = self.trial.name if self.trial is not None else None
        return attrs

    def output_folder(self, name: str) -> Path:
        return self.out_root / stage(name).output_folder(self.cfg.section(name))

    def _made(self, name: str) -> tuple[Path, str | None] | None:
        """The stage's HDF5 output and the key it was made with ("" without one; None: a damaged file, made
        anew); None without an output."""
        path = self.output_folder(name) / stage(name).h5_name
        if not path.is_file():
            return None
        try:
            return path, file_attrs(path).get("stage_key", "")
        except InputError:
            return path, None

    def fresh(self, name: str) -> Path | None:
        """The stage's HDF5 output if it exists and was made from the same inputs and configuration."""
        made = self._made(name)
        return made[0] if made is not None and made[1] == self.stage_key(name) else None

    def why_stale(self, name: str) -> str | None:
        """Why the stage's existing output will not do (None: there is none, or it is fresh): the settings it was
        made with that differ from this run's, or changed input files."""
        made, key_now = self._made(name), self.stage_key(name)
        if made is None or made[1] == key_now:
            return None
        path, key = made
        unreadable = f"the output in {path.parent} cannot be read"
        if key is None:
            return unreadable
        try:
            before = json.loads(key) if key else {}
        except ValueError:
            return unreadable
        now = json.loads(key_now)
        changed = [f"{section}.{setting} {was} in the existing output, {value} asked"
                   for section, settings in now["config"].items()
                   for setting, value in settings.items()
                   if (was := before.get("config", {}).get(section, {}).get(setting, "(none)")) != value]
        if before.get("inputs") != now["inputs"]:
            changed.append("the trial's files changed since")
        return "; ".join(changed) or "it was made by another version of gaitcli"

    def record(self, name: str, path: Path) -> None:
        """``path`` read by stage ``name``: its SHA-256 goes into that stage's provenance."""
        self.read.setdefault(name, {})[str(path)] = sha256(path)

    def context(self, name: str, *, inputs: dict | None = None, input_paths: dict | None = None,
                static_recording=None, progress: ProgressCallback = no_progress, plots: bool = True,
                workers: int | None = None, scheduler: str | None = None, written=None) -> StageContext:
        """The context of stage ``name`` in this run (``inputs``: the hand-offs of the stages it depends on;
        ``written(dep)``: the output of a stage this run computed, written now, or None)."""
        trial = self.trial
        input_paths = {} if input_paths is None else input_paths

        def optional(dep: str):
            if dep not in stage(name).optional:
                raise LookupError(f"stage {name} asked for {dep}, which is not one of its optional stages")
            if trial is None:
                return None
            path = written(dep) if written is not None else None
            if path is None:
                path = fresh_output(trial.ref, dep, self.cfg, out=self.out_root, progress=progress, plots=plots)
            input_paths[dep] = path
            self.record(name, path)
            return _read(stage(dep), path)

        return StageContext(subject=trial.subject if trial else None, folder=trial.folder if trial else None,
                            subject_path=trial.subject_path if trial else None,
                            trial_path=trial.trial_path if trial else None,
                            static_path=trial.static_path if trial else None,
                            inputs=inputs or {}, input_paths=input_paths, recording=self.recording,
                            static_recording=static_recording or (lambda: None), progress=progress, stage=name,
                            files=self.files, workers=workers, scheduler=scheduler, resolve_optional=optional,
                            record_input=lambda path: self.record(name, path))


def write_record(folder: Path, result, attrs: dict, *, h5_name: str) -> dict:
    """The default writer: the result as one HDF5 record (``result/``); its scalar fields are the summary."""
    write_h5(folder / h5_name, record_datasets("result", result), attrs)
    return {f.name: getattr(result, f.name) for f in dataclasses.fields(result)
            if isinstance(getattr(result, f.name), (bool, int, float, str))}


def _write(st, folder: Path, result, attrs: dict) -> dict:
    if st.write is not None:
        return st.write(folder, result, attrs)
    return write_record(folder, result, attrs, h5_name=st.h5_name)


def _read(st, path: Path):
    return st.read(path) if st.read is not None else read_result(path, st.result, "result")


def _history(result) -> tuple[str, ...]:
    """The processing steps behind a result (its own ``history`` or its trial's), for the HDF5 attributes."""
    history = getattr(result, "history", None)
    if history is None:
        history = getattr(getattr(result, "trial", None), "history", ())
    return tuple(history)


def needed_stages(names) -> tuple[str, ...]:
    """The stages ``names`` and whatever they need, in run order (every stage after the ones it depends on)."""
    wanted = {n for name in names for n in requirements(name)}
    return tuple(n for n in stage_names() if n in wanted)


@contextmanager
def recorded_warnings():
    """Yield a list that receives the message of every :class:`GaitWarning` given in the block (a stage's
    summary.json keeps them, for the report); each warning then goes on to the caller's filters and display as
    if not recorded."""
    said: list[str] = []
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", GaitWarning)  # recorded even where the caller ignores them (a batch)
        try:
            yield said
        finally:
            pending = list(caught)
    for w in pending:
        if issubclass(w.category, GaitWarning) and str(w.message) not in said:
            said.append(str(w.message))
        warnings.warn_explicit(w.message, w.category, w.filename, w.lineno, source=w.source)


def run_stages(trial: Path | None, names, cfg: PipelineConfig, *, out: Path | None = None,
               progress: ProgressCallback = no_progress, plots: bool = True, files: dict[str, Path] | None = None,
               workers: int | None = None, scheduler: str | None = None) -> list[StageOutcome]:
    """Run the stages ``names`` (and whatever they need) on one trial; one outcome per stage touched.

    The named stages always run; a stage they depend on is read back from its
    output where that is fresh. Nothing is written until every stage has been
    computed, except an optional stage a stage asks for (``StageContext.optional``),
    which is made and written first when its output is not fresh.

    Parameters
    ----------
    trial : Path or None
        The trial folder; None: no trial when no stage needed needs one, else the bundled sample.
    names : iterable of str
        The stages to run.
    cfg : PipelineConfig
        The resolved configuration.
    out : Path, optional
        The output root (default: the trial's ``gait_out/``).
    progress : callable
        Receives :class:`~gaitcli.core.registry.Progress` reports.
    plots : bool
        Draw each stage's figures.
    files : dict, optional
        Files named for the run (``StageContext.files``), e.g. predict's ``reference``.
    workers, scheduler
        Where a stage may run work in parallel (:func:`gaitcli.run.cluster.workers`).

    Returns
    -------
    list of StageOutcome
        One per stage touched: written, unconverged (written) or reused.

    Raises
    ------
    InputError
        Bad input; nothing is written.
    """
    names = tuple(names)
    needed = needed_stages(names)
    run = TrialRun(trial, out, cfg, files=files, needs_trial=any(stage(n).trial for n in needed))
    check_output_folder(run.out_root)
    handoffs, sources, outcomes, computed = {}, {}, [], {}

    def write(name: str) -> StageOutcome:
        """Write a computed stage's folder whole; its outcome."""
        st = stage(name)
        result, elapsed, said = computed.pop(name)
        target = run.output_folder(name)
        started = time.perf_counter()
        with stage_folder(target) as tmp:
            summary = _write(st, tmp, result, run.attrs(name, _history(result)))
            if plots and st.plots is not None:
                progress(Progress(name, "figures", 0, 1))
                st.plots(tmp / st.h5_name, tmp / "plots", run.title)
                progress(Progress(name, "figures", 1, 1))
            summary["warnings"] = said
            summary["elapsed_s"] = round(elapsed + time.perf_counter() - started, 3)
            write_json(tmp / "summary.json", summary)
        converged = st.converged(result)
        return StageOutcome(name, "written" if converged else "unconverged", target, summary, converged,
                            "" if converged else st.unconverged(result), summary["elapsed_s"])

    def write_early(name: str) -> Path | None:
        """An optional stage this run computed, written now because a later stage asks for its output."""
        if name not in computed:
            return None
        check_replaceable(run.output_folder(name))
        outcomes.append(write(name))
        return run.output_folder(name) / stage(name).h5_name

    def static_recording():
        # turned like the dynamic trial: by the axes its container recorded, else by reading the trial
        filtered = next((h for h in handoffs.values() if isinstance(h, Trial) and h.lab_to_model is not None), None)
        lab_to_model = run.recording().lab_to_model if filtered is None else filtered.lab_to_model
        return load_static(run.trial, lab_to_model)

    for name in needed:
        st = stage(name)
        if name not in names:
            path = run.fresh(name)
            if path is not None:
                try:
                    handoffs[name], sources[name] = _read(st, path), path
                    outcomes.append(StageOutcome(name, "reused", path.parent))
                    continue
                except (InputError, KeyError, OSError, ValueError, TypeError):  # older or damaged: make it anew
                    pass
            else:
                reason = run.why_stale(name)
                if reason:  # a result of other settings is about to be replaced: say so
                    warnings.warn(f"{name}: {reason}: running {name} again", GaitWarning, stacklevel=2)
        started = time.perf_counter()
        ctx = run.context(name, inputs={d: handoffs[d] for d in st.depends},
                          input_paths={d: sources[d] for d in st.depends}, static_recording=static_recording,
                          progress=progress, plots=plots, workers=workers, scheduler=scheduler, written=write_early)
        with recorded_warnings() as said:
            result = st.run(ctx, run.cfg.section(name))
        handoffs[name], sources[name] = st.handoff(result), run.trial.trial_path if run.trial else None
        computed[name] = (result, time.perf_counter() - started, said)

    for name in computed:  # before the first write: a user's file in any folder to replace stops them all
        check_replaceable(run.output_folder(name))
    for name in list(computed):
        outcomes.append(write(name))
    order = {n: i for i, n in enumerate(needed)}
    return sorted(outcomes, key=lambda o: order[o.stage])


def trial_stages(trial: Path | None, cfg: PipelineConfig) -> tuple[str, ...]:
    """What ``gait run`` performs on one trial: the pipeline's stages, and ``emg`` where the trial's subject.yaml
    maps EMG channels (``emg:``)."""
    names = tuple(cfg.stages)
    if "emg" not in names and trial is not None and open_trial(trial).subject.emg:
        names += ("emg",)
    return names


def run_stage(trial: Path | None, name: str, cfg: PipelineConfig, **options) -> StageOutcome:
    """Run one stage (and whatever it needs) on one trial; the outcome of ``name`` (see :func:`run_stages`)."""
    return next(o for o in run_stages(trial, [name], cfg, **options) if o.stage == name)


def fresh_output(trial: Path | None, name: str, cfg: PipelineConfig, *, out: Path | None = None,
                 progress: ProgressCallback = no_progress, plots: bool = True) -> Path:
    """The HDF5 output of stage ``name`` for one trial: the existing one when fresh, else made anew (with
    whatever it needs) by :func:`run_stages`."""
    run = TrialRun(trial, out, cfg)
    path = run.fresh(name)
    if path is None:
        run_stages(trial, [name], cfg, out=out, progress=progress, plots=plots)
        path = run.output_folder(name) / stage(name).h5_name
    return path
