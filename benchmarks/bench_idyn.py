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
kinematics, events, gait features and the sagittal export), and the pipeline's ``Run.idyn`` in
this process (static calibration, the stage, CSV/HDF5/JSON writers and plots; the filter stage's
output is made once beforehand and is fresh, so it is read, not recomputed), each with its peak
traced memory. ``--cli`` adds the wall time of ``gait -q idyn`` in a new process (imports, filter
stage and plots included). Threads are limited to one and the process to one core. Prints; asserts
nothing.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
import tracemalloc
import warnings
from pathlib import Path

for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(var, "1")
os.environ.setdefault("MPLBACKEND", "Agg")

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

import numpy as np  # noqa: E402

from gaitcli.config import IdynConfig  # noqa: E402
from gaitcli.dynamics.derivatives import coordinate_derivatives  # noqa: E402
from gaitcli.dynamics.inverse import inverse_dynamics  # noqa: E402
from gaitcli.dynamics.stage import external_wrenches, inverse_dynamics_stage  # noqa: E402
from gaitcli.errors import GaitWarning  # noqa: E402
from gaitcli.kinematics.calibration import calibrate  # noqa: E402
from gaitcli.kinematics.coordinates import poses_to_coordinates, track_segments  # noqa: E402
from gaitcli.core.recording import Markers  # noqa: E402
from gaitcli.resources import sample_trial  # noqa: E402
from gaitcli.synth import MARKER_RATE_HZ, simulate_trial  # noqa: E402
from timing import QuietConsole, median_s  # benchmarks/timing.py

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
    """A synthetic walk of exactly ``frames`` marker frames, its calibration and per-foot loads."""
    period_s = 1.2  # the normal condition's gait period
    strides = int(np.ceil(frames / (period_s * MARKER_RATE_HZ))) + 1
    trial = simulate_trial(condition="normal", seed=0, strides=strides)
    m = trial.markers
    markers = Markers(m.labels, m.positions_m[:frames], m.rate_hz, m.first_frame)
    feet = {side: {key: np.asarray(value)[:frames] for key, value in load.items()} for side, load in trial.feet.items()}
    calibration = calibrate(trial.static, mass_kg=MASS_KG, stature_m=STATURE_M, sex="male")
    return markers, feet, calibration


def kernels(markers, feet, calibration, repeat: int) -> None:
    n = markers.n_frames
    wrenches = external_wrenches(feet, n)
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
    from gaitcli import pipeline as pl

    folder = tmp / "normal"
    shutil.copytree(sample_trial("normal"), folder, ignore=shutil.ignore_patterns("gait_out", "truth"))
    cfg = pl.configure(None)
    run = pl.Run(folder, tmp / "out", cfg, QuietConsole())
    run.filter()  # written once: Run.idyn then reads the fresh filter.h5
    filtered = run.filtered()
    mass_kg = run.trial.subject.mass_kg
    calibration = run.calibration(filtered, mass_kg, run.static_markers())
    frames = filtered.markers.n_frames

    def stage():
        return inverse_dynamics_stage(filtered, calibration, IdynConfig(), mass_kg=mass_kg, mass_source="bench")

    stage_s, _ = median_s(stage, repeat)
    stage_mb = _peak_mb(stage)
    run_s, _ = median_s(run.idyn, repeat)
    run_mb = _peak_mb(run.idyn)
    print(f"\nthe idyn stage on the normal sample trial ({frames} frames), median of {repeat} runs, one core")
    print(f"{'':40} {'ms':>9} {'frames/s':>10} {'peak MB':>8}")
    print("-" * 70)
    print(f"{'inverse_dynamics_stage':40} {1e3 * stage_s:9.1f} {frames / stage_s:10.0f} {stage_mb:8.1f}")
    print(f"{'Run.idyn (calibration, writers, plots)':40} {1e3 * run_s:9.1f} {frames / run_s:10.0f} {run_mb:8.1f}")
    if cli:
        cli_folder = tmp / "cli_normal"
        shutil.copytree(sample_trial("normal"), cli_folder, ignore=shutil.ignore_patterns("gait_out", "truth"))

        def command():
            shutil.rmtree(cli_folder / "gait_out", ignore_errors=True)
            subprocess.run([sys.executable, "-m", "gaitcli.cli", "-q", "idyn", str(cli_folder)], check=True,
                           capture_output=True)

        runs = max(1, min(repeat, 3))
        print(f"`gait -q idyn` in a new process, filter stage included (median of {runs}): "
              f"{median_s(command, runs)[0]:.2f} s")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3, help="runs per timing; the median is reported")
    parser.add_argument("--frames", type=int, default=10_000, help="marker frames of the long trial")
    parser.add_argument("--cli", action="store_true", help="also time the whole `gait idyn` command")
    args = parser.parse_args(argv)
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", GaitWarning)
        started = time.perf_counter()
        markers, feet, calibration = long_trial(args.frames)
        print(f"(synthetic trial of {args.frames} frames made in {time.perf_counter() - started:.1f} s)")
        kernels(markers, feet, calibration, args.repeat)
        with tempfile.TemporaryDirectory(prefix="bench_idyn_") as tmp:
            whole_stage(Path(tmp), args.repeat, args.cli)
    return 0


if __name__ == "__main__":
    sys.exit(main())
