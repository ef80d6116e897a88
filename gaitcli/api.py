"""gaitcli as a Python library: open a trial, run its stages, read any output folder back, predict a gait.

These are the functions the ``gait`` command itself calls (``gait filter``, ``idyn``, ``emg``, ``muscles``,
``run`` go through :func:`run_trial`, ``gait predict`` through :func:`predict_gait`), so a script and the command line
compute, write and name the same things. The stages write their folders as the command does
(README.md's outputs table); what :func:`run_trial` returns is read back from those files by the same
readers :func:`read_outputs` uses, so both give the same objects for the same folder. Every table is a
:class:`pandas.DataFrame` whose column names carry their units (SI; angles in degrees: ``_deg``, ``_m``,
``_N``, ``_Nm``, ``_W``, ``_Nm_per_kg``, ``_W_per_kg``, ``_pct_body_weight``); the signs are README.md's
("Signs in the tables").

``import gaitcli`` loads this module on first use of a public name (``gaitcli.__all__``), and pandas is
imported when the first table is built (docs/architecture.md).
"""

from __future__ import annotations

import json
from functools import cached_property
from pathlib import Path

import numpy as np

from gaitcli.core.registry import ProgressCallback, no_progress, stage
from gaitcli.core.validate import replace_checked
from gaitcli.errors import InputError, NotConvergedError
from gaitcli.resources import sample_trial
from gaitcli.run.config import PipelineConfig, load_pipeline, pipeline_from_dict
from gaitcli.run.pipeline import StageOutcome, run_stages, trial_stages
from gaitcli.run.trial import TrialFolder
from gaitcli.run.trial import open_trial as _open_trial

__all__ = [
    "open_trial", "TrialFolder", "sample_trial", "pipeline_config", "PipelineConfig", "run_trial", "predict_gait",
    "read_outputs", "Outputs", "FilterOutputs", "IdynOutputs", "MuscleOutputs", "PredictionOutputs",
    "StageOutcome", "InputError", "NotConvergedError",
]

#: where an error of a setting given to a function of the API says it was given
CALLER = "gaitcli.pipeline_config"
#: the pelvis translations among the 27 coordinates (m; every other coordinate is an angle, deg)
TRANSLATIONS = ("pelvis_x", "pelvis_y", "pelvis_z")


def open_trial(path: str | Path) -> TrialFolder:
    """Open a trial: a trial folder, or one walk's C3D in a session folder, with its subject.

    Parameters
    ----------
    path : str or Path
        A trial folder (``trial.c3d`` or ``markers.csv``, ``subject.yaml`` or the session's ``.vsk``,
        optionally ``static.c3d``), or a walk's C3D beside its session's subject file.

    Returns
    -------
    TrialFolder
        The files found (``trial_path``, ``static_path``, ``subject_path``), the validated ``subject``
        (mass kg, stature m, sex, marker set) and ``out_root``, where the stages write by default.

    Raises
    ------
    InputError
        A file missing, or a subject file with a bad value (the message names the file and the key).

    Examples
    --------
    >>> trial = gaitcli.open_trial(gaitcli.sample_trial())
    >>> trial.trial_path.name, trial.subject.mass_kg
    ('trial.c3d', 75.0)
    """
    return _open_trial(path)


def pipeline_config(pipeline: str | Path | dict | PipelineConfig | None = None, **sections) -> PipelineConfig:
    """The configuration of a run: a pipeline file's, a bundled pipeline's or a mapping's, with overrides.

    The names and keys are those of the pipeline YAML (``pipelines/standard.yaml``): ``stages:`` and one
    section per stage (``filter``, ``idyn``, ``emg``, ``muscles``, ``predict``) with that stage's parameters.
    Every value goes through the validator the command line's flags and pipeline files go through.

    Parameters
    ----------
    pipeline : str, Path, dict, PipelineConfig or None
        A pipeline YAML file, a bundled pipeline by name (``"standard"``, ``"muscles_eid"``), the mapping such
        a file holds, or a configuration already made; None: the defaults (``pipelines/standard.yaml``).
    **sections : dict
        Per stage, parameters replacing the pipeline's (``filter={"cutoff_hz": 8}``); a value None keeps the
        pipeline's.

    Returns
    -------
    PipelineConfig
        ``stages`` and each stage's frozen configuration (``cfg.filter.cutoff_hz``, ``cfg.muscles.method``).

    Raises
    ------
    InputError
        An unknown stage or key, or a value out of its range; the message names the file (or ``command line``
        for an override) and the key.

    Examples
    --------
    >>> cfg = gaitcli.pipeline_config("muscles_eid", filter={"cutoff_hz": 8})
    >>> cfg.stages, cfg.filter.cutoff_hz, cfg.muscles.method
    (('filter', 'idyn', 'muscles'), 8.0, 'eid')
    >>> gaitcli.pipeline_config({"muscles": {"method": "eid", "nodes": 30}}).muscles.nodes
    30
    """
    if isinstance(pipeline, PipelineConfig):
        cfg = pipeline
    elif isinstance(pipeline, dict):
        cfg = pipeline_from_dict(pipeline, "pipeline mapping")
    else:
        cfg = load_pipeline(pipeline)
    for section, options in sections.items():
        if section not in cfg.sections:
            raise InputError(CALLER, section, f"not a stage (expected one of {', '.join(cfg.sections)})")
        given = {key: value for key, value in (options or {}).items() if value is not None}
        if given:
            cfg = cfg.replace_section(section, replace_checked(cfg.section(section), given, section=section,
                                                               path=CALLER))
    return cfg


def run_trial(trial: str | Path | TrialFolder | None = None, stages=None, config=None, *, out: str | Path | None = None,
        plots: bool = False, progress: ProgressCallback | None = None, workers: int | None = None,
        scheduler: str | None = None, files: dict | None = None) -> Outputs:
    """Run stages on one trial, write their folders as ``gait`` does, and return what they wrote.

    The stages asked for always run; a stage they need is read back from its output where that was made
    from the same files and configuration, else run first. Nothing is written until every stage has been
    computed, so bad input leaves every output as it was.

    Parameters
    ----------
    trial : str, Path, TrialFolder or None
        The trial folder or a walk's C3D (:func:`open_trial`); None: the bundled sample trial (written to
        ``./gait_out``).
    stages : iterable of str, optional
        The stages to run (``"filter"``, ``"idyn"``, ``"emg"``, ``"muscles"``, ``"predict"``); default: the
        configuration's ``stages`` and, where subject.yaml maps EMG channels, ``emg`` (as ``gait run``).
    config : str, Path, dict, PipelineConfig or None
        The configuration, as :func:`pipeline_config` takes it.
    out : str or Path, optional
        The output root (default: the trial's ``gait_out/``).
    plots : bool
        Also draw each stage's figures into its ``plots/`` (as ``gait`` does unless ``--no-plots``); off by
        default: they take as long as some stages.
    progress : callable, optional
        Receives :class:`gaitcli.core.registry.Progress` reports (the command line draws them as bars).
    workers, scheduler : optional
        Where a stage may run work in parallel: the number of worker processes, or a Dask scheduler's
        address (``predict`` with ``starts`` > 1).
    files : dict, optional
        Files named for the run, by name: predict's ``reference``, ``subject`` and ``init``.

    Returns
    -------
    Outputs
        One :class:`StageOutcome` per stage touched (``outcomes``) and each stage's outputs read back
        (``filter``, ``idyn``, ``emg`` folder, ``muscles[variant]``, ``predict``).

    Raises
    ------
    InputError
        Bad input (the message names the file, the field and what was expected); nothing is written.

    Notes
    -----
    An optimization that ends unconverged (EID, a prediction) is written with ``converged: false`` and
    returned: :attr:`Outputs.converged` says so, :meth:`Outputs.check` raises :class:`NotConvergedError`.

    Examples
    --------
    >>> outputs = gaitcli.run_trial(trial_folder, ["muscles"], {"muscles": {"method": "so"}})
    >>> [(o.stage, o.status) for o in outputs.outcomes]
    [('filter', 'reused'), ('idyn', 'reused'), ('muscles', 'written')]
    >>> outputs.muscles["so"].forces.columns[:3].tolist()
    ['time_s', 'iliopsoas_force_N', 'rectus_femoris_force_N']
    """
    cfg = pipeline_config(config)
    trial = trial.ref if isinstance(trial, TrialFolder) else (None if trial is None else Path(trial))
    names = trial_stages(trial, cfg) if stages is None else ((stages,) if isinstance(stages, str) else tuple(stages))
    files = {name: Path(path) for name, path in (files or {}).items() if path is not None}
    outcomes = run_stages(trial, names, cfg, out=None if out is None else Path(out),
                          progress=progress or no_progress, plots=plots, files=files, workers=workers,
                          scheduler=scheduler)
    paths = {_stage_key(o.stage, o.folder): o.folder / stage(o.stage).h5_name for o in outcomes}
    root = next((_output_root(key, path) for key, path in paths.items()), Path(out or "."))
    return Outputs(root, paths, tuple(outcomes))


def predict_gait(trial: str | Path | TrialFolder | None = None, config=None, *, reference: str | Path | None = None,
            subject: str | Path | None = None, init: str | Path | None = None, out: str | Path | None = None,
            plots: bool = False, progress: ProgressCallback | None = None, workers: int | None = None,
            scheduler: str | None = None, **settings) -> Outputs:
    """Predict one gait cycle (ch. 5) with the settings of ``gait predict``, and return what it wrote.

    Parameters
    ----------
    trial : str, Path, TrialFolder or None
        A trial whose subject to predict for, against a reference from its own strides; None: the
        dissertation's subject 1 against the shipped reference of the speed.
    config : str, Path, dict, PipelineConfig or None
        A configuration whose ``predict`` section to start from (:func:`pipeline_config`); the command line
        passes its flags' configuration here.
    reference, subject, init : str or Path, optional
        ``gait predict``'s ``--reference`` (a ``gait reference`` CSV), ``--subject`` (a subject.yaml) and
        ``--init`` (an earlier ``predict.h5`` to start from).
    out : str or Path, optional
        The output root (default: the trial's ``gait_out/``, else ``./gait_out``); the prediction goes to
        its ``predict/``.
    plots, progress, workers, scheduler
        As for :func:`run_trial`.
    **settings
        The ``predict`` section's parameters, as in a pipeline file (``speed_m_s=1.6``, ``weights=(2, 0)``,
        ``prosthesis="flex"``, ``nodes``, ``symmetric``, ``max_iterations``, ``time_limit_s``, ``starts``, …);
        ``gait predict --help`` lists them by their flags.

    Returns
    -------
    Outputs
        Its ``predict`` (:class:`PredictionOutputs`), and ``idyn`` where the trial's was run for it.

    Raises
    ------
    InputError
        A bad setting or file, before anything is solved.

    Examples
    --------
    A prediction takes about 25 s of one core; two IPOPT iterations on 6 nodes show the call:

    >>> outputs = gaitcli.predict_gait(nodes=6, max_iterations=2, out=workdir / "gait_out")
    >>> outputs.converged, outputs.predict.summary["iterations"]
    (False, 2)
    >>> outputs.predict.motion.columns[:4].tolist()
    ['time_s', 'cycle_pct', 'hip_x_m', 'hip_z_m']
    """
    cfg = pipeline_config(config, predict=settings)
    files = {"reference": reference, "subject": subject, "init": init}
    return run_trial(trial, ["predict"], cfg, out=out, plots=plots, progress=progress, workers=workers,
               scheduler=scheduler, files=files)


def read_outputs(path: str | Path) -> Outputs:
    """Read the outputs of ``gait`` (or :func:`run_trial`) back: an output root, a trial folder, a stage's folder
    or its file.

    Parameters
    ----------
    path : str or Path
        An output root (``gait_out/``: ``filter/``, ``idyn/``, ``emg/``, ``muscles/<variant>/``,
        ``predict/``), a trial folder holding ``gait_out/``, one stage's folder, or its HDF5 file
        (``filter.h5``, ``idyn.h5``, ``emg.h5``, ``muscles.h5``, ``predict.h5``).

    Returns
    -------
    Outputs
        The stages found; each is read when first asked for.

    Raises
    ------
    InputError
        No output of gait there; a damaged or foreign HDF5 file (when its stage is read).

    Examples
    --------
    >>> outputs = gaitcli.read_outputs(trial_folder / "gait_out")
    >>> sorted(outputs.stages)
    ['filter', 'idyn', 'muscles/eid']
    >>> outputs.idyn.strides[["stride", "side", "period_s", "stance_pct"]].head(2).round(2)
       stride side  period_s  stance_pct
    0       1    l      1.07       57.96
    1       2    r      1.07       57.94
    """
    path = Path(path)
    names = {stage(name).h5_name: name for name in ("filter", "idyn", "emg", "muscles", "predict")}
    if path.is_file() and path.name in names:
        key = _stage_key(names[path.name], path.parent)
        return Outputs(_output_root(key, path), {key: path})
    if path.is_dir() and any((path / h5).is_file() for h5 in names):
        h5 = next(h5 for h5 in names if (path / h5).is_file())
        key = _stage_key(names[h5], path)
        return Outputs(_output_root(key, path / h5), {key: path / h5})
    if path.is_dir() and not any((path / name).is_dir() for name in names.values()) and (path / "gait_out").is_dir():
        path = path / "gait_out"
    paths = {}
    for h5, name in names.items():
        found = sorted(path.glob(f"{name}/*/{h5}")) if name == "muscles" else [path / name / h5]
        paths.update({_stage_key(name, p.parent): p for p in found if p.is_file()})
    if not paths:
        raise InputError(path, None, "no outputs of gait here (expected an output folder with filter/filter.h5, "
                                     "idyn/idyn.h5, emg/emg.h5, muscles/<variant>/muscles.h5 or predict/predict.h5)")
    return Outputs(path, paths)


def _stage_key(name: str, folder: Path) -> str:
    """``"muscles/<variant>"`` for a muscle stage's folder, the stage's name otherwise."""
    return f"muscles/{Path(folder).name}" if name == "muscles" else name


def _output_root(key: str, h5_path: Path) -> Path:
    """The output root above a stage's HDF5 file (``muscles/<variant>/`` lies one folder deeper)."""
    return h5_path.parent.parent.parent if key.startswith("muscles/") else h5_path.parent.parent


def _summary(folder: Path) -> dict:
    """A stage folder's ``summary.json`` ({} where there is none)."""
    path = folder / "summary.json"
    if not path.is_file():
        return {}
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise InputError(path, None, f"not readable as JSON ({exc}; expected the summary gait wrote)") from None


def _frame(columns: dict, rename: dict | None = None):
    """A DataFrame of named columns (pandas imported here, on the first table)."""
    import pandas as pd

    frame = pd.DataFrame({name: np.asarray(values) for name, values in columns.items()})
    return frame.rename(columns=rename) if rename else frame


def _angle_name(name: str) -> str:
    """An angle column of the idyn tables with its unit: ``_m`` for a pelvis translation, ``_deg`` otherwise."""
    return f"{name}_m" if name in TRANSLATIONS else f"{name}_deg"


class Outputs:
    """The outputs of one trial's stages (or of a prediction): what :func:`run_trial` and :func:`read_outputs` return.

    Each stage is read from its HDF5 file when first asked for, then kept.

    Attributes
    ----------
    folder : Path
        The output root.
    paths : dict
        Each stage's HDF5 file by key: ``"filter"``, ``"idyn"``, ``"emg"``, ``"muscles/<variant>"``,
        ``"predict"``.
    outcomes : tuple of StageOutcome
        What became of each stage :func:`run_trial` touched (written, unconverged, reused); empty when read.

    Examples
    --------
    >>> outputs = gaitcli.read_outputs(trial_folder)
    >>> outputs.idyn.body_mass_kg, outputs.muscles["eid"].converged, outputs.predict
    (75.0, True, None)
    """

    def __init__(self, folder: Path, paths: dict[str, Path], outcomes: tuple[StageOutcome, ...] = ()):
        self.folder = Path(folder)
        self.paths = dict(paths)
        self.outcomes = tuple(outcomes)

    def __repr__(self) -> str:
        return f"Outputs({str(self.folder)!r}, stages={sorted(self.paths)})"

    @property
    def stages(self) -> tuple[str, ...]:
        """The keys of :attr:`paths`."""
        return tuple(self.paths)

    @property
    def converged(self) -> bool:
        """False where a stage's optimization ended unconverged (its outputs written all the same)."""
        if self.outcomes:
            return all(o.converged for o in self.outcomes)
        return all(m.converged for m in self.muscles.values()) and (self.predict is None or self.predict.converged)

    def check(self) -> Outputs:
        """These outputs; :class:`NotConvergedError` (as ``gait`` exits 3) where a stage did not converge."""
        failed = [o for o in self.outcomes if not o.converged]
        if failed:
            raise NotConvergedError(f"{failed[0].message}; results written to {failed[0].folder} with "
                                    "converged: false")
        return self

    @cached_property
    def filter(self) -> FilterOutputs | None:
        """The filter stage's outputs (None where there are none)."""
        return FilterOutputs.read(self.paths["filter"]) if "filter" in self.paths else None

    @cached_property
    def idyn(self) -> IdynOutputs | None:
        """The idyn stage's outputs (None where there are none)."""
        return IdynOutputs.read(self.paths["idyn"]) if "idyn" in self.paths else None

    @cached_property
    def muscles(self) -> dict[str, MuscleOutputs]:
        """The muscle stage's outputs by variant (``"eid"``, ``"so"``, ``"mso"``, ``"eid_l_swing"``, …)."""
        return {key.split("/", 1)[1]: MuscleOutputs.read(path) for key, path in self.paths.items()
                if key.startswith("muscles/")}

    @cached_property
    def predict(self) -> PredictionOutputs | None:
        """The prediction's outputs (None where there are none)."""
        return PredictionOutputs.read(self.paths["predict"]) if "predict" in self.paths else None

    @property
    def emg(self) -> Path | None:
        """The emg stage's folder (its tables are ``envelopes.csv``, ``cycle.csv``, ``onoff.csv``), or None."""
        return self.paths["emg"].parent if "emg" in self.paths else None


class FilterOutputs:
    """The filter stage's outputs (``filter/``), read from ``filter.h5``.

    Attributes
    ----------
    folder : Path
    summary : dict
        ``summary.json``.
    trial : gaitcli.core.container.Trial
        The filtered trial the later stages start from (markers, each foot's load, events).
    markers : pandas.DataFrame
        ``time_s``, ``frame``, ``<marker>_x_m``, ``_y_m``, ``_z_m`` (model axes: x forward, y left, z up).
    grf : pandas.DataFrame
        Per foot (``foot_r_``, ``foot_l_``): ``force_x_N`` … ``cop_z_m``, ``free_moment_Nm`` and ``load_known``.
    events : pandas.DataFrame
        ``time_s``, ``frame``, ``side``, ``event`` (``heel_strike``, ``toe_off``), ``source``.

    Examples
    --------
    >>> filtered = gaitcli.read_outputs(trial_folder).filter
    >>> filtered.summary["cutoff_hz"], int((filtered.events["event"] == "heel_strike").sum())
    (6.0, 8)
    >>> round(filtered.grf["foot_r_force_z_N"].max())  # N: 1.29 times the body weight of 75 kg
    947
    """

    def __init__(self, folder: Path, summary: dict, trial):
        from gaitcli.signal.outputs import events_table, load_columns, marker_columns

        self.folder, self.summary, self.trial = Path(folder), summary, trial
        self.markers = _frame(marker_columns(trial.markers))
        grf = {"time_s": trial.time_s}
        for side, load in trial.feet.items():
            grf.update(load_columns(f"foot_{side}", load))
            grf[f"foot_{side}_load_known"] = np.asarray(load.known, bool)
        self.grf = _frame(grf)
        self.events = _frame(events_table(trial.events, trial.markers.first_frame))

    @classmethod
    def read(cls, path: str | Path) -> FilterOutputs:
        """The outputs of a ``filter.h5`` and its folder."""
        from gaitcli.io.stage_files import read_filter_signals

        return cls(Path(path).parent, _summary(Path(path).parent), read_filter_signals(path).trial)


class IdynOutputs:
    """The idyn stage's outputs (``idyn/``), read from ``idyn.h5``; moments and powers NaN where the foot load
    they depend on is unknown (README.md).

    Attributes
    ----------
    folder : Path
    summary : dict
        ``summary.json`` (Table 3.1's features, the residuals, the fit).
    body_mass_kg : float
    angles : pandas.DataFrame
        ``time_s`` and the joint angles of ``kinematics.csv`` (``hip_r_flexion_deg``, …; the 27 coordinates,
        ``pelvis_x_m`` …, with ``angles: posture``).
    coordinates : pandas.DataFrame
        ``time_s`` and the model's 27 coordinates, zero in the standing posture (m, deg).
    moments : pandas.DataFrame
        ``time_s``, the 21 joint moments of ``joint_moments.csv`` in N·m (``hip_r_extensor_moment_Nm``, …) and
        per kg (``…_Nm_per_kg``).
    powers : pandas.DataFrame
        ``time_s`` and each hip's, knee's and ankle's total power (``hip_r_power_W``, ``…_W_per_kg``; generated
        positive).
    strides : pandas.DataFrame
        One row per complete stride, in time order: ``stride`` (1, 2, …), ``side``, ``start_s``, ``end_s``,
        ``toe_off_s``, ``period_s``, ``stance_pct``.
    cycles : pandas.DataFrame
        ``gait_cycle.csv``: every stride at 0–100 % (``cycle_pct``, ``side``, ``stride``, ``start_s``), its
        angles (deg), moments (``…_Nm_per_kg``), powers (``…_W_per_kg``) and ground reactions
        (``…_pct_body_weight``); a left stride's pelvis obliquity and rotation negated.
    sagittal : gaitcli.dynamics.sagittal.SagittalExport
        What the muscle stage reads: each leg's sagittal motion and load, the events.

    Examples
    --------
    >>> idyn = gaitcli.read_outputs(trial_folder).idyn
    >>> stride = idyn.cycles[idyn.cycles["stride"] == 4]
    >>> stride["side"].iloc[0], len(stride), round(stride["knee_r_flexion_deg"].max())
    ('r', 101, 61)
    >>> print(round(idyn.moments["ankle_r_plantarflexor_moment_Nm_per_kg"].max(), 1))
    2.0
    """

    def __init__(self, folder: Path, summary: dict, output):
        tables = output.tables
        self.folder, self.summary, self.sagittal = Path(folder), summary, output.sagittal
        self.body_mass_kg = float(tables.body_mass_kg)
        time = {"time_s": tables.time_s}
        self.angles = _frame({**time, **dict(zip(map(_angle_name, tables.angles.columns), tables.angles.values.T))})
        self.coordinates = _frame({**time, **dict(zip(map(_angle_name, tables.coordinates.columns),
                                                      tables.coordinates.values.T))})
        moments = tables.known_moments_Nm()
        self.moments = _frame({**time, **{f"{n}_Nm": moments[:, k] for k, n in enumerate(tables.moments.columns)},
                               **{f"{n}_Nm_per_kg": moments[:, k] / self.body_mass_kg
                                  for k, n in enumerate(tables.moments.columns)}})
        powers = tables.known_powers_W()
        joints = tables.powers.columns if tables.powers is not None else ()
        shown = [(k, j) for k, j in enumerate(joints) if j != "lumbar"]
        self.powers = _frame({**time, **{f"{j}_power_W": powers[:, k] for k, j in shown},
                              **{f"{j}_power_W_per_kg": powers[:, k] / self.body_mass_kg for k, j in shown}})
        strides = output.strides
        self.strides = _frame({
            "stride": np.arange(1, len(strides) + 1), "side": [s.side for s in strides],
            "start_s": [s.start_s for s in strides], "end_s": [s.end_s for s in strides],
            "toe_off_s": [s.toe_off_s for s in strides], "period_s": [s.period_s for s in strides],
            "stance_pct": [100 * (s.toe_off_s - s.start_s) / s.period_s for s in strides]})
        cycles = tables.cycles
        if cycles is None:
            raise InputError(Path(folder) / "idyn.h5", "gait_cycle", "absent: written by an older gaitcli (expected "
                                                                     "the strides at 0-100 %; run idyn again)")
        units = {**{n: _angle_name(n) for n in tables.angles.columns},
                 **{f"{n}_per_kg": f"{n}_Nm_per_kg" for n in tables.moments.columns}}
        self.cycles = _frame({"cycle_pct": cycles.cycle_pct, "side": cycles.side, "stride": cycles.stride,
                              "start_s": cycles.start_s,
                              **{units.get(n, n): cycles.values.values[:, k]
                                 for k, n in enumerate(cycles.values.columns)}})

    @classmethod
    def read(cls, path: str | Path) -> IdynOutputs:
        """The outputs of an ``idyn.h5`` and its folder."""
        from gaitcli.dynamics.outputs import read_idyn_output

        return cls(Path(path).parent, _summary(Path(path).parent), read_idyn_output(path))


class MuscleOutputs:
    """One muscle-stage variant's outputs (``muscles/<variant>/``), read from ``muscles.h5``.

    Attributes
    ----------
    folder : Path
    variant : str
        The folder's name: the method, ``_l`` (left leg), ``_swing``, ``_cb`` (Crowninshield–Brand).
    summary : dict
        ``summary.json`` (metabolic cost, the solver's report, the analysed interval).
    result : gaitcli.muscles.stage.MuscleResult
        Everything the stage computed (fibre lengths, moments, validation).
    forces, activations, excitations, metabolics : pandas.DataFrame
        ``time_s`` and per muscle ``<muscle>_force_N``, ``_activation``, ``_excitation``,
        ``_metabolic_rate_W`` (and ``total_metabolic_rate_W``), over the analysed interval.
    converged : bool
    metabolic_cost_J : float
        One leg over the interval (NaN where the energetics model does not apply, SO's excitations out of
        [0, 1]).

    Examples
    --------
    >>> eid = gaitcli.read_outputs(trial_folder).muscles["eid"]
    >>> eid.converged, round(eid.metabolic_cost_J), eid.forces.shape
    (True, 215, (50, 9))
    >>> eid.forces.drop(columns="time_s").max().idxmax()
    'vasti_force_N'
    """

    def __init__(self, folder: Path, summary: dict, result):
        from gaitcli.muscles.outputs import muscle_tables

        self.folder, self.summary, self.result = Path(folder), summary, result
        self.variant = self.folder.name
        tables = {name: _frame(columns) for name, columns in muscle_tables(result).items()}
        self.forces, self.activations = tables["forces"], tables["activations"]
        self.excitations, self.metabolics = tables["excitations"], tables["metabolics"]
        self.converged = bool(result.converged)
        self.metabolic_cost_J = float(result.metabolic_cost_J)

    @classmethod
    def read(cls, path: str | Path) -> MuscleOutputs:
        """The outputs of a ``muscles.h5`` and its folder."""
        from gaitcli.io.h5 import read_result
        from gaitcli.muscles.stage import MuscleResult

        return cls(Path(path).parent, _summary(Path(path).parent),
                   read_result(path, MuscleResult, what="gait muscles"))


class PredictionOutputs:
    """A prediction's outputs (``predict/``), read from ``predict.h5``.

    Attributes
    ----------
    folder : Path
    summary : dict
        ``summary.json`` (Et, Jdev, J, violations, phase durations, clinical checks, the reference).
    result : gaitcli.predict.stage.PredictResult
        Everything the prediction holds (design vector, phases, multipliers).
    motion, grf, moments, muscles : pandas.DataFrame
        ``motion.csv``'s hip position (m), trunk lean and sagittal angles (deg); ``grf.csv`` per foot (N, N/kg);
        ``moments.csv`` per joint (N·m); ``muscles.csv``: per muscle force (N), activation, excitation,
        metabolic rate (W); over the cycle (``time_s``, ``cycle_pct``).
    prosthesis : pandas.DataFrame or None
        With prostheses: each ankle's angle and spring, damping and total moments (N·m).
    converged : bool

    Examples
    --------
    :func:`predict_gait` returns them in its ``predict``; :func:`read_outputs` reads them from an output
    folder, here that of ``gait predict --nodes 6 --max-iterations 2 -o pr`` (two IPOPT iterations):

    >>> prediction = gaitcli.read_outputs(prediction_folder).predict
    >>> prediction.converged, prediction.prosthesis, prediction.muscles.shape[1]
    (False, None, 66)
    """

    def __init__(self, folder: Path, summary: dict, result):
        from gaitcli.predict.outputs import prediction_tables

        self.folder, self.summary, self.result = Path(folder), summary, result
        tables = {name: _frame(columns) for name, columns in prediction_tables(result).items()}
        self.motion, self.grf, self.moments, self.muscles = (tables[n] for n in ("motion", "grf", "moments",
                                                                                 "muscles"))
        self.prosthesis = tables.get("prosthesis")
        self.converged = bool(result.converged)

    @classmethod
    def read(cls, path: str | Path) -> PredictionOutputs:
        """The outputs of a ``predict.h5`` and its folder."""
        from gaitcli.io.h5 import read_result
        from gaitcli.predict.stage import PredictResult

        return cls(Path(path).parent, _summary(Path(path).parent),
                   read_result(path, PredictResult, what="gait predict"))
