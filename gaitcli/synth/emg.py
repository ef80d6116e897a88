"""Synthetic surface EMG with known truth (``gait synth --emg``): each leg's 8 muscles' activations, and raw EMG
channels they modulate.

The truth's activations: EID (Diss. 4.3) on the walk's own sagittal motion and ground reactions (no marker
noise, loads known everywhere), one cycle per leg, repeated over the trial as the walk repeats its cycle. Each
channel (mV, at the plates' analog rate) is

    raw(t) = gain · (a(t) · c(t) + BASELINE · n(t)) + offset

with c unit-variance Gaussian noise band-limited to 20–450 Hz (the surface EMG's band), n white unit noise (the
amplifier's floor), a per-channel ``gain`` (log-uniform in :data:`GAIN_MV`) and DC ``offset`` (uniform in
±:data:`OFFSET_MV`): the linear envelope of ``raw`` is gain · E|c| · a(t) low-passed, so normalised it recovers
the activation.
"""

from __future__ import annotations

import numpy as np

from gaitcli.core.container import FootLoad, Trial
from gaitcli.core.events import SIDES, Events
from gaitcli.core.recording import Analogs
from gaitcli.dynamics.sagittal import sagittal_export
from gaitcli.emg.processing import BAND_HZ, bandpass
from gaitcli.kinematics.forward import forward_kinematics
from gaitcli.muscles.parameters import MUSCLE_NAMES
from gaitcli.muscles.stage import MusclesConfig, run_muscles_stage

#: the channel label's muscle word (a lab's abbreviation; subject.yaml's emg map names the muscle)
LABELS = {"iliopsoas": "IL", "rectus_femoris": "RF", "glutei": "GMAX", "hamstrings": "HAM", "vasti": "VAS",
          "gastrocnemius": "GAS", "tibialis_anterior": "TA", "soleus": "SOL"}
#: the amplifier's floor, as a fraction of a fully active muscle's signal
BASELINE = 0.02
#: range of the channels' gains (mV for a fully active muscle's noise of unit variance) and DC offsets, mV
GAIN_MV = (0.3, 1.5)
OFFSET_MV = 0.2


def channel_label(muscle: str, side: str) -> str:
    """``R TA``: the side's letter and the muscle's abbreviation."""
    return f"{side.upper()} {LABELS[muscle]}"


def emg_map() -> dict[str, str]:
    """subject.yaml's ``emg:`` block of the synthetic channels: label → sided muscle."""
    return {channel_label(m, s): f"{m}_{s}" for s in SIDES for m in MUSCLE_NAMES}


def truth_activations(trial, *, stature_m: float, sex: str, mass_kg: float) -> dict[str, np.ndarray]:
    """``{sided muscle: activation at each marker frame}`` of a :class:`~gaitcli.synth.recording.SyntheticTrial`
    (module docstring): EID on each leg's first cycle of the true motion, repeated with the walk's period."""
    params = trial.calibration.body
    n = trial.q.shape[0]
    feet = {s: FootLoad(trial.feet[s]["force_N"], trial.feet[s]["cop_m"], trial.feet[s]["free_moment_Nm"],
                        np.ones(n, bool)) for s in SIDES}
    events = Events.concatenate([Events.from_times([e[0]], rate_hz=trial.markers.rate_hz, side=e[2], kind=e[3],
                                                   source="kinematics") for e in trial.events])
    truth = Trial(markers=trial.markers, feet=feet, events=events)
    states = forward_kinematics(trial.q, params, trial.qd)
    export = sagittal_export(truth, states.joint_centre_m, trial.q, params, body_mass_kg=mass_kg)
    time_s, period_s = trial.markers.time_s, trial.design.period_s
    out = {}
    for side in SIDES:
        result = run_muscles_stage(export, MusclesConfig(method="eid", side=side), stature_m=stature_m, sex=sex)
        start = result.time_s[0]
        phase_s = (time_s - start) % period_s  # the walk repeats its cycle exactly
        for k, muscle in enumerate(result.muscle_names):
            out[f"{muscle}_{side}"] = np.interp(phase_s, result.time_s - start, result.activations[:, k],
                                                period=period_s)
    return out


def emg_channels(activations: dict[str, np.ndarray], marker_time_s: np.ndarray, rate_hz: float, n_samples: int,
                 rng: np.random.Generator) -> Analogs:
    """Raw EMG (mV) at ``rate_hz`` of every muscle in ``activations`` (module docstring), ``n_samples`` from the
    first marker frame."""
    t = np.arange(n_samples) / rate_hz
    labels, columns = [], []
    carrier = bandpass(rng.normal(size=(n_samples, len(activations))), rate_hz=rate_hz, band_hz=BAND_HZ)
    carrier /= carrier.std(axis=0)
    gains = np.exp(rng.uniform(*np.log(GAIN_MV), size=len(activations)))
    offsets = rng.uniform(-OFFSET_MV, OFFSET_MV, size=len(activations))
    for k, (muscle, activation) in enumerate(activations.items()):
        a = np.interp(t, marker_time_s, activation)
        columns.append(gains[k] * (a * carrier[:, k] + BASELINE * rng.normal(size=n_samples)) + offsets[k])
        labels.append(channel_label(muscle[:-2], muscle[-1]))
    return Analogs(labels=tuple(labels), units=("mV",) * len(labels), rate_hz=rate_hz,
                   values=np.column_stack(columns))
