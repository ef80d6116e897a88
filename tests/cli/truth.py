"""Comparisons of the filter stage's tables with a synthetic trial's truth/ folder.

Shared by the CLI tests (which read the files ``gait filter`` wrote) and the stage
tests (which build the same tables in memory). Tables are pandas DataFrames in the
layout of ``events.csv`` (time_s, frame, side, event, source) and ``grf.csv``
(``plateK_…``, ``plateK_foot``, ``foot_r_…``, ``foot_l_…``); the truth tables are
``truth/events.csv`` (time_s, frame, side, event, on_plate), ``truth/grf.csv``
(per foot, every contact, unfiltered) and ``truth/plates.csv`` (plate, foot).

The reference for the filtered ground reactions is the truth filtered here by an
independent implementation of the same filter (3.1.4): a 2nd-order Butterworth
designed at ``f_d = (fs/π) atan(tan(π fc/fs) / C)``, ``C = (√2 − 1)^(1/4) = 0.802``,
run forward and backward with scipy's ``filtfilt``.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.signal import butter, filtfilt

AXES = ("x", "y", "z")

# Tolerances. Figures measured on the five bundled sample trials (frames at 100 Hz, detected − truth, from the
# event times); tests/signal/test_stage.py tabulates them per trial.
PLATE_EVENT_FRAMES = 2  # plate heel strike / toe off: measured +0.7…+0.8 / −0.4…−0.5 frame (knee_orthosis
#   −0.03…+1.3); the bound is 2 frames
KINEMATIC_HEEL_STRIKE_FRAMES = (-2.0, 2.0)  # Zeni heel strike after removing its bias against the plate events
#   (stage.calibrate_kinematic_events); the raw Zeni bias was −2.6 … −4.0 frames (the heel's forward excursion from
#   the pelvis peaks 25–40 ms before the foot lands)
KINEMATIC_TOE_OFF_FRAMES = 2.0  # Zeni toe off after the same bias correction (raw: −1.7 … +1.3 frames)
GRF_FRACTION_OF_PEAK = 0.03  # per-foot force vs the truth filtered alike (truth.lowpass_reference), max over the
#   frames the plate is given to its foot, as a fraction of the stance's peak Fz. Derivation: the 6 Hz filter is
#   linear, so filtering the truth the same way removes its effect (the unfiltered truth differs by 3–4 % of peak
#   at the loading edges, 19–20 % on knee_orthosis whose load rises fastest). What remains is the plate's 1 N
#   noise (≈0.1 N after 6 Hz, 0.01 % of peak) and the filter run on the plate at 1 kHz versus on the truth at
#   100 Hz, i.e. the loading edge sampled 10× more finely: measured 0.04–0.07 % of peak (0.24 % and 1.7 % on
#   knee_orthosis). 3 % is "a few %" with room for a steeper synthetic edge, and still fails a wrong foot, a
#   missing stance or a mis-scaled plate (each ≥ 100 % of peak at some frame).
COP_M = 0.005  # COP vs the filtered truth where its Fz > 10 % of peak: measured 0.1–0.4 mm (1.4 mm knee_orthosis)
FREE_MOMENT_NM = 2.0  # free moment there: measured 0.04–0.06 N·m (0.7 knee_orthosis), of a 12–35 N·m range


def read_truth(trial: Path) -> dict[str, pd.DataFrame]:
    """``events``, ``grf`` and ``plates`` tables of a synthetic trial's ``truth/`` folder."""
    truth = Path(trial) / "truth"
    return {name: pd.read_csv(truth / f"{name}.csv", keep_default_na=False, na_values=["NaN"])
            for name in ("events", "grf", "plates")}


def read_table(path: Path) -> pd.DataFrame:
    """A CSV written by gaitcli (``NaN`` for missing numbers; empty text cells stay empty strings)."""
    return pd.read_csv(path, keep_default_na=False, na_values=["NaN"])


def event_errors(events: pd.DataFrame, truth_events: pd.DataFrame, rate_hz: float, source: str) -> pd.DataFrame:
    """For every detected event of ``source``: the nearest truth event of the same side and kind.

    Columns: side, event, time_s, err_frames (detected − truth, in marker frames from the
    times, so sub-frame), frame_diff (difference of the 1-based frame columns), on_plate.
    """
    rows = []
    for _, e in events[events["source"] == source].iterrows():
        t = truth_events[(truth_events["side"] == e["side"]) & (truth_events["event"] == e["event"])]
        j = int(np.argmin(np.abs(t["time_s"].to_numpy() - e["time_s"])))
        rows.append({"side": e["side"], "event": e["event"], "time_s": e["time_s"],
                     "err_frames": (e["time_s"] - t["time_s"].iloc[j]) * rate_hz,
                     "frame_diff": int(e["frame"]) - int(t["frame"].iloc[j]), "on_plate": int(t["on_plate"].iloc[j])})
    return pd.DataFrame(rows, columns=["side", "event", "time_s", "err_frames", "frame_diff", "on_plate"])


def plate_feet(grf: pd.DataFrame, n_plates: int) -> dict[str, list[str]]:
    """The feet each plate was assigned to anywhere in the trial (``plateK_foot``, empty = nobody)."""
    return {f"plate{k}": sorted(set(grf[f"plate{k}_foot"].astype(str)) - {""}) for k in range(1, n_plates + 1)}


def lowpass_reference(x: np.ndarray, rate_hz: float, cutoff_hz: float) -> np.ndarray:
    """Zero-lag 2nd-order Butterworth with net cut-off ``cutoff_hz`` along axis 0 (independent of gaitcli)."""
    c = (math.sqrt(2.0) - 1.0) ** 0.25  # two passes of a 2nd-order filter: −3 dB moves to 0.802 f_d
    design_hz = rate_hz / math.pi * math.atan(math.tan(math.pi * cutoff_hz / rate_hz) / c)
    b, a = butter(2, design_hz, fs=rate_hz)
    return filtfilt(b, a, x, axis=0)


def stance_reference(truth_grf: pd.DataFrame, side: str, frames: np.ndarray, rate_hz: float,
                     cutoff_hz: float = 6.0) -> dict[str, np.ndarray]:
    """The truth load of the one stance of ``side`` that contains ``frames``, alone, filtered at ``cutoff_hz``.

    A plate feels only the stance on it, so the other contacts of that foot are zeroed
    before filtering. Returns ``force_N`` (n, 3), ``cop_m`` (n, 2) and ``free_moment_Nm``
    (n,) formed from the filtered force and moment like the plate's (COP NaN where the
    filtered vertical force is not positive), ``raw_force_N`` (the unfiltered stance)
    and ``stance`` (bool mask of its loaded frames).
    """
    force = truth_grf[[f"foot_{side}_force_{a}_N" for a in AXES]].to_numpy()
    cop = np.nan_to_num(truth_grf[[f"foot_{side}_cop_{a}_m" for a in AXES]].to_numpy())
    free = truth_grf[f"foot_{side}_free_moment_Nm"].to_numpy()
    lo, hi = _stance(force[:, 2] > 0, frames)
    stance = np.zeros(force.shape[0], dtype=bool)
    stance[lo:hi + 1] = True
    force = np.where(stance[:, None], force, 0.0)
    moment = np.cross(cop, force)  # about the origin; the truth COP is on the floor z = 0
    moment[:, 2] += np.where(stance, free, 0.0)
    f = lowpass_reference(force, rate_hz, cutoff_hz)
    m = lowpass_reference(moment, rate_hz, cutoff_hz)
    with np.errstate(divide="ignore", invalid="ignore"):
        cop_xy = np.where(f[:, 2:3] > 0, np.stack([-m[:, 1] / f[:, 2], m[:, 0] / f[:, 2]], axis=1), np.nan)
    free_f = m[:, 2] - (cop_xy[:, 0] * f[:, 1] - cop_xy[:, 1] * f[:, 0])
    return {"force_N": f, "cop_m": cop_xy, "free_moment_Nm": free_f, "raw_force_N": force, "stance": stance}


def grf_errors(grf: pd.DataFrame, truth: dict[str, pd.DataFrame], rate_hz: float, cutoff_hz: float = 6.0) -> list[dict]:
    """Per plate of ``truth/plates.csv``: the per-foot ground reaction of grf.csv against the filtered truth.

    Over the frames where grf.csv gives that plate to its foot: the largest force error
    per axis as a fraction of the stance's peak vertical force, the largest error of
    the unfiltered comparison, and — where the reference vertical force exceeds 10 %
    of peak — the largest COP (m) and free-moment (N·m) errors.
    """
    out = []
    for plate, side in zip(truth["plates"]["plate"], truth["plates"]["foot"]):
        owned = (grf[f"{plate}_foot"].astype(str) == side).to_numpy()
        ref = stance_reference(truth["grf"], side, owned, rate_hz, cutoff_hz)
        est = grf[[f"foot_{side}_force_{a}_N" for a in AXES]].to_numpy()
        peak = ref["raw_force_N"][:, 2].max()
        firm = owned & (ref["force_N"][:, 2] > 0.1 * peak)
        est_cop = grf[[f"foot_{side}_cop_x_m", f"foot_{side}_cop_y_m"]].to_numpy()
        est_free = grf[f"foot_{side}_free_moment_Nm"].to_numpy()
        out.append({
            "plate": plate, "side": side, "frames": int(owned.sum()), "peak_N": float(peak),
            "force_rel": np.abs(est - ref["force_N"])[owned].max(axis=0) / peak,
            "unfiltered_rel": np.abs(est[:, 2] - ref["raw_force_N"][:, 2])[owned].max() / peak,
            "cop_m": np.abs(est_cop - ref["cop_m"])[firm].max(axis=0),
            "free_moment_Nm": float(np.abs(est_free - ref["free_moment_Nm"])[firm].max()),
        })
    return out


def truth_load_edges(truth_grf: pd.DataFrame, side: str, frames: np.ndarray) -> tuple[int, int]:
    """1-based first and last frame of the truth stance of ``side`` that contains ``frames`` (load > 0)."""
    lo, hi = _stance(truth_grf[f"foot_{side}_force_z_N"].to_numpy() > 0, frames)
    return lo + 1, hi + 1


def _stance(loaded: np.ndarray, frames: np.ndarray) -> tuple[int, int]:
    """0-based first and last index of the run of ``loaded`` through the middle of the ``frames`` mask."""
    middle = int(np.flatnonzero(frames)[frames.sum() // 2])
    runs = np.flatnonzero(np.diff(np.concatenate([[0], loaded.astype(np.int8), [0]])))
    starts, stops = runs[::2], runs[1::2]
    k = int(np.flatnonzero((starts <= middle) & (middle < stops))[0])
    return int(starts[k]), int(stops[k]) - 1
