"""The registry entries of the built-in stages: one :class:`~gaitcli.core.registry.Stage` each.

Each entry ties a stage's pure function (in its package) to its writer (the
package's ``outputs.py``), its figures (``report/plots.py``) and the reader of
its hand-off (``io/h5.py``). Adding a
stage is one module with its config and run function plus one entry here
(``docs/architecture.md``).

``predict`` needs no trial; with one it asks for the trial's idyn output (an
optional stage) only where it needs its reference or the subject's mass. Its
entry resolves what a prediction starts from: the subject (the ``subject`` file
named for the run, else the trial's, else the dissertation's subject 1), the
reference (the ``reference`` file, else one built from the trial's idyn output,
else the bundled one), the prostheses' curve and the ``init`` solution.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from gaitcli.core.container import Trial
from gaitcli.core.registry import Progress, Stage, StageContext, register
from gaitcli.dynamics.sagittal import SagittalExport
from gaitcli.dynamics.stage import IdynConfig, run_idyn
from gaitcli.emg.stage import EmgConfig, EmgResult
from gaitcli.errors import InputError
from gaitcli.io.h5 import read_result
from gaitcli.muscles.stage import MuscleResult, MusclesConfig, run_muscles_stage
from gaitcli.predict.checks import failed_checks
from gaitcli.predict.solve import NlpCache
from gaitcli.predict.stage import PredictConfig, PredictResult
from gaitcli.signal.stage import FilterConfig, filter_trial


def _filter(ctx: StageContext, cfg: FilterConfig):
    return filter_trial(ctx.recording(), cfg, marker_set=ctx.subject.marker_set, path=ctx.trial_path)


def _idyn(ctx: StageContext, cfg: IdynConfig):
    return run_idyn(ctx.inputs["filter"], ctx.static_recording(), ctx.subject, cfg, subject_path=ctx.subject_path,
                    static_path=ctx.static_path, trial_path=ctx.trial_path)


def _muscles(ctx: StageContext, cfg: MusclesConfig):
    """The muscle stage; where subject.yaml maps EMG channels, its activations against the emg stage's
    envelopes (:func:`gaitcli.emg.comparison.compare_with_emg`)."""
    from dataclasses import replace

    from gaitcli.emg.comparison import compare_with_emg

    ctx.report(f"muscles ({cfg.method.upper()})", 0, 1)
    result = run_muscles_stage(ctx.inputs["idyn"], cfg, stature_m=ctx.subject.stature_m, sex=ctx.subject.sex,
                               source=ctx.input_paths.get("idyn"))
    ctx.report(f"muscles ({cfg.method.upper()})", 1, 1)
    if ctx.subject.emg:
        emg = ctx.optional("emg")
        result = replace(result, emg=compare_with_emg(result.time_s, result.activations, result.muscle_names,
                                                      result.side, emg))
    return result


def _emg(ctx: StageContext, cfg: EmgConfig) -> EmgResult:
    """The emg stage on the trial's analog channels and the filter stage's events; the MVC trial subject.yaml
    names (``emg_mvc``, checked inside the trial folder by run/trial.py) read for its channels alone."""
    import warnings

    from gaitcli.emg.stage import run_emg
    from gaitcli.errors import GaitWarning
    from gaitcli.io.c3d import read_c3d

    trial = ctx.inputs["filter"]
    mvc_path = ctx.folder / ctx.subject.emg_mvc if ctx.subject.emg_mvc else None
    mvc = None
    if mvc_path is not None and cfg.normalise != "peak":
        with warnings.catch_warnings():  # markers and plates of a contraction trial are not read
            warnings.filterwarnings("ignore", category=GaitWarning)
            mvc = read_c3d(mvc_path, to_model_axes=False).analogs
        if mvc is None:
            raise InputError(mvc_path, "emg_mvc", "the MVC trial has no analog channels besides its force plates "
                                                  "(expected the EMG channels of the trial)")
    return run_emg(ctx.recording().analogs, trial.events, ctx.subject.emg or None, cfg, mvc=mvc,
                   source=ctx.trial_path, map_source=ctx.subject_path, mvc_source=mvc_path, history=trial.history)


def _emg_figures(h5_path, folder, title):
    from gaitcli.report.emg_plots import emg_figures

    return emg_figures(h5_path, folder, title=title)


def _unconverged_muscles(result: MuscleResult) -> str:
    why = f": {result.diagnosis}" if result.diagnosis else ""
    return f"{result.method.upper()} did not converge ({result.status}){why}"


def _writer(module: str, name: str):
    """The writer ``<module>.<name>`` (a stage package's ``outputs``), imported when a stage first writes."""
    def write(folder, result, attrs):
        from importlib import import_module

        return getattr(import_module(module), name)(folder, result, attrs)
    return write


def _figures(name: str):
    """The figures ``report.plots.<name>(h5_path, folder, title)``, imported only when plots are drawn."""
    def draw(h5_path, folder, title):
        from gaitcli.report import plots

        return getattr(plots, name)(h5_path, folder, title=title)
    return draw


def _number(value, spec: str) -> str:
    """``value`` formatted by ``spec``, or "?" where the summary has none (a null: no strides, a failed fit)."""
    return "?" if value is None or value != value else format(value, spec)


def describe_filter(s: dict) -> str:
    """``filter: 428 frames, 2 plates, 6 Hz, 3 gaps filled``."""
    return (f"{s.get('frames')} frames, {s.get('plates')} plates, {_number(s.get('cutoff_hz'), 'g')} Hz, "
            f"{s.get('gaps_filled', 0)} gaps filled")


def describe_idyn(s: dict) -> str:
    """``idyn: 6 strides, 1.30 m/s, stance 58/58 %``."""
    return (f"{s.get('strides')} strides, {_number(s.get('speed_m_s'), '.2f')} m/s, stance "
            f"{_number(s.get('stance_right_pct'), '.0f')}/{_number(s.get('stance_left_pct'), '.0f')} %")


def describe_emg(s: dict) -> str:
    """``emg: 8 channels, 4 strides, normalised to peak`` (and the channels that clip)."""
    text = (f"{len(s.get('channels', []))} channels, {s.get('strides')} strides, normalised to "
            f"{s.get('normalisation')}")
    return text + (f"; clipping: {', '.join(s['clipped'])}" if s.get("clipped") else "")


def describe_muscles(s: dict) -> str:
    """``muscles: eid right: converged, 215 J`` (and excitations outside [0, 1], the validation's RMS)."""
    side = {"r": "right", "l": "left"}.get(s.get("side"), s.get("side"))
    text = (f"{s.get('method')} {side}{' swing' if s.get('phase') == 'swing' else ''}: "
            f"{'converged' if s.get('converged') else 'did not converge'}")
    if s.get("metabolic_cost_J") is not None:  # SO has none
        text += f", {_number(s['metabolic_cost_J'], '.0f')} J"
    low, high = s.get("min_excitation"), s.get("max_excitation")
    if low is not None and high is not None and (low < -1e-3 or high > 1 + 1e-3):
        text += f", excitations {low:.2f}…{high:.2f} outside [0, 1]"
    if s.get("validation_rms_deg") is not None:
        text += f", forward validation {s['validation_rms_deg']:.2f}° RMS"
    return text


def describe_prediction(s: dict) -> str:
    """``predict: converged in 232 it., Et 350 J/m, 1 gait check failed``."""
    failed = failed_checks(s.get("gait_checks"))
    return (f"{'converged' if s.get('converged') else 'did not converge'} in {s.get('iterations')} it., "
            f"Et {_number(s.get('cost_of_transport_J_per_m'), '.0f')} J/m, J {_number(s.get('objective'), '.4g')}, "
            f"{len(failed)} gait check{'' if len(failed) == 1 else 's'} failed"
            + (f" ({', '.join(failed)})" if failed else ""))


FILTER = register(Stage(
    name="filter", config=FilterConfig, run=_filter, write=_writer("gaitcli.signal.outputs", "write_filter_outputs"),
    read=lambda path: read_result(path, Trial, "trial"), handoff=lambda result: result.trial,
    h5_name="filter.h5", plots=_figures("filter_figures"), describe=describe_filter))

IDYN = register(Stage(
    name="idyn", config=IdynConfig, depends=("filter",), run=_idyn,
    write=_writer("gaitcli.dynamics.outputs", "write_idyn_outputs"),
    read=lambda path: read_result(path, SagittalExport, "sagittal"), handoff=lambda result: result.sagittal,
    h5_name="idyn.h5", plots=_figures("idyn_figures"), describe=describe_idyn))

EMG = register(Stage(
    name="emg", config=EmgConfig, depends=("filter",), run=_emg,
    write=_writer("gaitcli.emg.outputs", "write_emg_outputs"), result=EmgResult, h5_name="emg.h5",
    plots=_emg_figures, describe=describe_emg))

MUSCLES = register(Stage(
    name="muscles", config=MusclesConfig, depends=("idyn",), optional=("emg",), run=_muscles,
    write=_writer("gaitcli.muscles.outputs", "write_muscle_outputs"),
    result=MuscleResult, h5_name="muscles.h5",
    plots=_figures("muscle_figures"), folder=lambda cfg: f"muscles/{cfg.variant}",
    converged=lambda result: result.converged, unconverged=_unconverged_muscles, describe=describe_muscles))


# ------------------------------------------------------------------------------------------------------- predict
@dataclass(frozen=True)
class PredictionInputs:
    """What a prediction starts from besides its configuration: the subject's model parameters, the reference
    of Jdev (None: the shipped one of each prediction's speed, :meth:`at_speed`), the prostheses' curve of a
    commercial foot or a file (None otherwise) and a design vector to start from (None: the default guess)."""

    params: object
    reference: object
    device: object = None
    init: np.ndarray | None = None
    warm: object = None  # the init file's variables and multipliers (predict.solve.WarmStart), where it has them

    def at_speed(self, cfg: PredictConfig, reference=None):
        """(cfg, reference, speed reference) of a prediction at ``cfg``'s speed: ``reference`` or the given one
        as it is (speed reference None); else the shipped reference at that speed for this subject
        (:func:`gaitcli.predict.speed_reference.speed_reference`), whose group's stride ± 1 SD bounds the stride
        (5.44) unless ``cfg.stride_range_m`` is set."""
        from gaitcli.predict.speed_reference import speed_reference

        if reference is not None or self.reference is not None:
            return cfg, (reference if reference is not None else self.reference), None
        by_speed = speed_reference(cfg.speed_m_s, self.params.leg_length_m, self.params.limb.gravity_m_s2)
        if cfg.stride_range_m is None:
            cfg = replace(cfg, stride_range_m=by_speed.stride_range_m)
        return cfg, by_speed.reference, by_speed


@dataclass(frozen=True)
class Prediction:
    """The predict stage's result: the prediction, its configuration and, of ``--starts N``, every start's
    figures (starts.csv's table) and how many starts reached the best J."""

    result: PredictResult
    cfg: PredictConfig
    starts: dict | None = None
    agreed: int = 0
    by_speed: object = None  # the shipped per-speed reference it tracked (predict.speed_reference), if it did

    @property
    def history(self) -> tuple[str, ...]:
        return self.result.history


def read_warm(path: Path):
    """The last NLP variables and multipliers of an earlier ``predict.h5`` (a ``WarmStart``), or None where the
    file has none (written before they were stored, or by an unconverged run that never solved)."""
    from gaitcli.io.h5 import read_field
    from gaitcli.predict.solve import WarmStart

    try:
        arrays = [np.asarray(read_field(path, PredictResult, name, what="gait predict"), float)
                  for name in ("nlp_variables", "constraint_multipliers", "bound_multipliers")]
    except (InputError, KeyError, ValueError, TypeError):
        return None
    return WarmStart(*arrays) if all(a.size for a in arrays) else None


def read_init(path: Path):
    """The design vector χ of an earlier ``predict.h5`` (the ``init`` file)."""
    from gaitcli.io.h5 import read_field

    try:
        design = np.asarray(read_field(path, PredictResult, "design", what="gait predict"), float)
        if design.ndim != 1 or not np.isfinite(design).all():
            bad = int(np.size(design) - np.isfinite(design).sum())
            raise InputError(path, "--init", f"result/design holds {bad} values that are not finite numbers "
                                             "(expected the solution of an earlier gait predict)")
        return design
    except InputError as exc:  # not HDF5, no design, a link loop
        if exc.field is not None:  # a design gaitcli will not read (too large, not finite, elsewhere): as said
            if exc.field.startswith("--init"):
                raise
            raise InputError(path, f"--init: {exc.field}", exc.problem) from None
    except (ValueError, TypeError):  # text where the design's numbers belong
        pass
    if not Path(path).exists():
        raise InputError(path, "--init", "file not found (expected a predict.h5 of an earlier gait predict)")
    raise InputError(path, "--init", "not a predict.h5 (expected result/design, the solution of an earlier "
                                     "gait predict)")


def prosthesis_curve(ctx: StageContext, cfg: PredictConfig):
    """The prostheses' curve of ``cfg.prosthesis``: a commercial foot (Table A.7), a YAML file's (validated:
    :func:`gaitcli.predict.prosthesis.curve_from_mapping`), or None (none, optimal)."""
    from gaitcli.io.yamlfile import read_yaml
    from gaitcli.predict.prosthesis import CHOICES, curve_for, curve_from_mapping

    if cfg.prosthesis in CHOICES:
        return curve_for(cfg.prosthesis)
    path = Path(cfg.prosthesis)
    curve = curve_from_mapping(read_yaml(path), path, cfg.monotone_range_rad())
    ctx.uses(path)
    return curve


def prediction_subject(ctx: StageContext):
    """The subject of a prediction: the ``subject`` file named for the run, else the trial's, else None (the
    dissertation's subject 1); a named subject must give its mass."""
    from gaitcli.kinematics.subject import load_subject

    path = ctx.files.get("subject")
    if path is None:
        return ctx.subject
    subject = load_subject(path)
    ctx.uses(path)
    if subject.mass_kg is None:
        raise InputError(path, "mass_kg", "got 'auto' (expected the body mass in kg: gait predict has no force "
                                          "plates to weigh the subject)")
    return subject


def prediction_inputs(ctx: StageContext, cfg: PredictConfig) -> PredictionInputs:
    """Everything a prediction starts from (module docstring), read and checked before anything is solved."""
    from gaitcli.dynamics.outputs import read_idyn_output
    from gaitcli.predict.model import WalkerParameters
    from gaitcli.predict.reference import read_reference, reference_from_idyn
    from gaitcli.predict.speed_reference import GROUPS_FILE, SpeedGroups, group_file

    device = prosthesis_curve(ctx, cfg)
    init = read_init(ctx.files["init"]) if "init" in ctx.files else None
    warm = read_warm(ctx.files["init"]) if init is not None else None
    given = ctx.files.get("reference")
    reference = read_reference(given) if given is not None else None
    for name in ("init", "reference"):
        if name in ctx.files:
            ctx.uses(ctx.files[name])
    subject = prediction_subject(ctx)
    mass = subject.mass_kg if subject is not None else None
    if reference is None or (subject is not None and mass is None):
        sagittal = ctx.optional("idyn")
        if sagittal is not None:
            if reference is None:
                idyn = read_idyn_output(ctx.input_paths["idyn"])
                reference, _, _ = reference_from_idyn([idyn], sources=[ctx.folder.resolve().name])
            if mass is None:
                mass = float(sagittal.body_mass_kg)
    params = (WalkerParameters.from_subject(mass, subject.stature_m, subject.sex,
                                            thigh_length_m=subject.thigh_length_m,
                                            shank_length_m=subject.shank_length_m)
              if subject is not None else WalkerParameters.subject_1())
    if reference is None:  # each speed's own (PredictionInputs.at_speed): the shipped tables are its inputs
        for path in (GROUPS_FILE, *(group_file(g) for g in SpeedGroups.read().names)):
            ctx.uses(path)
    return PredictionInputs(params, reference, device, init, warm)


@functools.lru_cache(maxsize=1)
def prediction_cache() -> NlpCache:
    """The prediction problems built in this process, kept for the next prediction it runs (a study's cases,
    ``--starts``, a test session's commands): one problem per structure, whose speed, weights and a foot's
    coefficients are parameters (:class:`gaitcli.predict.solve.NlpCache`)."""
    return NlpCache()


def _predict(ctx: StageContext, cfg: PredictConfig) -> Prediction:
    """A prediction (:func:`gaitcli.predict.stage.run_predict`); the optimal prosthesis by
    :func:`gaitcli.predict.starts.predict_optimal`; ``starts`` > 1: the best of that many
    (:func:`gaitcli.run.studies.best_of_starts`)."""
    from gaitcli.predict.stage import run_predict
    from gaitcli.predict.starts import predict_optimal

    start = prediction_inputs(ctx, cfg)
    cfg, reference, by_speed = start.at_speed(cfg)
    start = replace(start, reference=reference)
    if cfg.starts > 1:
        from gaitcli.run.studies import best_of_starts

        result, table, agreed = best_of_starts(cfg, params=start.params, reference=start.reference,
                                               device=start.device, workers_count=ctx.workers, scheduler=ctx.scheduler,
                                               progress=ctx.progress)
        return Prediction(result, cfg, table, agreed, by_speed)

    def iteration(k, objective, violation):
        ctx.progress(Progress("predict", "IPOPT iterations", k + 1, cfg.max_iterations,
                              detail=f"J {objective:.4g}, max violation {violation:.2g}"))

    if cfg.prosthesis == "optimal":
        result = predict_optimal(cfg, params=start.params, reference=start.reference, init=start.init,
                                 report=iteration, cache=prediction_cache())
    else:
        result = run_predict(cfg, params=start.params, reference=start.reference, init=start.init,
                             warm=start.warm, report=iteration, device=start.device, cache=prediction_cache())
    return Prediction(result, cfg, by_speed=by_speed)


def _write_prediction(folder: Path, prediction: Prediction, attrs: dict) -> dict:
    """The prediction's tables and predict.h5 (``predict.outputs``), and of ``--starts N`` starts.csv."""
    from gaitcli.io.outputs import write_table
    from gaitcli.predict.outputs import write_predict_outputs

    summary = write_predict_outputs(folder, prediction.result, attrs)
    if prediction.by_speed is not None:
        summary.update(prediction.by_speed.summary())
    if prediction.cfg.stride_range_m is not None:
        summary["stride_range_m"] = list(prediction.cfg.stride_range_m)
    if prediction.starts is not None:
        write_table(folder / "starts.csv", prediction.starts)
        summary.update({"starts": prediction.cfg.starts, "starts_converged": int(sum(prediction.starts["converged"])),
                        "starts_agreeing": prediction.agreed})
    return summary


def _unconverged_prediction(prediction: Prediction) -> str:
    """The prediction did not converge: why (IPOPT's status, or the time limit) and the violated constraint
    groups."""
    from gaitcli.predict.settings import TIME_LIMIT_STATUS
    from gaitcli.predict.stage import violated_groups

    result = prediction.result
    parts = [f"{name} by {value:.3g}" for name, value in violated_groups(result.violations).items()]
    status = (f"time limit of {prediction.cfg.time_limit_s:g} s reached" if result.status == TIME_LIMIT_STATUS
              else result.status)
    return f"the prediction did not converge ({status}" + (f"; violated: {', '.join(parts)}" if parts else "") + ")"


def _prediction_figures(h5_path, folder, title):
    from gaitcli.report.predict_plots import predict_figures

    return predict_figures(h5_path, folder, title=title or "subject 1")


PREDICT = register(Stage(
    name="predict", config=PredictConfig, optional=("idyn",), trial=False, run=_predict, write=_write_prediction,
    read=lambda path: read_result(path, PredictResult), handoff=lambda prediction: prediction.result,
    h5_name="predict.h5", plots=_prediction_figures,
    converged=lambda prediction: prediction.result.converged, unconverged=_unconverged_prediction,
    describe=describe_prediction))
