"""Writes the filter stage's files: markers_filtered.csv, grf.csv, events.csv and filter.h5, and gives its summary."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from gaitcli.core.events import Events
from gaitcli.core.recording import Markers
from gaitcli.io.h5 import Dataset, record_datasets, write_h5
from gaitcli.io.outputs import write_table
from gaitcli.signal.forceplates import PlateLoad
from gaitcli.signal.stage import FilterResult

AXES = ("x", "y", "z")


def marker_columns(markers: Markers) -> dict[str, np.ndarray]:
    """``time_s``, ``frame``, then ``<label>_x_m, _y_m, _z_m`` per marker."""
    columns = {"time_s": markers.time_s, "frame": np.arange(markers.n_frames) + markers.first_frame}
    for i, label in enumerate(markers.labels):
        for k, axis in enumerate(AXES):
            columns[f"{label}_{axis}_m"] = markers.positions_m[:, i, k]
    return columns


def load_columns(prefix: str, load: PlateLoad) -> dict[str, np.ndarray]:
    """Force (N), COP (m) and vertical free moment (N·m) of one plate or foot."""
    columns = {f"{prefix}_force_{a}_N": load.force_N[:, k] for k, a in enumerate(AXES)}
    columns.update({f"{prefix}_cop_{a}_m": load.cop_m[:, k] for k, a in enumerate(AXES)})
    columns[f"{prefix}_free_moment_Nm"] = load.free_moment_Nm
    return columns


def grf_columns(result: FilterResult) -> dict[str, np.ndarray]:
    """``grf.csv``: per plate (``plate1_…``) and per foot (``foot_r_…``, ``foot_l_…``), at the marker rate."""
    columns = {"time_s": result.markers.time_s}
    for i, load in enumerate(result.plates):
        columns.update(load_columns(f"plate{i + 1}", load))
        columns[f"plate{i + 1}_foot"] = result.plate_owner[i]
    for side in ("r", "l"):
        if side in result.plate_loads_per_foot:
            columns.update(load_columns(f"foot_{side}", result.plate_loads_per_foot[side]))
    return columns


def event_columns(result: FilterResult) -> dict[str, np.ndarray]:
    """``events.csv``: :func:`events_table` of the filtered trial's events."""
    return events_table(result.events, result.markers.first_frame)


def events_table(ev: Events, first_frame: int) -> dict[str, np.ndarray]:
    """``time_s``, ``frame`` (the file's numbering from ``first_frame``), ``side``, ``event``, ``source``."""
    return {"time_s": ev.time_s, "frame": ev.frame + first_frame, "side": ev.side, "event": ev.kind,
            "source": ev.source}


def summary(result: FilterResult) -> dict:
    """The filter stage's ``summary.json`` keys plus notes and counts."""
    ev = result.events
    rows = [{"time_s": float(t), "frame": int(f) + result.markers.first_frame, "side": str(s), "event": str(k),
             "source": str(src)} for t, f, s, k, src in zip(ev.time_s, ev.frame, ev.side, ev.kind, ev.source)]
    return {
        "frames": result.markers.n_frames,
        "marker_rate_hz": result.markers.rate_hz,
        "analog_rate_hz": result.recording.plates[0].rate_hz if result.recording.plates else None,
        "cutoff_hz": result.config.cutoff_hz,
        "design_cutoff_hz": result.design_cutoff_hz,
        "force_cutoff_hz": result.config.force_cutoff_hz,
        "plate_frames": result.config.plate_frames,
        "gaps_filled": sum(1 for g in result.gaps if g.filled),
        "gaps_unfilled": sum(1 for g in result.gaps if not g.filled),
        "events": rows,
        "plates": len(result.recording.plates),
        "markers": len(result.markers.labels),
        "notes": list(result.recording.notes),
    }


def write_filter_outputs(folder: Path, result: FilterResult, attrs: dict) -> dict:
    """Write every table of the filter stage and ``filter.h5`` into ``folder``; return the summary.

    ``filter.h5``: ``trial/`` the :class:`~gaitcli.core.container.Trial` the later
    stages read back (:func:`gaitcli.io.h5.read_result`), ``markers/raw`` and
    ``markers/gaps``, every plate at the marker and the analog rate, ``lab_to_model``.
    """
    folder = Path(folder)
    write_table(folder / "markers_filtered.csv", marker_columns(result.markers))
    write_table(folder / "grf.csv", grf_columns(result))
    write_table(folder / "events.csv", event_columns(result))

    recording = result.recording
    data = record_datasets("trial", result.trial)
    data["trial/markers/positions_m"].attrs.update({
        "cutoff_hz": result.config.cutoff_hz, "design_cutoff_hz": result.design_cutoff_hz,
        "axes": "frames, markers, xyz (model axes)"})
    data.update({
        "markers/raw": Dataset(recording.markers.positions_m, "m", {"axes": "frames, markers, xyz (model axes)"}),
        "markers/gaps": Dataset(np.array([[g.marker_index, g.first_frame, g.last_frame, g.filled]
                                          for g in result.gaps], dtype=int).reshape(-1, 4), "frame",
                                {"columns": "marker_index, first_frame, last_frame, filled (0-based frames)"}),
        "lab_to_model": Dataset(recording.lab_to_model, "1", {"meaning": "v_model = R @ v_lab"}),
    })
    for i, (load, analog, plate) in enumerate(zip(result.plates, result.plates_analog, recording.plates)):
        g = f"plates/plate{i + 1}"
        data[f"{g}/force"] = Dataset(load.force_N, "N", {"rate_hz": load.rate_hz})
        data[f"{g}/cop"] = Dataset(load.cop_m, "m", {"rate_hz": load.rate_hz})
        data[f"{g}/free_moment"] = Dataset(load.free_moment_Nm, "N*m", {"rate_hz": load.rate_hz})
        data[f"{g}/foot"] = Dataset(np.asarray(result.plate_owner[i], dtype=str), "1")
        data[f"{g}/analog/force"] = Dataset(analog.force_N, "N", {"rate_hz": analog.rate_hz})
        data[f"{g}/analog/cop"] = Dataset(analog.cop_m, "m", {"rate_hz": analog.rate_hz})
        data[f"{g}/analog/free_moment"] = Dataset(analog.free_moment_Nm, "N*m", {"rate_hz": analog.rate_hz})
        data[f"{g}/analog/raw_vertical_force"] = Dataset(
            np.zeros(0) if plate.force_N is None else plate.force_N[:, 2], "N", {"rate_hz": plate.rate_hz})
        data[f"{g}/corners"] = Dataset(plate.corners_m, "m")
    write_h5(folder / "filter.h5", data, attrs)
    return summary(result)

