"""Writes the emg stage's files: envelopes.csv, cycle.csv, onoff.csv and emg.h5, and gives its summary."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from gaitcli.emg.processing import bursts
from gaitcli.emg.stage import EmgResult
from gaitcli.io.h5 import record_datasets, write_h5
from gaitcli.io.outputs import write_table
from gaitcli.signal.cycles import CYCLE_PCT


def emg_columns(result: EmgResult) -> dict[str, np.ndarray]:
    """``envelopes.csv``: ``time_s``, then per muscle its normalised envelope and on/off (1/0) at the analog
    rate."""
    columns = {"time_s": result.time_s}
    for k, muscle in enumerate(result.muscles):
        columns[f"{muscle}_envelope"] = result.envelope[:, k]
        columns[f"{muscle}_on"] = result.on[:, k].astype(int)
    return columns


def emg_cycle_columns(result: EmgResult) -> dict[str, np.ndarray]:
    """``cycle.csv``: ``cycle_pct``, then per muscle the mean and SD of its envelope over its foot's strides and
    the fraction of them in which it is on."""
    columns = {"cycle_pct": CYCLE_PCT}
    for k, muscle in enumerate(result.muscles):
        columns[f"{muscle}_mean"] = result.cycle_mean[:, k]
        columns[f"{muscle}_sd"] = result.cycle_sd[:, k]
        columns[f"{muscle}_on_fraction"] = result.cycle_on[:, k]
    return columns


def emg_bursts(result: EmgResult) -> dict[str, list]:
    """``onoff.csv``: one row per burst of a muscle within a stride of its foot (a burst across a heel strike
    counts in both strides): times in s and % of that stride."""
    rows = {key: [] for key in ("muscle", "channel", "stride", "stride_start_s", "on_s", "off_s", "on_pct",
                                "off_pct")}
    t = result.time_s
    for k, (label, muscle) in enumerate(zip(result.channels, result.muscles)):
        for number, j in enumerate(np.flatnonzero(result.own_strides(k)), start=1):
            start, end = result.stride_start_s[j], result.stride_end_s[j]
            inside = (t >= start) & (t < end)
            first = int(np.argmax(inside))
            for on_s, off_s in bursts(result.on[inside, k], result.rate_hz, start_s=t[first]):
                for key, value in (("muscle", muscle), ("channel", label), ("stride", number),
                                   ("stride_start_s", start), ("on_s", on_s), ("off_s", off_s),
                                   ("on_pct", 100 * (on_s - start) / (end - start)),
                                   ("off_pct", 100 * (min(off_s, end) - start) / (end - start))):
                    rows[key].append(value)
    return rows


def emg_summary(result: EmgResult) -> dict:
    """The emg stage's ``summary.json``: channels and muscles, strides, normalisation, clipping, and per muscle
    the % of the cycle where its mean envelope peaks and the share of the cycle it is on."""
    per_muscle = {}
    for k, muscle in enumerate(result.muscles):
        mean = result.cycle_mean[:, k]
        finite = np.isfinite(mean)
        per_muscle[muscle] = {
            "channel": result.channels[k], "strides": int(result.own_strides(k).sum()),
            "reference_V": float(result.reference_V[k]),
            "peak_pct": float(CYCLE_PCT[np.nanargmax(mean)]) if finite.any() else None,
            "on_pct": float(100 * np.nanmean(result.cycle_on[:, k])) if finite.any() else None,
        }
    return {
        "channels": list(result.channels),
        "analog_rate_hz": result.rate_hz,
        "strides": int(result.stride_side.size),
        "strides_right": int(np.count_nonzero(result.stride_side == "r")),
        "strides_left": int(np.count_nonzero(result.stride_side == "l")),
        "normalisation": result.normalisation,
        "clipped": list(result.clipped),
        "muscles": per_muscle,
    }


def write_emg_outputs(folder: Path, result: EmgResult, attrs: dict) -> dict:
    """``envelopes.csv``, ``cycle.csv``, ``onoff.csv`` and ``emg.h5`` (``result/``: the :class:`EmgResult`,
    read back by :func:`gaitcli.io.h5.read_result`) into ``folder``; return the summary."""
    folder = Path(folder)
    write_table(folder / "envelopes.csv", emg_columns(result))
    write_table(folder / "cycle.csv", emg_cycle_columns(result))
    write_table(folder / "onoff.csv", emg_bursts(result))
    data = record_datasets("result", result)
    for name, meaning in (("envelope", "linear envelope / reference_V, samples x channels"),
                          ("stride_envelope", "strides x 101 (0-100 % of the cycle) x channels, / reference_V"),
                          ("cycle_mean", "101 x channels, / reference_V")):
        data[f"result/{name}"].attrs["meaning"] = meaning
    write_h5(folder / "emg.h5", data, attrs)
    return emg_summary(result)
