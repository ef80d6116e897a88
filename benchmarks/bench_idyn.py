"""Idyn-stage throughput: pose + inverse dynamics on a 10 000-frame walk, and the whole stage on a sample trial.

Run from the repository root: ``python benchmarks/bench_idyn.py [--repeat N] [--frames N] [--cli]``.

Part 1 — kernels on a long trial: ``gaitcli.synth.simulate_trial`` (normal gait, 2 mm noise,
10 mm artefact) with enough strides for ``--frames`` marker frames at 100 Hz (default 10 000,
about 84 strides), cut to exactly that many. Timed one after the other, median of ``--repeat``
runs each: ``track_segments`` (SVD fit of 8 clusters per frame), ``poses_to_coordinates`` (27
coordinates), ``coordinate_derivatives`` (quintic splines) and ``inverse_dynamics`` (global-Jacobian
equations of motion with both feet's ground reactions). Frames per second per part and in total;
peak traced memory (``tracemalloc``, numpy's buffers included) of one pass through all four,
measured in a separate run because tracing slows allocation.

Part 2 — the whole ``gait idyn`` stage on the bundled normal sample trial (560 frames): the stage
function alone (``inverse_dynamics_stage`` on the filtered trial: the four kernels plus forward
kinematics, events, gait features and the sagittal export), and ``pipeline.run_stage(trial, "idyn")``
in this process, with and without figures (input hashes, filter.h5 read back, static calibration,
the stage, CSV/HDF5/JSON writers, and the figures drawn from idyn.h5; the filter stage's output is
made once beforehand and is fresh, so it is read, not recomputed), each with its peak traced memory.
``--cli`` adds the wall time of ``gait -q idyn`` in a new process (imports, filter stage and plots
included). Threads are limited to one and the process to one core. Prints; asserts nothing.
"""

from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
import time
import tracemalloc
import warnings
from pathlib import Path

import numpy as np

# timing first, before numpy: one thread, Agg backend (its import sets the environment)
from timing import copy_sample, median_s, one_core, sample_outputs, time_gait

from gaitcli.core.container import FootLoad, Trial
from gaitcli.core.events import Events
from gaitcli.core.recording import Markers
from gaitcli.core.registry import stage
from gaitcli.dynamics.derivatives import coordinate_derivatives
from gaitcli.dynamics.inverse import inverse_dynamics
from gaitcli.dynamics.stage import (
    IdynConfig,
    body_mass,
    external_wrenches,
    inverse_dynamics_stage,
    reference_frames,
    static_calibration,
)
from gaitcli.errors import GaitWarning
from gaitcli.kinematics.calibration import calibrate
from gaitcli.kinematics.coordinates import poses_to_coordinates, track_segments
from gaitcli.run.config import configure
from gaitcli.run.pipeline import load_static, run_stage, run_stages
from gaitcli.run.trial import open_trial
from gaitcli.synth import MARKER_RATE_HZ, simulate_trial

MASS_KG, STATURE_M = 75.0, 1.78


def _peak_mb(func) -> float:
    """Peak memory traced by ``tracemalloc`` while ``func`` runs, MB."""
    tracemalloc.start()
    try:
        func()
        return tracemalloc.get_traced_memory()[1] / 1e6
    finally:
        tracemalloc.stop()


def long_trial(frames: int):
    """A synthetic walk of exactly ``frames`` marker frames (as a :class:`Trial`, both feet's loads known) and
    its calibration."""
    period_s = 1.2  # the normal condition's gait period
    strides = int(np.ceil(frames / (period_s * MARKER_RATE_HZ))) + 1
    trial = simulate_trial(condition="normal", seed=0, strides=strides)
    m = trial.markers
    markers = Markers(m.labels, m.positions_m[:frames], m.rate_hz, m.first_frame)
    feet = {side: FootLoad(force_N=np.asarray(load["force_N"])[:frames], cop_m=np.asarray(load["cop_m"])[:frames],
                           free_moment_Nm=np.asarray(load["free_moment_Nm"])[:frames],
                           known=np.ones(frames, dtype=bool))
            for side, load in trial.feet.items()}
    calibration = calibrate(trial.static, mass_kg=MASS_KG, stature_m=STATURE_M, sex="male")
    return Trial(markers=markers, feet=feet, events=Events()), calibration


def kernels(trial: Trial, calibration, repeat: int) -> None:
    markers = trial.markers
    n = markers.n_frames
    wrenches = external_wrenches(trial)
    parts = {}
    parts["track_segments"], poses = median_s(lambda: track_segments(markers, calibration), repeat)
    parts["poses_to_coordinates"], q = median_s(lambda: poses_to_coordinates(poses), repeat)
    parts["coordinate_derivatives"], (qd, qdd) = median_s(lambda: coordinate_derivatives(q, markers.rate_hz),
                                                           repeat)
    parts["inverse_dynamics"], _ = median_s(lambda: inverse_dynamics(q, qd, qdd, calibration.body, wrenches),
                                             repeat)

    def once():
        p = track_segments(markers, calibration)
        y = poses_to_coordinates(p)
        yd, ydd = coordinate_derivatives(y, markers.rate_hz)
        inverse_dynamics(y, yd, ydd, calibration.body, wrenches)

    peak = _peak_mb(once)
    total = sum(parts.values())
    print(f"pose + inverse dynamics, {n} frames at {markers.rate_hz:g} Hz "
          f"({len(markers.labels)} markers), median of {repeat} runs, one core")
    print(f"{'part':24} {'ms':>9} {'frames/s':>11}")
    print("-" * 46)
    for name, seconds in parts.items():
        print(f"{name:24} {1e3 * seconds:9.1f} {n / seconds:11.0f}")
    print(f"{'total':24} {1e3 * total:9.1f} {n / total:11.0f}")
    print(f"peak traced memory of one pass: {peak:.1f} MB ({1e3 * peak / n:.1f} kB per frame)")


def whole_stage(tmp: Path, repeat: int, cli: bool) -> None:
    folder, h5 = sample_outputs(tmp, ("filter",))  # written once: run_stage("idyn") then reads the fresh filter.h5
    filtered = stage("filter").read(h5["filter"])
    trial = open_trial(folder)
    cfg = IdynConfig()
    static = load_static(trial, filtered.lab_to_model)
    mass_kg, mass_source, _ = body_mass(filtered, trial.subject, cfg, static=static, source=trial.subject_path)
    markers, static_frames, _ = reference_frames(filtered, static, trial.subject, subject_path=trial.subject_path)
    calibration = static_calibration(markers, static_frames, trial.subject, mass_kg, source=trial.static_path)
    frames = filtered.markers.n_frames
    pipeline_cfg = configure(None)

    def stage_only():
        return inverse_dynamics_stage(filtered, calibration, cfg, mass_kg=mass_kg, mass_source=mass_source)

    rows = {"inverse_dynamics_stage": stage_only,
            "run_stage idyn (read, calib., writers)": lambda: run_stage(folder, "idyn", pipeline_cfg, plots=False),
            "run_stage idyn, with figures": lambda: run_stage(folder, "idyn", pipeline_cfg, plots=True)}
    filter_status = next(o.status for o in run_stages(folder, ["idyn"], pipeline_cfg, plots=False)
                         if o.stage == "filter")
    print(f"\nthe idyn stage on the normal sample trial ({frames} frames), median of {repeat} runs, one core "
          f"(filter output {filter_status} by run_stage)")
    print(f"{'':40} {'ms':>9} {'frames/s':>10} {'peak MB':>8}")
    print("-" * 70)
    for label, func in rows.items():
        seconds, _ = median_s(func, repeat)
        print(f"{label:40} {1e3 * seconds:9.1f} {frames / seconds:10.0f} {_peak_mb(func):8.1f}")
    if cli:
        cli_folder = copy_sample("normal", tmp / "cli_normal")
        runs = max(1, min(repeat, 3))
        seconds = time_gait("-q", "idyn", cli_folder, repeat=runs,
                            before=lambda: shutil.rmtree(cli_folder / "gait_out", ignore_errors=True))
        print(f"`gait -q idyn` in a new process, filter stage included (median of {runs}): {seconds:.2f} s")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3, help="runs per timing; the median is reported")
    parser.add_argument("--frames", type=int, default=10_000, help="marker frames of the long trial")
    parser.add_argument("--cli", action="store_true", help="also time the whole `gait idyn` command")
    args = parser.parse_args(argv)
    one_core()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", GaitWarning)
        started = time.perf_counter()
        trial, calibration = long_trial(args.frames)
        print(f"(synthetic trial of {args.frames} frames made in {time.perf_counter() - started:.1f} s)")
        kernels(trial, calibration, args.repeat)
        with tempfile.TemporaryDirectory(prefix="bench_idyn_") as tmp:
            whole_stage(Path(tmp), args.repeat, args.cli)
    return 0


if __name__ == "__main__":
    sys.exit(main())
