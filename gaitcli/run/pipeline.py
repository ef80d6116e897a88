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
from dataclasses import dataclass
from pathlib import Path

from gaitcli.run.config import PipelineConfig, section_dict, to_yaml
from gaitcli.core.recording import Recording
from gaitcli.core.container import Trial
from gaitcli.core.registry import ProgressCallback, StageContext, no_progress, requirements, stage, stage_names
from gaitcli.errors import GaitWarning, InputError
from gaitcli.io.atomic import check_output_folder, check_replaceable
from gaitcli.io.h5 import file_attrs, provenance, read_result, record_datasets, write_h5
from gaitcli.io.outputs import stage_folder, write_json
from gaitcli.resources import sample_trial
from gaitcli.run.trial import TrialFolder, open_trial, sha256

#: bump when a stage's output files change, so that older outputs count as stale
OUTPUT_FORMAT = 2


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


class TrialRun:
    """One trial, its output root and the resolved configuration: freshness, provenance, inputs read once."""

    def __init__(self, trial: Path | None, out: Path | None, cfg: PipelineConfig):
        bundled = trial is None
        self.trial = open_trial(sample_trial() if bundled else trial)
        if out is None:
            out = Path.cwd() / "gait_out" if bundled else self.trial.folder / "gait_out"
        self.out_root = Path(out)
        self.cfg = cfg
        self.inputs = {p.name: sha256(p) for p in self.trial.input_files()}
        self._recording: Recording | None = None

    def recording(self) -> Recording:
        if self._recording is None:
            self._recording = load_recording(self.trial)
        return self._recording

    def stage_key(self, name: str) -> str:
        """What a stage's output depends on: input hashes and the configuration of it and earlier stages."""
        cfg = {s: section_dict(self.cfg, s) for s in requirements(name)}
        return json.dumps({"inputs": self.inputs, "config": cfg, "format": OUTPUT_FORMAT}, sort_keys=True)

    def attrs(self, name: str, history: tuple[str, ...] = ()) -> dict:
        attrs = provenance(to_yaml(self.cfg), self.inputs, history)
        attrs["stage_key"] = self.stage_key(name)
        attrs["trial"] = self.trial.folder.resolve().name
        return attrs

    def output_folder(self, name: str) -> Path:
        return self.out_root / stage(name).output_folder(self.cfg.section(name))

    def fresh(self, name: str) -> Path | None:
        """The stage's HDF5 output if it exists and was made from the same inputs and configuration."""
        path = self.output_folder(name) / stage(name).h5_name
        if not path.is_file():
            return None
        try:
            key = file_attrs(path).get("stage_key")
        except InputError:  # damaged: made anew
            return None
        return path if key == self.stage_key(name) else None


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


def run_stages(trial: Path | None, names, cfg: PipelineConfig, *, out: Path | None = None,
               progress: ProgressCallback = no_progress, plots: bool = True) -> list[StageOutcome]:
    """Run the stages ``names`` (and whatever they need) on one trial; one outcome per stage touched.

    The named stages always run; a stage they depend on is read back from its
    output where that is fresh. Nothing is written until every stage has been
    computed. Raises :class:`~gaitcli.errors.InputError` for bad input (nothing
    written); an unconverged optimization is written and reported in its outcome.
    """
    run = TrialRun(trial, out, cfg)
    check_output_folder(run.out_root)
    names = tuple(names)
    needed = needed_stages(names)
    handoffs, sources, outcomes, computed = {}, {}, [], []

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
        started = time.perf_counter()
        ctx = StageContext(subject=run.trial.subject, folder=run.trial.folder, subject_path=run.trial.subject_path,
                           trial_path=run.trial.trial_path, static_path=run.trial.static_path,
                           inputs={d: handoffs[d] for d in st.depends}, input_paths={d: sources[d] for d in st.depends},
                           recording=run.recording, static_recording=static_recording, progress=progress, stage=name)
        result = st.run(ctx, cfg.section(name))
        handoffs[name], sources[name] = st.handoff(result), run.trial.trial_path
        computed.append((name, result, time.perf_counter() - started))

    for name, _, _ in computed:  # before the first write: a user's file in any folder to replace stops them all
        check_replaceable(run.output_folder(name))
    for name, result, elapsed in computed:
        st = stage(name)
        target = run.output_folder(name)
        started = time.perf_counter()
        with stage_folder(target) as tmp:
            summary = _write(st, tmp, result, run.attrs(name, _history(result)))
            if plots and st.plots is not None:
                st.plots(tmp / st.h5_name, tmp / "plots", run.trial.folder.resolve().name)
            summary["elapsed_s"] = round(elapsed + time.perf_counter() - started, 3)
            write_json(tmp / "summary.json", summary)
        converged = st.converged(result)
        outcomes.append(StageOutcome(name, "written" if converged else "unconverged", target, summary, converged,
                                     "" if converged else st.unconverged(result), summary["elapsed_s"]))
    order = {n: i for i, n in enumerate(needed)}
    return sorted(outcomes, key=lambda o: order[o.stage])


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


@dataclass(frozen=True)
class PredictOutcome:
    """What ``gait predict`` wrote: the folder, its summary, whether the optimization converged and, if not,
    a one-line ``message`` naming the violated constraint groups."""

    folder: Path
    summary: dict
    converged: bool
    message: str = ""


def _read_init(path: Path):
    """The design vector χ of an earlier ``predict.h5`` (``--init``)."""
    import numpy as np

    from gaitcli.errors import InputError
    from gaitcli.io.h5 import read_field
    from gaitcli.predict.stage import PredictResult

    try:
        return np.asarray(read_field(path, PredictResult, "design", what="gait predict"), float)
    except InputError as exc:  # not HDF5, no design, a link loop
        if exc.field is not None:  # a design gaitcli will not read (too large): as io.h5 names it
            raise
    except (ValueError, TypeError):  # text where the design's numbers belong
        pass
    if not Path(path).exists():
        raise InputError(path, "--init", "file not found (expected a predict.h5 of an earlier gait predict)")
    raise InputError(path, "--init", "not a predict.h5 (expected result/design, the solution of an earlier "
                                     "gait predict)")


def prosthesis_of(cfg):
    """The prostheses' curve of ``cfg.prosthesis``: a commercial foot (Table A.7), a YAML file's (validated:
    :func:`gaitcli.predict.prosthesis.curve_from_mapping`), or None (none, optimal)."""
    from gaitcli.errors import InputError
    from gaitcli.io.yamlfile import read_yaml
    from gaitcli.predict.prosthesis import CHOICES, curve_for, curve_from_mapping

    if cfg.prosthesis in CHOICES:
        return curve_for(cfg.prosthesis)
    path = Path(cfg.prosthesis)
    if path.suffix.lower() not in (".yaml", ".yml"):
        raise InputError(None, "--prosthesis", f"got {cfg.prosthesis!r} (expected {', '.join(CHOICES)} or a .yaml "
                                               "file of a_p, b_p, c0, a_n, b_n, d_prosth)")
    if not path.is_file():
        raise InputError(path, "--prosthesis", "file not found (expected a YAML file of a_p, b_p, c0, a_n, b_n, "
                                               "d_prosth)")
    return curve_from_mapping(read_yaml(path), path, cfg.monotone_range_rad())


def predict_inputs(trial: Path | None, *, out: Path | None = None, reference_path: Path | None = None,
                   subject_path: Path | None = None, progress: ProgressCallback = no_progress,
                   pipeline: PipelineConfig | None = None):
    """The subject's model parameters, the reference, the inputs' SHA-256 and the trial folder of a prediction:
    the subject is ``subject_path``'s, else the trial's, else the dissertation's subject 1; the reference is
    ``reference_path``'s, else one built from the trial's idyn output (made if missing or stale), else the
    bundled one."""
    from gaitcli.run.config import configure
    from gaitcli.dynamics.outputs import read_idyn_output
    from gaitcli.errors import InputError
    from gaitcli.predict.model import WalkerParameters
    from gaitcli.predict.reference import read_reference, reference_from_idyn
    from gaitcli.resources import bundled_reference
    from gaitcli.kinematics.subject import load_subject

    folder = open_trial(trial) if trial is not None else None
    reference = read_reference(reference_path) if reference_path is not None else None
    subject = load_subject(subject_path) if subject_path is not None else (folder.subject if folder else None)
    if subject is not None and subject_path is not None and subject.mass_kg is None:
        raise InputError(subject_path, "mass_kg", "got 'auto' (expected the body mass in kg: gait predict has no "
                                                  "force plates to weigh the subject)")
    inputs = {str(p): sha256(p) for p in (reference_path, subject_path) if p is not None}
    mass = subject.mass_kg if subject is not None else None
    if folder is not None and (reference is None or mass is None):
        idyn = fresh_output(trial, "idyn", pipeline or configure(None), out=out, progress=progress, plots=False)
        inputs[str(idyn)] = sha256(idyn)
        output = read_idyn_output(idyn)
        if reference is None:
            reference, _, _ = reference_from_idyn([output], sources=[folder.folder.resolve().name])
        if mass is None:
            mass = output.sagittal.body_mass_kg
    if reference is None:
        reference = read_reference(bundled_reference())
        inputs[str(bundled_reference())] = sha256(bundled_reference())
    params = (WalkerParameters.from_subject(mass, subject.stature_m, subject.sex,
                                            thigh_length_m=subject.thigh_length_m,
                                            shank_length_m=subject.shank_length_m)
              if subject is not None else WalkerParameters.subject_1())
    return params, reference, inputs, folder


def predict_study(trial: Path | None, study_path: Path, *, out: Path | None = None,
                  reference_path: Path | None = None, subject_path: Path | None = None, workers: int | None = None,
                  force: bool = False, progress: ProgressCallback = no_progress,
                  pipeline: PipelineConfig | None = None, scheduler: str | None = None):
    """``gait predict --study FILE``: validate the study file and the inputs, run every case
    (:func:`gaitcli.run.studies.run_study`) into ``OUT/study/``. Returns (rows, the study folder)."""
    from gaitcli.run.config import configure
    from gaitcli.io.yamlfile import read_yaml
    from gaitcli.predict.starts import StudySpec
    from gaitcli.run.studies import run_study

    if not Path(study_path).is_file():
        raise InputError(study_path, "--study", "file not found (expected a study YAML: name, speeds_m_s, weights, "
                                                "conditions)")
    spec = StudySpec.from_mapping(read_yaml(study_path), study_path)
    params, reference, inputs, _ = predict_inputs(trial, out=out, reference_path=reference_path,
                                                  subject_path=subject_path, progress=progress, pipeline=pipeline)
    inputs[str(study_path)] = sha256(study_path)
    root = Path(out) if out is not None else (Path(trial) / "gait_out" if trial is not None else Path("gait_out"))
    check_output_folder(root)
    attrs = provenance(to_yaml(configure(None)) if pipeline is None else to_yaml(pipeline), inputs)
    return run_study(spec, root, params=params, reference=reference, subject=repr(params), attrs=attrs,
                     workers=workers, force=force, scheduler=scheduler, progress=progress)


def predict_trial(trial: Path | None, cfg, *, out: Path | None = None, reference_path: Path | None = None,
                  subject_path: Path | None = None, init_path: Path | None = None,
                  progress: ProgressCallback = no_progress, pipeline: PipelineConfig | None = None,
                  plots: bool = True, starts: int = 1, seed: int = 0, workers: int | None = None,
                  scheduler: str | None = None) -> PredictOutcome:
    """``gait predict``: validate every input, predict (:func:`gaitcli.predict.stage.run_predict`; the optimal
    prosthesis by :func:`gaitcli.predict.starts.predict_optimal`; ``starts`` > 1: the best of that many starts,
    :func:`gaitcli.run.studies.best_of_starts`), write ``OUT/predict/`` whole (``predict.outputs``) with its
    ``summary.json`` (and ``starts.csv``). Subject and reference as :func:`predict_inputs`."""
    from gaitcli.run.config import configure
    from gaitcli.core.registry import Progress
    from gaitcli.predict.nlp import TIME_LIMIT_STATUS
    from gaitcli.predict.prosthesis import CHOICES as PROSTHESIS_CHOICES
    from gaitcli.predict.stage import run_predict, violated_groups
    from gaitcli.predict.outputs import write_predict_outputs

    # everything is validated before anything runs or is written
    device = prosthesis_of(cfg)
    init = _read_init(Path(init_path)) if init_path is not None else None
    params, reference, inputs, folder = predict_inputs(trial, out=out, reference_path=reference_path,
                                                       subject_path=subject_path, progress=progress,
                                                       pipeline=pipeline)
    root = Path(out) if out is not None else (Path(trial) / "gait_out" if trial is not None else Path("gait_out"))
    check_output_folder(root)  # before the solve, which may take minutes
    for p in (init_path, None if cfg.prosthesis in PROSTHESIS_CHOICES else Path(cfg.prosthesis)):
        if p is not None:
            inputs[str(p)] = sha256(p)

    def iteration(k, objective, violation):
        progress(Progress("predict", "IPOPT iterations", k + 1, cfg.max_iterations,
                          detail=f"J {objective:.4g}, max violation {violation:.2g}"))

    starts_table = None
    if starts > 1:
        from gaitcli.run.studies import best_of_starts

        result, starts_table, agreed = best_of_starts(cfg, starts, params=params, reference=reference, device=device,
                                                 seed=seed, workers=workers, scheduler=scheduler, progress=progress)
    elif cfg.prosthesis == "optimal":
        from gaitcli.predict.starts import predict_optimal

        result = predict_optimal(cfg, params=params, reference=reference, init=init, report=iteration)
    else:
        result = run_predict(cfg, params=params, reference=reference, init=init, report=iteration, device=device)
    target = root / "predict"
    attrs = provenance(to_yaml(configure(None)) if pipeline is None else to_yaml(pipeline), inputs, result.history)
    attrs["predict_config"] = json.dumps(dataclasses.asdict(cfg))
    with stage_folder(target) as tmp:
        summary = write_predict_outputs(tmp, result, attrs)
        if starts_table is not None:
            from gaitcli.io.outputs import write_table

            write_table(tmp / "starts.csv", starts_table)
            summary.update({"starts": starts, "starts_converged": int(sum(starts_table["converged"])),
                            "starts_agreeing": agreed})
        write_json(tmp / "summary.json", summary)
        if plots:
            from gaitcli.report.predict_plots import predict_figures

            progress(Progress("predict", "figures", 0, 1))
            predict_figures(tmp / "predict.h5", tmp / "plots", title=folder.folder.name if folder else "subject 1")
            progress(Progress("predict", "figures", 1, 1))
    message = ""
    if not result.converged:
        bad = violated_groups(result.violations)
        parts = [f"{name} by {value:.3g}" for name, value in bad.items()]
        status = (f"time limit of {cfg.time_limit_s:g} s reached" if result.status == TIME_LIMIT_STATUS
                  else result.status)
        message = (f"the prediction did not converge ({status}"
                   + (f"; violated: {', '.join(parts)}" if parts else "") + ")")
    return PredictOutcome(folder=target, summary=summary, converged=result.converged, message=message)
