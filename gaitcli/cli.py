"""The ``gait`` command: parses options, loads config, calls the pipeline, prints.

Exit codes: 0 success; 2 bad usage or bad input (one line naming the file, the
field and what was expected); 3 an optimization ended unconverged (results
written, ``converged: false``); 130 interrupted (Ctrl-C or SIGTERM; nothing written); 1 an internal
error. ``--debug`` shows tracebacks.
"""

from __future__ import annotations

import dataclasses
import json
import math
import sys
import traceback
import warnings
from pathlib import Path

import click

from gaitcli import __version__
from gaitcli.core.interrupts import terminate_as_interrupt
from gaitcli.core.registry import stage
from gaitcli.core.validate import check_parameter, expected_one_of, parameter_spec
from gaitcli.dynamics.stage import IdynConfig
from gaitcli.emg.stage import EmgConfig
from gaitcli.errors import GaitError, GaitWarning, InputError, NotConvergedError
from gaitcli.kinematics.subject import SEXES
from gaitcli.muscles.stage import MusclesConfig
from gaitcli.predict.stage import PredictConfig
from gaitcli.run.config import configure
from gaitcli.signal.stage import FilterConfig
from gaitcli.synth.gait import CONDITIONS
from gaitcli.synth.recording import DEFAULT_NOISE_MM, SYNTH_GAITS, SYNTH_MARKER_SETS


class Console:
    """Where the CLI prints: messages and warnings to stderr, the summary (``--json``) to stdout."""

    def __init__(self, quiet: bool = False, as_json: bool = False):
        self.quiet = quiet
        self.as_json = as_json
        self.summaries: dict[str, dict] = {}

    def info(self, message: str) -> None:
        if not self.quiet:
            click.echo(message, err=True)

    def outcomes(self, outcomes) -> None:
        """Say what each stage wrote; keep the summaries for ``--json``."""
        for outcome in outcomes:
            if outcome.status == "reused":
                continue
            self.summaries[outcome.stage] = outcome.summary
            if not self.quiet and not self.as_json:
                summary = outcome.summary or {}
                line = stage(outcome.stage).describe(summary)
                said = len(summary.get("warnings") or ())
                line += f"{', ' if line else ''}{said} warning{'s' * (said != 1)}" if said else ""
                click.echo(f"{outcome.stage}: {line + '; ' if line else ''}wrote {outcome.folder}", err=True)

    def progress(self):
        """The rich progress display (silent with --quiet)."""
        from gaitcli.progress import ProgressDisplay

        return ProgressDisplay(enabled=not self.quiet)

    def print_json(self, stage: str | None = None) -> None:
        """With ``--json``: one JSON document on stdout — the stage's summary, or all of them for ``run``."""
        data = self.summaries if stage is None else self.summaries.get(stage)
        if self.as_json and data:  # nothing when the stage failed before writing
            click.echo(json.dumps(data, indent=2, default=str))

    def run(self, trial, names, cfg, *, out, plots: bool, show: str | None = None, **options) -> None:
        """Run the stages through :func:`gaitcli.api.run_trial` with a progress display (``options``: its files,
        workers, scheduler); unconverged → exit 3."""
        from gaitcli.api import run_trial

        with self.progress() as progress:
            outputs = run_trial(trial, names, cfg, out=out, progress=progress, plots=plots, **options)
        self.finish(outputs, show)

    def finish(self, outputs, show: str | None = None) -> None:
        """Say what the stages of ``outputs`` (:class:`gaitcli.api.Outputs`) wrote, the summary with ``--json``;
        unconverged → :class:`NotConvergedError` (exit 3)."""
        self.outcomes(outputs.outcomes)
        self.print_json(show)
        outputs.check()


_SHOWN_WARNINGS: set[str] = set()


def _show_warning(message, category, filename, lineno, file=None, line=None):
    """Each warning once per run (a trial read by two stages would say the same twice)."""
    text = f"gait: warning: {message}" if issubclass(category, GaitWarning) else \
        f"gait: warning: {category.__name__}: {message}"
    if text not in _SHOWN_WARNINGS:
        _SHOWN_WARNINGS.add(text)
        click.echo(text, err=True)


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="gait")
@click.option("--quiet", "-q", is_flag=True, help="No progress bars or messages.")
@click.option("--json", "as_json", is_flag=True, help="Print the stage summary as JSON on stdout.")
@click.option("--debug", is_flag=True, expose_value=False,  # read by main(), which catches the errors
              help="Show tracebacks on errors.")
@click.pass_context
def gait(ctx, quiet, as_json):
    """Gait-lab processing: filter, inverse dynamics, muscles, predictive gait."""
    ctx.obj = Console(quiet=quiet, as_json=as_json)


class FiniteFloat(click.FloatRange):
    """click's FloatRange that refuses NaN and ±inf (which every range comparison lets through)."""

    name = "finite float"

    def convert(self, value, param, ctx):
        number = click.FLOAT.convert(value, param, ctx)
        if not math.isfinite(number):
            self.fail(f"got {value!r} (expected a finite number)", param, ctx)
        return super().convert(number, param, ctx)


class Choice(click.Choice):
    """click's Choice with the validators' message: "got …, expected one of …; did you mean …?"."""

    def convert(self, value, param, ctx):
        if value in self.choices:
            return value
        self.fail(expected_one_of(value, self.choices), param, ctx)


def _trial_argument(func):
    return click.argument("trial", required=False, type=click.Path(path_type=Path))(func)


def _trial_options(func):
    """TRIAL, -o/--out, --pipeline and --no-plots: the options every trial command takes."""
    func = click.option("--no-plots", "no_plots", is_flag=True, help="Skip the figures (plots/).")(func)
    func = click.option("--pipeline", "pipeline", type=click.Path(path_type=Path),
                        help="Pipeline YAML file, or a bundled pipeline by name (standard, muscles_eid); "
                             "default: standard.")(func)
    func = click.option("-o", "--out", "out", type=click.Path(path_type=Path),
                        help="Output root (default TRIAL/gait_out; ./gait_out for the bundled sample).")(func)
    return _trial_argument(func)


def _default_text(value) -> str:
    """A parameter's default as the help shows it: pairs as "A,B", exact small fractions as "4/3"."""
    from fractions import Fraction

    if isinstance(value, tuple):
        return ",".join(_default_text(v) for v in value)
    if isinstance(value, float) and value != int(value):
        fraction = Fraction(value).limit_denominator(100)
        if float(fraction) == value:
            return f"{fraction.numerator}/{fraction.denominator}"
    return f"{value:g}" if isinstance(value, float) else str(value)


def _config_option(config, name: str, *flags: str, flag: bool = False):
    """A click option for the stage parameter ``config.name``: type, choices, range and help from its declaration,
    and the value checked by the same validator as a pipeline file's (:func:`core.validate.check_parameter`),
    an error naming the flag."""
    f = next(f for f in dataclasses.fields(config) if f.name == name)
    spec = parameter_spec(f)

    def checked(ctx, param, value):
        return value if value is None else check_parameter(f, value, where=param.opts[0])

    # the default is the declaration's, shown unless the help says it; the option's own default stays None, so
    # that a flag not given leaves the pipeline file's value
    said = "(default" in spec["help"] or "; default" in spec["help"] or f.default is None or flag
    text = "on" if f.default is True else "off" if f.default is False else _default_text(f.default)
    options = {"default": None, "help": spec["help"] + ("" if said else f"  [default: {text}]"), "callback": checked}
    if flag:
        return click.option(*flags, name, is_flag=True, **options)
    if "/" in flags[0]:  # --name/--no-name
        return click.option(*flags, name, **options)
    if spec.get("parse") is not None and not isinstance(f.default, (int, float)):
        kind = click.STRING
        options["metavar"] = spec.get("metavar")
    elif spec["choices"] is not None:
        kind = Choice(spec["choices"])
    elif isinstance(f.default, int):
        kind = click.IntRange(min=spec["low"], max=spec["high"], min_open=spec["low_open"])
    else:
        kind = FiniteFloat(min=spec["low"], max=spec["high"], min_open=spec["low_open"])
    return click.option(*flags, name, type=kind, **options)


@gait.command("filter")
@_trial_options
@_config_option(FilterConfig, "cutoff_hz", "--cutoff")
@_config_option(FilterConfig, "events", "--events")
@click.pass_obj
def filter_command(console: Console, trial, out, pipeline, no_plots, cutoff_hz, events):
    """Fill gaps, zero-lag filter markers and plates, find gait events."""
    cfg = configure(pipeline, filter={"cutoff_hz": cutoff_hz, "force_cutoff_hz": cutoff_hz, "events": events})
    console.run(trial, ["filter"], cfg, out=out, plots=not no_plots, show="filter")


@gait.command("idyn")
@_trial_options
@_config_option(IdynConfig, "angles", "--angles")
@_config_option(IdynConfig, "moments", "--moments")
@_config_option(IdynConfig, "frames", "--frames")
@_config_option(IdynConfig, "pose", "--pose")
@_config_option(FilterConfig, "events", "--events")
@click.option("--export", "exports", type=Choice(("opensim", "c3d")), multiple=True,
              help="Also write the results for OpenSim (.trc, .mot, .sto, ExternalLoads) or as a C3D copy of the "
                   "trial with angles and moments, into OUT/export/ (repeatable).")
@click.pass_obj
def idyn_command(console: Console, trial, out, pipeline, no_plots, angles, moments, frames, pose, events, exports):
    """Anatomical joint angles, moments and powers; segment poses, 27 coordinates, 21 joint moments and the pelvis
    residuals."""
    cfg = configure(pipeline, idyn={"angles": angles, "moments": moments, "frames": frames, "pose": pose},
                    filter={"events": events})
    _run_exporting(console, trial, ["idyn"], cfg, out=out, plots=not no_plots, exports=exports, show="idyn")


def _run_exporting(console: Console, trial, names, cfg, *, out, plots: bool, exports, show: str | None,
                   **options) -> None:
    """:meth:`Console.run`, then the exports of idyn's results (``--export``), whose file names are checked before
    any stage runs: a name too long stops it with nothing written."""
    if exports:
        from gaitcli.io.atomic import check_output_file
        from gaitcli.run.exports import export_targets
        from gaitcli.run.pipeline import TrialRun

        run = TrialRun(trial, out, cfg)
        for path in export_targets(run.out_root, set(exports), trial_name=run.trial.name):
            check_output_file(path)
    console.run(trial, names, cfg, out=out, plots=plots, show=show, **options)
    if exports:
        from gaitcli.run.exports import export_trial

        written, notes = export_trial(run.out_root, set(exports), trial_c3d=run.trial.trial_path)
        for path in written:
            console.info(f"idyn: exported {path}")
        for note in notes:
            console.info(f"idyn: {note}")


@gait.command("emg")
@_trial_options
@_config_option(EmgConfig, "normalise", "--normalise")
@_config_option(EmgConfig, "envelope_cutoff_hz", "--envelope-cutoff")
@_config_option(FilterConfig, "events", "--events")
@click.pass_obj
def emg_command(console: Console, trial, out, pipeline, no_plots, normalise, envelope_cutoff_hz, events):
    """EMG: band-pass, rectify, linear envelope, on/off, mean ± SD over each muscle's strides (4.5.4); channels
    by subject.yaml's emg map, else by their labels."""
    cfg = configure(pipeline, emg={"normalise": normalise, "envelope_cutoff_hz": envelope_cutoff_hz},
                    filter={"events": events})
    console.run(trial, ["emg"], cfg, out=out, plots=not no_plots, show="emg")


@gait.command("muscles")
@_trial_options
@_config_option(MusclesConfig, "method", "--method")
@_config_option(MusclesConfig, "side", "--side")
@_config_option(MusclesConfig, "nodes", "--nodes")
@_config_option(MusclesConfig, "phase", "--phase")
@_config_option(MusclesConfig, "validate", "--validate", flag=True)
@_config_option(MusclesConfig, "objective", "--objective")
@click.pass_obj
def muscles_command(console: Console, trial, out, pipeline, no_plots, method, side, nodes, phase, validate,
                    objective):
    """Muscle forces, activations, excitations and metabolic cost of 8 leg muscles (SO | MSO | EID)."""
    cfg = configure(pipeline, muscles={"method": method, "side": side, "nodes": nodes, "phase": phase,
                                       "validate": validate, "objective": objective})
    console.run(trial, ["muscles"], cfg, out=out, plots=not no_plots, show="muscles")


@gait.command("predict")
@_trial_argument
@click.option("-o", "--out", "out", type=click.Path(path_type=Path),
              help="Output root (default TRIAL/gait_out; ./gait_out without a trial).")
@_config_option(PredictConfig, "speed_m_s", "--speed")
@_config_option(PredictConfig, "weights", "--weights")
@_config_option(PredictConfig, "nodes", "--nodes")
@_config_option(PredictConfig, "symmetric", "--symmetric/--no-symmetric")
@_config_option(PredictConfig, "max_iterations", "--max-iterations")
@_config_option(PredictConfig, "time_limit_s", "--time-limit")
@click.option("--reference", "reference", type=click.Path(path_type=Path, dir_okay=False),
              help="Reference CSV of `gait reference` (default: the trial's own, or the shipped reference of the "
                   "speed, Schwartz et al. 2008's groups).")
@click.option("--subject", "subject", type=click.Path(path_type=Path, dir_okay=False),
              help="subject.yaml of the person to predict for (default: the trial's, or the dissertation's "
                   "subject 1, 73.0 kg, 1.792 m).")
@click.option("--init", "init", type=click.Path(path_type=Path, dir_okay=False),
              help="Start from the solution in an earlier predict.h5 (same --nodes and --symmetric).")
@_config_option(PredictConfig, "start", "--start")
@_config_option(PredictConfig, "foot_mass_kg", "--foot-mass")
@_config_option(PredictConfig, "foot_mass_at", "--foot-mass-at")
@_config_option(PredictConfig, "prosthesis", "--prosthesis")
@_config_option(PredictConfig, "strength_scale", "--strength-scale")
@_config_option(PredictConfig, "monotone_range_deg", "--monotone-range")
@_config_option(PredictConfig, "stride_range_m", "--stride-range")
@_config_option(PredictConfig, "starts", "--starts")
@_config_option(PredictConfig, "seed", "--seed")
@click.option("--workers", "workers", type=click.IntRange(min=1, max=256), default=None,
              help="Worker processes for --starts and --study (default: one per core).")
@click.option("--scheduler", "scheduler", default=None, metavar="ADDRESS",
              help="Run --starts and --study as tasks on the Dask cluster at ADDRESS (tcp://host:port).")
@click.option("--study", "study", type=click.Path(path_type=Path, dir_okay=False),
              help="Run a study file's grid (speeds × weight sets × conditions) into OUT/study/, reusing the cases "
                   "already computed with the same inputs; see pipelines/study_*.yaml.")
@click.option("--force", "force", is_flag=True, help="With --study: solve every case again.")
@click.option("--no-plots", "no_plots", is_flag=True, help="Skip the figures (plots/).")
@click.pass_obj
def predict_command(console: Console, trial, out, reference, subject, init, workers, scheduler, study, force, no_plots,
                    **settings):
    """Predict a gait cycle by state dynamic optimization: motion, ground reactions, muscles, cost (ch. 5)."""
    if workers is not None and scheduler is not None:
        raise click.UsageError("--workers and --scheduler exclude each other (a scheduler has its own workers)")
    cfg = configure(None, predict=settings)
    files = {"reference": reference, "subject": subject}
    if study is not None:
        from gaitcli.report.study_plots import study_text
        from gaitcli.run.studies import run_study

        with console.progress() as progress:
            rows, folder = run_study(trial, study, cfg, out=out, files=files, workers_count=workers,
                                     scheduler=scheduler, force=force, progress=progress)
        console.info(study_text(rows))
        console.info(f"predict: wrote {folder} ({len(rows)} cases, study.csv)")
        bad = [r["case"] for r in rows if not r["converged"]]
        if bad:
            raise NotConvergedError(f"{len(bad)} of {len(rows)} study cases did not converge ({', '.join(bad)}); "
                                    f"marked in {folder / 'study.csv'}")
        return
    from gaitcli.api import predict_gait

    with console.progress() as progress:
        outputs = predict_gait(trial, cfg, reference=reference, subject=subject, init=init, out=out,
                               plots=not no_plots, progress=progress, workers=workers, scheduler=scheduler)
    console.finish(outputs, "predict")


@gait.command("synth")
@click.argument("out_dir", type=click.Path(path_type=Path))
@click.option("--condition", type=Choice(tuple(CONDITIONS)), default="normal", show_default=True,
              help="Experiment of 3.1.1 (added masses, locked joints).")
@click.option("--seed", type=int, default=0, show_default=True, help="Seed of the marker noise and artefact.")
@click.option("--noise-mm", type=FiniteFloat(min=0), default=DEFAULT_NOISE_MM, show_default=True,
              help="White marker noise: RMS of the 3-D position error, mm (each axis gets noise/√3).")
@click.option("--artefact-mm", type=FiniteFloat(min=0), default=10.0, show_default=True,
              help="Low-frequency skin artefact: peak 3-D displacement of a marker, mm.")
@click.option("--plate-noise-n", "plate_noise_N", type=FiniteFloat(min=0), default=1.0, show_default=True,
              help="White noise on the force-plate channels, N (N·mm/20 on moments).")
@click.option("--strides", type=click.IntRange(min=1, max=1000), default=3, show_default=True,
              help="Gait cycles in the trial.")
@click.option("--mass-kg", type=FiniteFloat(min=0, max=500, min_open=True), default=75.0, show_default=True,
              help="Body mass of the subject, kg.")
@click.option("--stature-m", type=FiniteFloat(min=0.5, max=2.5, min_open=True, max_open=True), default=1.78,
              show_default=True, help="Stature of the subject, m.")
@click.option("--sex", type=Choice(SEXES), default="male", show_default=True,
              help="Selects de Leva's segment tables.")
@click.option("--period-s", type=FiniteFloat(min=0.5, max=3.0), default=None,
              help="Gait cycle, s (default: the gait's: the prediction's scaled by √stature, or the condition's "
                   "for the normative curves).")
@click.option("--marker-set", type=Choice(tuple(SYNTH_MARKER_SETS)), default="dissertation", show_default=True,
              help="Label the markers as this preset does, with its clusters (subject.yaml names it).")
@click.option("--gait", "gait_kind", type=Choice(SYNTH_GAITS), default=None,
              help="predicted: the shipped muscle-driven prediction (1.30 m/s at 1.78 m, period 1.07 s scaled by "
                   "√stature; no locked joints); normative: Winter's curves re-timed over the "
                   "stance foot.  [default: predicted for normal walking, normative for the other conditions]")
@click.option("--session", is_flag=True,
              help="A session folder as Nexus leaves one: Static 01.c3d, Walking 01.c3d … (--walks), one "
                   "subject.yaml; walk k has the seed SEED + k - 1.")
@click.option("--walks", type=click.IntRange(min=1, max=99), default=3, show_default=True,
              help="With --session: the number of walks.")
@click.option("--emg", is_flag=True,
              help="Also an EMG channel per muscle and leg (mV), modulated by the truth's activations (EID on the "
                   "true motion; truth/activations.csv), mapped in subject.yaml.")
@click.option("--rate-hz", "marker_rate_hz", type=FiniteFloat(min=50, max=500), default=100.0, show_default=True,
              help="The markers' sampling rate, Hz (the plates sample 10 times as fast: 120 → 1200 Hz).")
@click.option("--medial-markers", is_flag=True,
              help="With --marker-set plug_in_gait: medial knee and ankle markers (RKNM, LKNM, RMED, LMED).")
@click.pass_obj
def synth_command(console: Console, out_dir, condition, seed, noise_mm, artefact_mm, plate_noise_N, strides,
                  mass_kg, stature_m, sex, period_s, marker_set, gait_kind, session, walks, emg, marker_rate_hz,
                  medial_markers):
    """Write a synthetic trial folder with known truth (trial.c3d, static.c3d, subject.yaml, truth/), or with
    --session a session folder of several walks."""
    from gaitcli.synth import write_trial
    from gaitcli.synth.folder import write_session

    gait_kind = gait_kind or ("predicted" if condition == "normal" else "normative")
    options = {"condition": condition, "noise_mm": noise_mm, "artefact_mm": artefact_mm,
               "plate_noise_N": plate_noise_N, "strides": strides, "mass_kg": mass_kg, "stature_m": stature_m,
               "sex": sex, "period_s": period_s, "marker_set": marker_set, "gait": gait_kind,
               "marker_rate_hz": marker_rate_hz, "medial_markers": medial_markers}
    if session:
        if emg:
            raise click.UsageError("--emg writes one trial (not with --session)")
        written = write_session(out_dir, walks=walks, seed=seed, **options)
        console.info(f"synth: wrote {out_dir} ({condition}, a static and {len(written)} walks of "
                     f"{written[0].design.speed_m_s:.2f} m/s)")
        return
    trial = write_trial(out_dir, seed=seed, emg=emg, **options)
    console.info(f"synth: wrote {out_dir} ({condition}, {trial.markers.n_frames} frames at {marker_rate_hz:g} Hz, "
                 f"{trial.design.speed_m_s:.2f} m/s, {len(trial.plates)} plates{', 16 EMG channels' if emg else ''})")


@gait.command("reference")
@click.argument("trials", nargs=-1, required=True, type=click.Path(path_type=Path))
@click.option("-o", "--out", "out", required=True, type=click.Path(path_type=Path, dir_okay=False),
              help="The reference table to write (CSV: cycle_pct, <variable>_mean, <variable>_sd).")
@click.option("--pipeline", "pipeline", type=click.Path(path_type=Path),
              help="Pipeline for the idyn stage where a trial's idyn output is missing or stale.")
@click.option("--band", "band", type=click.Path(path_type=Path, dir_okay=False),
              help="Also write a normal band for figures (mean, SD over the cycle of every angle and moment of "
                   "hip, knee and ankle, both legs pooled): gait report --reference takes it.")
@click.option("--sd-floor", "sd_floor", is_flag=True,
              help="Raise every SD to a floor (3°, 0.1 N·m/kg, 0.2 W/kg, 0.3 N/kg): for one subject's strides, "
                   "which vary far less than between subjects. Off: the SDs as measured (a prediction's Jdev "
                   "applies the floors itself).")
@click.pass_obj
def reference_command(console: Console, trials, out, pipeline, band, sd_floor):
    """A reference gait (mean and SD over the cycle) from the idyn outputs of one or more trials."""
    from gaitcli.dynamics.outputs import read_idyn_output
    from gaitcli.io.outputs import write_table
    from gaitcli.predict.reference import FORCES, reference_from_idyn
    from gaitcli.run.pipeline import fresh_output

    cfg = configure(pipeline)
    outputs = [fresh_output(trial, "idyn", cfg, plots=False) for trial in trials]
    names = [Path(t).resolve().name for t in trials]
    reference, right, left = reference_from_idyn([read_idyn_output(p) for p in outputs], sources=names,
                                                 sd_floor=sd_floor)
    write_table(out, reference.columns())
    forces = [reference.strides[v] for v in FORCES]
    if band is not None:
        from gaitcli.signal.bands import band_from_gait_cycles

        normal = band_from_gait_cycles([p.parent / "gait_cycle.csv" for p in outputs], source=", ".join(names),
                                       sd_floor=sd_floor)
        write_table(band, normal.columns())
        console.info(f"reference: wrote {band} (band of {len(normal.mean)} variables, "
                     f"{min(normal.strides.values())}–{max(normal.strides.values())} strides each)")
    console.info(f"reference: wrote {out} ({right} right and {left} left strides of {len(trials)} "
                 f"trial(s); forces from {min(forces)}–{max(forces)} "
                 "strides per variable)")


@gait.command("run")
@_trial_options
@_config_option(FilterConfig, "cutoff_hz", "--cutoff")
@_config_option(IdynConfig, "frames", "--frames")
@_config_option(IdynConfig, "pose", "--pose")
@click.option("--export", "exports", type=Choice(("opensim", "c3d")), multiple=True,
              help="Also export idyn's results (as gait idyn --export; one trial, not a session).")
@click.option("--workers", type=click.IntRange(min=1), default=None,
              help="A session's walks (or a prediction's starts) at once on this many local worker processes "
                   "(default: the number of CPUs; 1: one after the other in this process).")
@click.option("--scheduler", help="Address of an existing Dask scheduler (tcp://host:port) instead of local workers.")
@click.pass_obj
def run_command(console: Console, trial, out, pipeline, no_plots, cutoff_hz, frames, pose, exports, workers,
                scheduler):
    """Run every stage of the pipeline on a trial, in order; on a session folder, on every walk (in parallel)
    and then the session's strides pooled into gait_out/session/. The options override the pipeline's."""
    from gaitcli.run.session import session_folder

    if workers is not None and scheduler is not None:
        raise click.UsageError("--workers and --scheduler exclude each other (a scheduler has its own workers)")
    cfg = configure(pipeline, filter={"cutoff_hz": cutoff_hz, "force_cutoff_hz": cutoff_hz},
                    idyn={"frames": frames, "pose": pose})
    if trial is not None and session_folder(trial) is not None:
        for flag, given in (("-o/--out", out), ("--export", exports)):
            if given:
                raise click.UsageError(f"{flag} is for one trial: a session's outputs go to SESSION/gait_out/")
        _run_session(console, trial, cfg, plots=not no_plots, workers=workers, scheduler=scheduler)
        return
    if exports and "idyn" not in cfg.stages:
        raise click.UsageError("--export exports idyn's results: the pipeline has no idyn stage")
    from gaitcli.run.pipeline import trial_stages

    _run_exporting(console, trial, trial_stages(trial, cfg), cfg, out=out, plots=not no_plots, exports=exports,
                   show=None, workers=workers, scheduler=scheduler)


def _name_vsk_subjects(console: Console, lab_dir: Path, command: str) -> None:
    """One line per folder below ``lab_dir`` whose subject is its .vsk alone: which file, and that sex is assumed."""
    from gaitcli.run.batch import vsk_subjects

    for folder, vsk in vsk_subjects(lab_dir):
        where = "" if folder == Path(lab_dir) else f"{folder.relative_to(lab_dir).as_posix()}: "
        console.info(f"{command}: {where}subject from {vsk.name} (no subject.yaml; male assumed, `sex:` in a "
                     "subject.yaml says otherwise)")


def _run_session(console: Console, folder: Path, cfg, *, plots: bool, workers: int | None,
                 scheduler: str | None) -> None:
    """``gait run SESSION``: the walks as a batch with its progress display, then one line per failed walk and
    the session's; a failed or unconverged walk → its exit code (the highest)."""
    import os

    from gaitcli.progress import BatchProgress
    from gaitcli.run.batch import stages_of
    from gaitcli.run.session import run_session

    _name_vsk_subjects(console, folder, "session")
    with BatchProgress(stages_of(cfg), enabled=not console.quiet) as progress:
        def started(total, to_run, dashboard):
            progress.start(total)
            if to_run:
                console.info(f"session: {to_run} of {total} walks to run")

        done = run_session(folder, cfg, workers=workers or os.cpu_count() or 1, scheduler=scheduler, plots=plots,
                           on_rows=progress, on_start=started)
    failed = {r.trial: r for r in done.batch.rows if r.status in ("failed", "unconverged")}
    for walk, row in failed.items():
        console.info(f"session: {walk}: {row.status}: {row.reason}")
    if done.pooled is not None:
        info = done.pooled.summary()
        used = {side: info["strides"][side]["used"] + info["strides"][side]["kinematics only"] for side in "rl"}
        console.info(f"session: wrote {done.output} ({info['walks']} walk{'s' * (info['walks'] != 1)}; {used['r']} "
                     f"right and {used['l']} left strides, {info['per_stride']['speed_m_s_mean']:.2f} m/s)")
    click.echo(f"{done.batch.line()} ({done.batch.elapsed_s:.1f} s)")
    if failed:  # the first failure as the command's error: bad input 2, unconverged 3, an internal error 1
        walk, row = min(failed.items(), key=lambda item: {2: 0, 1: 1, 3: 2}.get(item[1].exit_code, 1))
        message = f"{len(failed)} of {len(done.walks)} walks {'did not converge' if row.exit_code == 3 else 'failed'}"
        if row.exit_code == 2:  # the reason names the walk's file
            raise InputError(folder, None, f"{message}: {row.reason}")
        error = NotConvergedError if row.exit_code == 3 else GaitError
        raise error(f"{message} (listed above; {folder / 'gait_out' / 'batch_summary.csv'})")


@gait.command("batch")
@click.argument("lab_dir", type=click.Path(path_type=Path))
@click.option("--pipeline", "pipeline", type=click.Path(path_type=Path),
              help="Pipeline YAML file, or a bundled pipeline by name; default: standard.")
@click.option("--workers", type=click.IntRange(min=1), default=None,
              help="Worker processes of the local Dask cluster (default: the number of CPUs).")
@click.option("--scheduler", help="Address of an existing Dask scheduler (tcp://host:port) instead of a local cluster.")
@click.option("--force", is_flag=True, help="Run every trial again, also those whose outputs are current.")
@click.option("--no-plots", "no_plots", is_flag=True, help="Skip the figures (plots/).")
@click.option("--baseline", "baseline", type=click.Path(path_type=Path),
              help="Then compare the trials' outputs with this stored tree (as gait compare; exit 1 when they differ).")
@click.option("--tolerances", "tolerances", type=click.Path(path_type=Path, dir_okay=False),
              help="With --baseline: a tolerance YAML as for gait compare.")
@click.pass_context
def batch_command(ctx, lab_dir, pipeline, workers, scheduler, force, no_plots, baseline, tolerances):
    """Run the pipeline on every trial folder below LAB_DIR in parallel (Dask, else a process pool); batch_summary.csv
    in LAB_DIR."""
    import os

    from gaitcli.progress import BatchProgress
    from gaitcli.run.batch import BATCH_SUMMARY, run_batch, stages_of
    from gaitcli.run.compare import DEFAULT_TOLERANCES, compare_trees, outputs_only, read_tolerances

    console: Console = ctx.obj
    if workers is not None and scheduler is not None:
        raise click.UsageError("--workers and --scheduler exclude each other (a scheduler has its own workers)")
    cfg = configure(pipeline)
    rules = DEFAULT_TOLERANCES if tolerances is None else read_tolerances(tolerances)  # bad input before any run
    if baseline is not None and not baseline.is_dir():
        raise InputError(baseline, "--baseline", "not found (expected a folder of stored outputs, as gait batch "
                                                 "left them below a lab folder)")

    _name_vsk_subjects(console, lab_dir, "batch")
    with BatchProgress(stages_of(cfg), enabled=not console.quiet) as progress:
        def started(total, to_run, dashboard):
            progress.start(total)
            if to_run:
                console.info(f"batch: {to_run} of {total} trials to run"
                             + (f"; Dask dashboard {dashboard}" if dashboard else ""))

        result = run_batch(lab_dir, cfg, workers=workers or os.cpu_count() or 1, scheduler=scheduler, force=force,
                           plots=not no_plots, on_rows=progress, on_start=started)
    for trial, status in result.trial_status().items():
        if status == "failed":
            reason = next(r.reason for r in result.rows if r.trial == trial and r.status == "failed")
            console.info(f"batch: {trial}: failed: {reason}")
    console.info(f"batch: wrote {Path(lab_dir) / BATCH_SUMMARY}")
    click.echo(f"{result.line()} ({result.elapsed_s:.1f} s)")
    if baseline is not None:
        comparison = compare_trees(baseline, lab_dir, tolerances=rules, select=outputs_only)
        if comparison.findings and not console.quiet:
            _print_findings(comparison)
        click.echo(f"baseline {baseline}: {comparison.summary_line()}")
        if not comparison.ok:
            ctx.exit(1)


@gait.command("compare")
@click.argument("a", type=click.Path(path_type=Path))
@click.argument("b", type=click.Path(path_type=Path))
@click.option("--tolerances", "tolerances", type=click.Path(path_type=Path, dir_okay=False),
              help="YAML file of tolerances per unit family (families:), per column or summary key pattern "
                   "(columns:) and patterns not compared (ignore:); default: the table in README.md.")
@click.pass_context
def compare_command(ctx, a, b, tolerances):
    """Compare two output trees (e.g. a stored baseline and today's run): every summary.json value and CSV column.

    Exit 0 when everything agrees within tolerance, 1 when something differs (the table says what, where and by
    how much), 2 for bad input."""
    from gaitcli.run.compare import DEFAULT_TOLERANCES, compare_trees, read_tolerances

    console: Console = ctx.obj
    result = compare_trees(a, b, tolerances=DEFAULT_TOLERANCES if tolerances is None else read_tolerances(tolerances))
    if console.as_json:
        click.echo(json.dumps(result.to_json(), indent=2))
    elif not console.quiet and result.findings:
        _print_findings(result)
    console.info(f"compare: {result.summary_line()}")
    if not result.ok:
        ctx.exit(1)


def _print_findings(result) -> None:
    """The findings as a table on stderr: rich's on a terminal, aligned plain text in logs (never cut)."""
    from gaitcli.run.compare import TABLE_HEADER, finding_rows

    rows = finding_rows(result)
    if sys.stderr.isatty():
        from rich import box
        from rich.console import Console as RichConsole
        from rich.table import Table

        table = Table(title=f"A {result.a}  ·  B {result.b}", title_justify="left", box=box.SIMPLE_HEAD)
        for name in TABLE_HEADER:
            table.add_column(name, overflow="fold")  # names are folded onto more lines, never cut
        for row in rows:
            table.add_row(*row)
        RichConsole(stderr=True).print(table)
        return
    widths = [max(len(r[k]) for r in [TABLE_HEADER, *rows]) for k in range(len(TABLE_HEADER))]
    for row in [TABLE_HEADER, tuple("-" * w for w in widths), *rows]:
        click.echo("  ".join(cell.ljust(w) for cell, w in zip(row, widths)).rstrip(), err=True)


@gait.command("report")
@click.argument("out_dirs", metavar="OUT_DIR...", nargs=-1, required=True, type=click.Path(path_type=Path))
@click.option("--reference", "reference", type=click.Path(path_type=Path, dir_okay=False),
              help="Normal band for the cycle figures: a band CSV (gait reference --band) or a gait reference "
                   "table (default: the package's band, Schwartz et al. 2008's free speed).")
@click.option("--export", "exports", type=Choice(("opensim", "c3d")), multiple=True,
              help="Also export each trial's idyn results for OpenSim or as a C3D copy (as gait idyn --export).")
@click.option("--compare", is_flag=True,
              help="Compare the conditions OUT_DIR... (trials, walks, sessions or bundled sample trials' names) "
                   "with the first: Table 3.1 each, mean ± SD overlaid, SPM where they differ (runs filter and "
                   "idyn where needed).")
@click.option("-o", "--out", "out", type=click.Path(path_type=Path, file_okay=False),
              help="With --compare: where the comparison goes (default ./gait_compare; OUT/compare/report.html).")
@click.pass_obj
def report_command(console: Console, out_dirs, reference, exports, compare, out):
    """A self-contained HTML page per trial, session, prediction or study in OUT_DIR (and an index for a batch);
    with --compare, one page comparing the conditions."""
    from gaitcli.report.html import find_report, write_report
    from gaitcli.signal.bands import default_band, read_band

    band = default_band() if reference is None else read_band(reference)
    if compare:
        if len(out_dirs) < 2 or exports:
            raise click.UsageError("--compare takes two or more conditions and no --export")
        _compare(console, out_dirs, band, Path("gait_compare") if out is None else out)
        return
    if len(out_dirs) != 1 or out is not None:
        raise click.UsageError("one OUT_DIR (several with --compare; -o/--out is for --compare)")
    out_dir = out_dirs[0]
    pages = write_report(out_dir, band)
    for page in pages:
        console.info(f"report: wrote {page.path}")
    if exports:
        from gaitcli.run.exports import export_trial
        from gaitcli.run.trial import open_trial

        kind, root = find_report(Path(out_dir).resolve())
        roots = [root] if kind == "trial" else [p.path.parent for p in pages if p.status not in ("index", "study")]
        for output in roots:
            if not (output / "idyn" / "idyn.h5").is_file():
                continue
            trial_file = open_trial(output.parent).trial_path if output.name == "gait_out" else None
            formats = set(exports) if trial_file is not None else set(exports) - {"c3d"}
            written, notes = export_trial(output, formats, trial_c3d=trial_file)
            for path in written:
                console.info(f"report: exported {path}")
            for note in notes:
                console.info(f"report: {note}")


def _compare(console: Console, refs, band, out: Path) -> None:
    """``gait report A B … --compare``: every condition read (its filter and idyn run where needed), compared
    with the first, written to OUT/compare/ with its page."""
    import os

    from gaitcli.report.html import write_compare_report
    from gaitcli.run.conditions import compare_conditions, condition_sources, read_condition, write_comparison

    cfg = configure(None)
    sources = condition_sources(refs, out.resolve())
    conditions = []
    for source in sources:
        console.info(f"compare: reading {source.name}")
        conditions.append(read_condition(source, cfg, workers=os.cpu_count() or 1))
    comparison = compare_conditions(conditions)
    folder = write_comparison(out.resolve(), comparison, page=lambda tmp: write_compare_report(tmp, band))
    console.info(f"compare: {len(conditions)} conditions, {len(comparison.spans)} spans where one differs from "
                 f"{sources[0].name}; wrote {folder / 'report.html'}")


#: the options of the gait group itself, taken anywhere on the command line (``gait idyn TRIAL --json``)
GLOBAL_FLAGS = ("--quiet", "-q", "--json", "--debug")


def global_options_first(argv: list[str]) -> list[str]:
    """``argv`` with the group's flags (:data:`GLOBAL_FLAGS`) given after the subcommand moved before it, so that
    they work in either place; nothing after ``--`` is moved."""
    end = argv.index("--") if "--" in argv else len(argv)
    flags = [a for a in argv[:end] if a in GLOBAL_FLAGS]
    return flags + [a for a in argv[:end] if a not in GLOBAL_FLAGS] + argv[end:]


def main(argv: list[str] | None = None) -> int:
    """Console-script entry point; maps errors to exit codes."""
    argv = global_options_first(list(sys.argv[1:] if argv is None else argv))
    debug = "--debug" in argv
    previous = warnings.showwarning
    warnings.showwarning = _show_warning
    try:
        _SHOWN_WARNINGS.clear()
        with terminate_as_interrupt(), warnings.catch_warnings():
            if not debug:  # numpy's and matplotlib's own warnings are for developers
                warnings.simplefilter("ignore")
            warnings.simplefilter("always", GaitWarning)
            warnings.showwarning = _show_warning
            code = gait.main(args=argv, prog_name="gait", standalone_mode=False)
        return code if isinstance(code, int) else 0  # ctx.exit(N) (compare: 1 when the trees differ)
    except click.exceptions.Exit as exc:
        return exc.exit_code
    except click.UsageError as exc:  # one line, as for bad input
        command = f"gait {exc.ctx.command_path.split(' ', 1)[1]}" if exc.ctx and " " in exc.ctx.command_path \
            else "gait"
        click.echo(f"gait: error: {exc.format_message()} (see '{command} --help')", err=True)
        return exc.exit_code
    except click.ClickException as exc:
        exc.show()
        return exc.exit_code
    except (click.exceptions.Abort, KeyboardInterrupt):  # Ctrl-C or SIGTERM: nothing was written
        click.echo("gait: interrupted", err=True)
        return 130
    except GaitError as exc:
        if debug:
            traceback.print_exc()
        click.echo(f"gait: error: {exc}", err=True)
        return exc.exit_code
    except Exception as exc:  # an internal error: say so, show the traceback only with --debug
        if debug:
            traceback.print_exc()
        click.echo(f"gait: internal error: {type(exc).__name__}: {exc} (run with --debug for the traceback)", err=True)
        return 1
    finally:
        warnings.showwarning = previous

