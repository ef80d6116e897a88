"""EMG-stage timings: ``run_emg`` on long synthetic records and on the two real trials with raw EMG.

Run from the repository root: ``python benchmarks/bench_emg.py [--repeat N]``. On one core, prints the median
wall time of ``run_emg`` (volts, band-pass, rectification, envelope, on/off, strides, mean ± SD; no files) for
16 channels at 1 and 2 kHz over 10 s and 60 s of walking (a stride every 1.1 s), as seconds and as the ratio of
the record's duration to the processing time (how many times faster than real time), and the same for
../shared/data's BTS.c3d (8 channels) and Gait.c3d (16) with their events as `gait filter` detects them (where
that folder is present). The whole ``gait emg`` command (reading, filter, figures) is not timed here.
Asserts nothing.
"""

from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np
from timing import median_s, one_core

from gaitcli.core.events import Events
from gaitcli.core.recording import Analogs
from gaitcli.emg.processing import bandpass
from gaitcli.emg.stage import EmgConfig, run_emg

SHARED = Path(__file__).resolve().parents[2] / "shared" / "data"
REAL = {"BTS.c3d": (SHARED / "c3d" / "BTS.c3d", "mass_kg: 70\nstature_m: 1.75\nsex: male\nmarker_map: "
                    "{r heel: CAr, l heel: CAl, r met: MT2r, l met: MT2l}\n"),
        "Gait.c3d": (SHARED / "emg" / "Gait.c3d",
                     "mass_kg: 70\nstature_m: 1.75\nsex: male\nmarker_set: plug_in_gait\n")}


def synthetic(duration_s: float, rate_hz: float, channels: int = 16) -> tuple[Analogs, Events]:
    """``channels`` of band-limited noise modulated by bursts once a stride (1.1 s), and the strides' events."""
    rng = np.random.default_rng(0)
    t = np.arange(0, duration_s, 1 / rate_hz)
    carrier = bandpass(rng.normal(size=(t.size, channels)), rate_hz=rate_hz)
    phase = (t[:, None] / 1.1 + np.arange(channels) / channels) % 1.0
    values = 1e-3 * (0.05 + np.exp(-((phase - 0.5) / 0.1) ** 2)) * carrier
    labels = tuple(f"{side} {word}" for side in "RL" for word in ("TA", "SOL", "GAS", "VAS", "RF", "HAM", "GMAX",
                                                                    "ADD"))[:channels]
    strikes = np.arange(0.2, duration_s - 0.1, 1.1)
    events = Events.concatenate([Events.from_times(strikes, rate_hz=100, side="r", kind="heel_strike",
                                                   source="kinematics"),
                                 Events.from_times(strikes[:-1] + 0.55, rate_hz=100, side="l", kind="heel_strike",
                                                   source="kinematics")])
    return Analogs(labels=labels, units=("V",) * channels, rate_hz=rate_hz, values=values), events


def real(name: str):
    """(analogs, events) of a real trial: its channels, its events as the filter stage finds them."""
    from gaitcli.run.pipeline import load_recording
    from gaitcli.run.trial import open_trial
    from gaitcli.signal.stage import FilterConfig, filter_trial

    path, subject = REAL[name]
    with tempfile.TemporaryDirectory() as tmp, warnings.catch_warnings():
        warnings.simplefilter("ignore")
        shutil.copy(path, Path(tmp) / "trial.c3d")
        (Path(tmp) / "subject.yaml").write_text(subject)
        recording = load_recording(open_trial(tmp))
        events = filter_trial(recording, FilterConfig()).events
    return recording.analogs, events


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args(argv)
    one_core()
    cases = [(f"synthetic {d:g} s, {r / 1000:g} kHz", *synthetic(d, r)) for d in (10.0, 60.0) for r in (1e3, 2e3)]
    cases += [(name, *real(name)) for name, (path, _) in REAL.items() if path.is_file()]
    print(f"{'record':<26} {'channels':>8} {'samples':>9} {'run_emg (s)':>12} {'× real time':>12} {'strides':>8}")
    for name, analogs, events in cases:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            seconds, result = median_s(lambda a=analogs, e=events: run_emg(a, e, None, EmgConfig()), args.repeat)
        duration = analogs.n_samples / analogs.rate_hz
        print(f"{name:<26} {len(result.channels):>8} {analogs.n_samples:>9} {seconds:>12.3f} "
              f"{duration / seconds:>12.0f} {result.stride_side.size:>8}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
