"""Writes the filter stage's files: markers_filtered.csv, grf.csv, events.csv, filter.h5, summary.json, plots/."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from gaitcli.io.outputs import Dataset, write_h5, write_json, write_table
from gaitcli.core.recording import Markers, Recording
from gaitcli.report import plots
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
        if side in result.feet:
            columns.update(load_columns(f"foot_{side}", result.feet[side]))
    return columns


def event_columns(result: FilterResult) -> dict[str, np.ndarray]:
    ev = result.events
    return {"time_s": ev.time_s, "frame": ev.frame + result.markers.first_frame, "side": ev.side,
            "event": ev.kind, "source": ev.source}


def summary(result: FilterResult, recording: Recording, elapsed_s: float) -> dict:
    """The filter stage's ``summary.json`` keys (DESIGN.md) plus notes and counts."""
    ev = result.events
    rows = [{"time_s": float(t), "frame": int(f) + result.markers.first_frame, "side": str(s), "event": str(k),
             "source": str(src)} for t, f, s, k, src in zip(ev.time_s, ev.frame, ev.side, ev.kind, ev.source)]
    return {
        "frames": result.markers.n_frames,
        "marker_rate_hz": result.markers.rate_hz,
        "analog_rate_hz": recording.plates[0].rate_hz if recording.plates else None,
        "cutoff_hz": result.config.cutoff_hz,
        "design_cutoff_hz": result.design_cutoff_hz,
        "force_cutoff_hz": result.config.force_cutoff_hz,
        "gaps_filled": sum(1 for g in result.gaps if g.filled),
        "gaps_unfilled": sum(1 for g in result.gaps if not g.filled),
        "events": rows,
        "plates": len(recording.plates),
        "markers": len(result.markers.labels),
        "notes": list(recording.notes),
        "elapsed_s": round(elapsed_s, 3),
    }


def write_filter_outputs(folder: Path, result: FilterResult, recording: Recording, attrs: dict,
                         *, elapsed_s: float) -> dict:
    """Write every file of the filter stage into ``folder``; return the summary."""
    folder = Path(folder)
    write_table(folder / "markers_filtered.csv", marker_columns(result.markers))
    write_table(folder / "grf.csv", grf_columns(result))
    write_table(folder / "events.csv", event_columns(result))

    m = result.markers
    data = {
        "markers/labels": Dataset(np.array(m.labels), "1"),
        "markers/time": Dataset(m.time_s, "s"),
        "markers/raw": Dataset(result.raw_markers.positions_m, "m", {"axes": "frames, markers, xyz (model axes)"}),
        "markers/filtered": Dataset(m.positions_m, "m", {"cutoff_hz": result.config.cutoff_hz,
                                                         "design_cutoff_hz": result.design_cutoff_hz,
                                                         "rate_hz": m.rate_hz, "first_frame": m.first_frame}),
        "markers/gaps": Dataset(np.array([[g.marker_index, g.first_frame, g.last_frame, g.filled]
                                          for g in result.gaps], dtype=int).reshape(-1, 4), "frame",
                                {"columns": "marker_index, first_frame, last_frame, filled (0-based frames)"}),
        "events/time": Dataset(result.events.time_s, "s"),
        "events/frame": Dataset(result.events.frame, "frame", {"base": "0-based"}),
        "events/side": Dataset(np.asarray(result.events.side, dtype=str), "1"),
        "events/kind": Dataset(np.asarray(result.events.kind, dtype=str), "1"),
        "events/source": Dataset(np.asarray(result.events.source, dtype=str), "1"),
        "lab_to_model": Dataset(recording.lab_to_model, "1", {"meaning": "v_model = R @ v_lab"}),
    }
    for i, (load, analog, plate) in enumerate(zip(result.plates, result.plates_analog, recording.plates)):
        g = f"plates/plate{i + 1}"
        data[f"{g}/force"] = Dataset(load.force_N, "N", {"rate_hz": load.rate_hz})
        data[f"{g}/cop"] = Dataset(load.cop_m, "m", {"rate_hz": load.rate_hz})
        data[f"{g}/free_moment"] = Dataset(load.free_moment_Nm, "N*m", {"rate_hz": load.rate_hz})
        data[f"{g}/foot"] = Dataset(np.asarray(result.plate_owner[i], dtype=str), "1")
        data[f"{g}/analog/force"] = Dataset(analog.force_N, "N", {"rate_hz": analog.rate_hz})
        data[f"{g}/analog/cop"] = Dataset(analog.cop_m, "m", {"rate_hz": analog.rate_hz})
        data[f"{g}/analog/free_moment"] = Dataset(analog.free_moment_Nm, "N*m", {"rate_hz": analog.rate_hz})
        data[f"{g}/corners"] = Dataset(plate.corners_m, "m")
    for side, load in result.feet.items():
        data[f"feet/{side}/force"] = Dataset(load.force_N, "N")
        data[f"feet/{side}/cop"] = Dataset(load.cop_m, "m")
        data[f"feet/{side}/free_moment"] = Dataset(load.free_moment_Nm, "N*m")
    write_h5(folder / "filter.h5", data, attrs)

    plots.filter_figures(folder / "plots", result, title=attrs.get("trial", ""))
    info = summary(result, recording, elapsed_s)
    write_json(folder / "summary.json", info)
    return info


def filtered_trial(result: FilterResult):
    """The part of a filter result the idyn stage uses."""
    from gaitcli.dynamics.stage import FilteredTrial

    feet = {side: {"force_N": load.force_N, "cop_m": load.cop_m, "free_moment_Nm": load.free_moment_Nm}
            for side, load in result.feet.items()}
    return FilteredTrial(markers=result.markers, feet=feet, events=result.events)


def read_filtered_trial(path: Path):
    """Read ``filter.h5`` back into the :class:`~gaitcli.dynamics.stage.FilteredTrial` the idyn stage uses."""
    import h5py

    from gaitcli.dynamics.stage import FilteredTrial
    from gaitcli.core.events import Events

    with h5py.File(path, "r") as h5:
        ds = h5["markers/filtered"]
        labels = tuple(x.decode() if isinstance(x, bytes) else str(x) for x in h5["markers/labels"][()])
        markers = Markers(labels, ds[()], float(ds.attrs["rate_hz"]), int(ds.attrs["first_frame"]))
        feet = {}
        for side in ("r", "l"):
            if f"feet/{side}/force" in h5:
                feet[side] = {"force_N": h5[f"feet/{side}/force"][()], "cop_m": h5[f"feet/{side}/cop"][()],
                              "free_moment_Nm": h5[f"feet/{side}/free_moment"][()]}
        text = (lambda key: np.array([x.decode() if isinstance(x, bytes) else str(x) for x in h5[key][()]]))
        events = Events(frame=h5["events/frame"][()].astype(int), time_s=h5["events/time"][()],
                        side=text("events/side"), kind=text("events/kind"), source=text("events/source"))
    return FilteredTrial(markers=markers, feet=feet, events=events)
