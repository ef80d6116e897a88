"""Wiring between the CLI and the stages: inputs → stage functions → writers.

Every input is read and validated before anything is written. A later stage
reads an earlier stage's HDF5 output when it is up to date (same input hashes
and same stage configuration) and runs the earlier stage itself otherwise.
"""

from __future__ import annotations

import dataclasses
import json
import time
import warnings
from pathlib import Path

import h5py
import numpy as np

from gaitcli.config import PipelineConfig, load_pipeline, to_yaml, with_overrides
from gaitcli.errors import GaitWarning, InputError
from gaitcli.io.outputs import provenance, stage_folder
from gaitcli.core.recording import Recording
from gaitcli.resources import sample_trial
from gaitcli.trial import TrialFolder, open_trial, sha256


#: bump when a stage's output files change, so that older outputs count as stale
OUTPUT_FORMAT = 1


def configure(pipeline: Path | None, **sections) -> PipelineConfig:
    """Load the pipeline file (or defaults) and apply the CLI's overrides per section."""
    cfg = load_pipeline(pipeline)
    for section, options in sections.items():
        cfg = with_overrides(cfg, section, **options)
    return cfg


def load_recording(trial: TrialFolder) -> Recording:
    """Read the dynamic trial (C3D or CSV) in model axes, with the subject's marker map applied."""
    from gaitcli.io.c3d import read_c3d
    from gaitcli.io.tables import read_csv_trial
    from gaitcli.kinematics.markerset import apply_marker_map

    if trial.trial_path.suffix.lower() == ".c3d":
        recording = read_c3d(trial.trial_path)
    else:
        recording = read_csv_trial(trial.trial_path, trial.forces_path)
    if trial.subject.marker_map:
        recording.markers = apply_marker_map(recording.markers, trial.subject.marker_map,
                                             source=trial.subject_path)
    return recording


def check_cutoffs(cfg, recording: Recording, path: Path) -> None:
    """Cut-offs must lie below the Nyquist frequency of the signals they filter."""
    rate = recording.markers.rate_hz
    if cfg.cutoff_hz >= rate / 2:
        raise InputError(path, "filter.cutoff_hz", f"got {cfg.cutoff_hz:g} Hz (expected below the Nyquist frequency "
                                                   f"{rate / 2:g} Hz of its {rate:g} Hz markers)")
    if recording.plates and cfg.force_cutoff_hz >= rate / 2:  # plate signals end up at the marker frames
        raise InputError(path, "filter.force_cutoff_hz", f"got {cfg.force_cutoff_hz:g} Hz (expected below the "
                                                         f"Nyquist frequency {rate / 2:g} Hz of the marker frames)")


class Run:
    """One invocation on one trial: where inputs and outputs are, and the resolved configuration."""

    def __init__(self, trial: Path | None, out: Path | None, cfg: PipelineConfig, console):
        bundled = trial is None
        self.trial = open_trial(sample_trial() if bundled else trial)
        if out is None:
            out = Path.cwd() / "gait_out" if bundled else self.trial.folder / "gait_out"
        self.out_root = Path(out)
        self.cfg = cfg
        self.console = console
        self.inputs = {p.name: sha256(p) for p in self.trial.input_files()}

    # -- provenance and freshness -------------------------------------------------------------
    def stage_key(self, stage: str) -> str:
        """What a stage's output depends on: input hashes and the configuration of it and earlier stages."""
        sections = {"filter": ["filter"], "idyn": ["filter", "idyn"], "muscles": ["filter", "idyn", "muscles"]}
        cfg = {s: dataclasses.asdict(getattr(self.cfg, s)) for s in sections[stage]}
        return json.dumps({"inputs": self.inputs, "config": cfg, "format": OUTPUT_FORMAT}, sort_keys=True)

    def attrs(self, stage: str) -> dict:
        attrs = provenance(to_yaml(self.cfg), self.inputs)
        attrs["stage_key"] = self.stage_key(stage)
        attrs["trial"] = str(self.trial.folder)
        return attrs

    def fresh(self, stage: str, h5_name: str) -> Path | None:
        """The stage's HDF5 output if it exists and was made from the same inputs and configuration."""
        path = self.out_root / stage / h5_name
        if not path.is_file():
            return None
        try:
            with h5py.File(path, "r") as h5:
                key = h5.attrs.get("stage_key")
        except OSError:
            return None
        return path if key == self.stage_key(stage) else None

    def reuse(self, stage: str, h5_name: str, read, run):
        """``read(h5)`` of a fresh earlier output, else ``run()`` (the stage again, which writes it anew)."""
        path = self.fresh(stage, h5_name)
        if path is not None:
            try:
                return read(path)
            except (KeyError, OSError, ValueError):  # an older or damaged output: make it anew
                pass
        return run()

    # -- stages -----------------------------------------------------------------------------
    def filter(self):
        """Run the filter stage and write its outputs; returns the in-memory result."""
        from gaitcli.report.filter_outputs import write_filter_outputs
        from gaitcli.signal.stage import filter_trial

        started = time.perf_counter()
        recording = load_recording(self.trial)
        check_cutoffs(self.cfg.filter, recording, self.trial.trial_path)
        result = filter_trial(recording, self.cfg.filter)
        target = self.out_root / "filter"
        with stage_folder(target) as tmp:
            summary = write_filter_outputs(tmp, result, recording, self.attrs("filter"),
                                           elapsed_s=time.perf_counter() - started)
        self.console.summary("filter", summary, target)
        return result

    def filtered(self):
        """The filter stage's result: read from a fresh ``filter.h5``, else by running the filter stage."""
        from gaitcli.report.filter_outputs import filtered_trial, read_filtered_trial

        return self.reuse("filter", "filter.h5", read_filtered_trial, lambda: filtered_trial(self.filter()))

    def static_markers(self):
        """The standing trial's markers in the dynamic trial's axes, mapped; None when there is no static.c3d."""
        from gaitcli.io.axes import apply_rotation
        from gaitcli.io.c3d import read_c3d
        from gaitcli.kinematics.markerset import apply_marker_map

        subject = self.trial.subject
        if self.trial.static_path is None:
            if subject.static_frames is None:
                raise InputError(self.trial.subject_path, "static_frames",
                                 "no static.c3d in the trial folder: name the standing frames of the trial as "
                                 "[first, last] (file frame numbers)")
            return None
        dynamic = load_recording(self.trial)
        with warnings.catch_warnings():  # a standing trial has no plates to speak of
            warnings.filterwarnings("ignore", message=".*force plate", category=GaitWarning)
            static = read_c3d(self.trial.static_path, to_model_axes=False)
        markers = apply_rotation(static, dynamic.lab_to_model).markers
        if subject.marker_map:
            markers = apply_marker_map(markers, subject.marker_map, source=self.trial.subject_path)
        return markers

    def calibration(self, filtered, mass_kg: float, static=None):
        """Static calibration from static.c3d's markers or from named frames of the filtered trial."""
        from gaitcli.kinematics.calibration import calibrate

        subject = self.trial.subject
        common = dict(mass_kg=mass_kg, stature_m=subject.stature_m, sex=subject.sex,
                      thigh_length_m=subject.thigh_length_m, shank_length_m=subject.shank_length_m,
                      disturbances=subject.disturbances)
        if static is not None:
            return calibrate(static, source=self.trial.static_path, **common)
        if subject.static_frames is None:
            raise InputError(self.trial.subject_path, "static_frames",
                             "no static.c3d in the trial folder: name the standing frames of the trial as "
                             "[first, last] (file frame numbers)")
        first, last = subject.static_frames
        m = filtered.markers
        frames = np.arange(first, last + 1) - m.first_frame
        if frames[0] < 0 or frames[-1] >= m.n_frames:
            raise InputError(self.trial.subject_path, "static_frames",
                             f"got [{first}, {last}] (expected frames within {m.first_frame}–"
                             f"{m.first_frame + m.n_frames - 1})")
        return calibrate(m, frames=frames, source=self.trial.trial_path, **common)

    def idyn(self):
        """Run the idyn stage (and the filter stage first when its output is missing or stale)."""
        from gaitcli.dynamics.stage import check_mass, estimate_mass_kg, inverse_dynamics_stage
        from gaitcli.report.idyn_outputs import write_idyn_outputs

        started = time.perf_counter()
        subject = self.trial.subject
        static = self.static_markers()
        if static is not None:  # a static trial the model cannot use fails before anything is written
            self.calibration(None, subject.mass_kg or 70.0, static)
        filtered = self.filtered()
        if subject.mass_kg is not None:
            mass, source = subject.mass_kg, "subject.yaml"
        else:
            mass = check_mass(estimate_mass_kg(filtered, gravity_m_s2=self.cfg.idyn.gravity_m_s2),
                              self.trial.subject_path)
            source = "estimated from the force plates (2·∫Fz dt / (g·stride period) per recorded stance)"
        calibration = self.calibration(filtered, mass, static)
        result = inverse_dynamics_stage(filtered, calibration, self.cfg.idyn, mass_kg=mass, mass_source=source)
        target = self.out_root / "idyn"
        with stage_folder(target) as tmp:
            summary = write_idyn_outputs(tmp, result, self.attrs("idyn"), elapsed_s=time.perf_counter() - started)
        self.console.summary("idyn", summary, target)
        return result

    def idyn_outputs(self):
        """What the muscle stage needs: from a fresh ``idyn.h5``, else by running the idyn stage."""
        from gaitcli.report.idyn_outputs import muscle_inputs, read_muscle_inputs

        return self.reuse("idyn", "idyn.h5", read_muscle_inputs, lambda: muscle_inputs(self.idyn()))

    def muscles(self):
        """Run SO, MSO or EID on one leg; unconverged solutions are written, then reported (exit 3)."""
        from gaitcli.errors import NotConvergedError
        from gaitcli.muscles.interval import prepare_leg
        from gaitcli.muscles.stage import MuscleOptions, run_muscles
        from gaitcli.report.muscles_outputs import write_muscle_outputs

        started = time.perf_counter()
        cfg = self.cfg.muscles
        inputs = self.idyn_outputs()
        if inputs.source is None:  # computed in this run rather than read back from idyn.h5
            inputs = dataclasses.replace(inputs, source=self.out_root / "idyn" / "sagittal.csv")
        leg = prepare_leg(inputs, cfg.side, cfg.phase, stature_m=self.trial.subject.stature_m,
                          sex=self.trial.subject.sex)
        options = MuscleOptions(objective=cfg.objective)
        with self.console.progress(f"muscles ({cfg.method.upper()})") as bar:
            result = run_muscles(leg.motion, leg.limb, method=cfg.method,
                                 nodes=cfg.nodes if cfg.method == "eid" else None, interval=leg.interval_s,
                                 periodic=leg.periodic, options=options, validate=cfg.validate)
            bar.update(completed=1, total=1)
        target = self.out_root / "muscles" / cfg.method
        with stage_folder(target) as tmp:
            summary = write_muscle_outputs(tmp, result, self.attrs("muscles"), phase=cfg.phase,
                                           interval=leg.interval_s, events=inputs.events,
                                           elapsed_s=time.perf_counter() - started)
        self.console.summary("muscles", summary, target)
        if not result.converged:
            why = f": {result.diagnosis}" if result.diagnosis else ""
            raise NotConvergedError(f"{cfg.method.upper()} did not converge ({result.status}){why}; results written "
                                    f"to {target} with converged: false")
        return result

    def all(self):
        for stage in self.cfg.stages:
            getattr(self, stage)()
