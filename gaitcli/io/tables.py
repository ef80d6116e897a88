"""Table readers and writers: a trial as markers.csv + forces.csv, and OpenSim's .trc / .mot.

markers.csv (lab axes, z up, metres)::

    time_s, <label>_x_m, <label>_y_m, <label>_z_m, ...   (one triplet per marker; empty cell = not seen)

forces.csv (the same lab axes; floor at z = 0)::

    time_s, plate<k>_force_x_N, plate<k>_force_y_N, plate<k>_force_z_N,
            plate<k>_cop_x_m, plate<k>_cop_y_m, plate<k>_free_moment_Nm, ...   (k = 1, 2, ...)

The force is the one the ground exerts on the subject, applied at the centre of
pressure (COP, on the floor z = 0) together with the free moment about the
vertical. COP and free moment may be empty where the plate carries no more
than 20 N vertical. The COP has only x and y, so this lab must be z-up with the
floor at z = 0; the horizontal orientation is free (the axis inference of
:mod:`gaitcli.io.axes` rotates it, as for C3D files). Time columns must be
uniformly spaced; both files must start at the same time.

Each plate becomes a :class:`ForcePlate` with its centre at the mean COP over
the loaded samples (z = 0) and moment about that centre
``M = (COP - centre) × F + (0, 0, T_z)``. The CSV does not give the plate
outline: ``corners_m`` is a 0.6 m (x) × 0.4 m (y) rectangle around that centre,
in C3D corner order (plate z into the floor); nothing downstream should rely
on its size.

``.trc`` and ``.mot`` are OpenSim 4's formats as its TRCFileAdapter and Storage
write them (described in :mod:`gaitcli.io.opensim`).
"""

from __future__ import annotations

import csv
import re
import warnings
from pathlib import Path

import numpy as np

from gaitcli.core.recording import ForcePlate, Markers, Recording
from gaitcli.errors import GaitWarning, InputError, shown
from gaitcli.io.atomic import atomic_path
from gaitcli.io.axes import LOAD_THRESHOLD_N, apply_rotation, infer_lab_to_model
from gaitcli.io.c3d.markers import LAB_REACH_M

__all__ = [
    "PLATE_SIZE_M",
    "read_csv_trial",
    "read_forces_csv",
    "read_markers_csv",
    "read_mot",
    "read_trc",
    "write_mot",
    "write_trc",
]

PLATE_SIZE_M = (0.6, 0.4)
"""Outline (x, y) given to plates read from forces.csv, which carries no corners."""

_TRC_KEYS = ("DataRate", "CameraRate", "NumFrames", "NumMarkers", "Units", "OrigDataRate",
             "OrigDataStartFrame", "OrigNumFrames")
_LENGTH_M = {"mm": 1e-3, "cm": 1e-2, "m": 1.0}
_MARKER_COLUMN = re.compile(r"^(.+)_([xyz])_m$")
_PLATE_COLUMN = re.compile(r"^plate(\d+)_(force_x_N|force_y_N|force_z_N|cop_x_m|cop_y_m|free_moment_Nm)$")
_PLATE_FIELDS = ("force_x_N", "force_y_N", "force_z_N", "cop_x_m", "cop_y_m", "free_moment_Nm")


# ----------------------------------------------------------------- CSV trial


#: the most cells (rows × columns) of a markers.csv or forces.csv gaitcli reads: as many as 20 minutes of 60
#: markers at 100 Hz and 1 kHz plates hold; read as text first, each cell takes ~100 bytes (~2 GB here)
CSV_MAX_CELLS = 20_000_000


def _read_numeric_csv(path: Path) -> tuple[list[str], np.ndarray]:
    """Header names and a float array (rows, columns) of a comma-separated file; empty cells are NaN."""
    if not path.is_file():
        raise InputError(path, None, "file not found")
    try:
        with open(path, newline="") as f:
            rows = []
            for row in csv.reader(f):
                if any(cell.strip() for cell in row):
                    rows.append(row)
                    if len(rows) * len(rows[0]) > CSV_MAX_CELLS:  # checked as read: memory stays bounded
                        raise InputError(path, None, f"more than {CSV_MAX_CELLS // len(rows[0])} rows of "
                                                     f"{len(rows[0])} columns, more than gaitcli reads "
                                                     f"({CSV_MAX_CELLS} cells; split the trial)")
    except (UnicodeDecodeError, csv.Error) as exc:
        raise InputError(path, None, f"not a readable CSV file ({' '.join(str(exc).split())[:80]})") from None
    except PermissionError:
        raise InputError(path, None, "cannot be read (permission denied)") from None
    if not rows:
        raise InputError(path, None, "file is empty (expected a header row starting with time_s)")
    names = [s.strip() for s in rows[0]]
    if len(set(names)) != len(names):
        dup = next(n for n in names if names.count(n) > 1)
        raise InputError(path, dup, "column appears more than once")
    if "time_s" not in names:
        raise InputError(path, "time_s", "column missing (expected time_s as the first column)")
    if names[0] != "time_s":
        raise InputError(path, "time_s", f"is column {names.index('time_s') + 1} (expected the first column)")
    body = rows[1:]
    if not body:
        raise InputError(path, None, "no data rows")
    for line, row in enumerate(body, start=2):
        if len(row) < len(names):
            raise InputError(path, names[len(row)], f"line {line} has fewer cells than the header")
        if len(row) > len(names):
            raise InputError(path, None, f"malformed CSV: line {line} has {len(row)} cells, the header {len(names)}")
    cells = np.char.strip(np.array(body, dtype=str))
    cells[cells == ""] = "nan"
    try:
        return names, cells.astype(float)
    except ValueError:
        for (row, col), cell in np.ndenumerate(cells):
            try:
                float(cell)
            except ValueError:
                raise InputError(path, names[col], f"line {row + 2}: got {shown(cell)} (expected a number)") from None
        raise


def _uniform_rate(path: Path, time_s: np.ndarray) -> float:
    """Sampling rate (Hz) of a strictly increasing, uniformly spaced time column."""
    if not np.isfinite(time_s).all():
        row = int(np.flatnonzero(~np.isfinite(time_s))[0])
        raise InputError(path, "time_s", f"line {row + 2}: missing time")
    if time_s.size < 2:
        raise InputError(path, "time_s", "needs at least two rows")
    dt = np.diff(time_s)
    step = float(np.median(dt))
    if step <= 0 or np.any(np.abs(dt - step) > 1e-6 + 1e-3 * step):
        row = int(np.argmax(np.abs(dt - step))) + 3
        raise InputError(path, "time_s", f"line {row}: not uniformly increasing (step {step:g} s expected)")
    return 1.0 / step


def read_markers_csv(path) -> Markers:
    """Markers (lab axes, metres) from a markers.csv; ``first_frame`` follows the first time."""
    path = Path(path)
    names, values = _read_numeric_csv(path)
    labels: list[str] = []
    where: dict[str, dict[str, int]] = {}
    for j, name in enumerate(names[1:], start=1):
        match = _MARKER_COLUMN.match(name)
        if not match:
            raise InputError(path, name, "unexpected column (expected <label>_x_m, <label>_y_m, <label>_z_m)")
        label, axis = match[1], match[2]
        if label not in where:
            labels.append(label)
            where[label] = {}
        where[label][axis] = j
    for label in labels:
        missing = [a for a in "xyz" if a not in where[label]]
        if missing:
            raise InputError(path, f"{label}_{missing[0]}_m", "column missing (each marker needs _x_m, _y_m, _z_m)")
    rate = _uniform_rate(path, values[:, 0])
    idx = np.array([[where[label][a] for a in "xyz"] for label in labels], dtype=int).reshape(-1, 3)
    positions = values[:, idx] if labels else np.zeros((values.shape[0], 0, 3))
    positions = _gaps_beyond_reach(path, labels, positions)
    return Markers(tuple(labels), positions, rate, first_frame=int(round(values[0, 0] * rate)) + 1)


def _gaps_beyond_reach(path: Path, labels, positions: np.ndarray) -> np.ndarray:
    """``positions`` (frames, markers, 3) m with non-finite samples and those beyond ±LAB_REACH_M of the lab
    origin as NaN (the latter warned, naming the markers)."""
    far = (np.abs(np.nan_to_num(positions)) > LAB_REACH_M).any(axis=2)
    if far.any():
        named = ", ".join(dict.fromkeys(labels[m] for m in np.nonzero(far)[1]))
        warnings.warn(f"{path.name}: {far.sum()} marker samples beyond {LAB_REACH_M:g} m of the lab origin read as "
                      f"gaps ({named})", GaitWarning, stacklevel=3)
    positions[~np.isfinite(positions).all(axis=2) | far] = np.nan
    return positions


def _csv_corners(centre: np.ndarray) -> np.ndarray:
    """0.6 x 0.4 m outline around ``centre`` in C3D corner order (x = c1 - c2 along +x, y = c1 - c4 along -y)."""
    hx, hy = PLATE_SIZE_M[0] / 2, PLATE_SIZE_M[1] / 2
    offsets = np.array([[hx, -hy, 0.0], [-hx, -hy, 0.0], [-hx, hy, 0.0], [hx, hy, 0.0]])
    return centre + offsets


def read_forces_csv(path) -> tuple[list[ForcePlate], float]:
    """Plates (lab axes, ground-on-subject) from a forces.csv, and the file's first time (s)."""
    path = Path(path)
    names, values = _read_numeric_csv(path)
    columns: dict[int, dict[str, int]] = {}
    for j, name in enumerate(names[1:], start=1):
        match = _PLATE_COLUMN.match(name)
        if not match:
            raise InputError(path, name, "unexpected column (expected plate<k>_force_x_N ... plate<k>_free_moment_Nm)")
        columns.setdefault(int(match[1]), {})[match[2]] = j
    rate = _uniform_rate(path, values[:, 0])
    plates = []
    for k in sorted(columns):
        missing = [f for f in _PLATE_FIELDS if f not in columns[k]]
        if missing:
            raise InputError(path, f"plate{k}_{missing[0]}", "column missing")
        force = values[:, [columns[k][f] for f in _PLATE_FIELDS[:3]]]
        if not np.isfinite(force).all():
            row, col = np.argwhere(~np.isfinite(force))[0]
            raise InputError(path, f"plate{k}_{_PLATE_FIELDS[col]}", f"line {row + 2}: missing value")
        cop_xy = values[:, [columns[k]["cop_x_m"], columns[k]["cop_y_m"]]]
        free = values[:, columns[k]["free_moment_Nm"]]
        loaded = force[:, 2] > LOAD_THRESHOLD_N
        for name, v in (("cop_x_m", cop_xy[:, 0]), ("cop_y_m", cop_xy[:, 1]), ("free_moment_Nm", free)):
            gap = loaded & ~np.isfinite(v)
            if gap.any():
                row = int(np.flatnonzero(gap)[0])
                raise InputError(path, f"plate{k}_{name}", f"line {row + 2}: missing where the plate is loaded")
        usable = np.isfinite(cop_xy).all(axis=1)
        pick = loaded & usable if (loaded & usable).any() else usable
        centre = np.zeros(3)
        if pick.any():
            centre[:2] = cop_xy[pick].mean(axis=0)
        r = np.zeros_like(force)
        r[:, :2] = np.where(usable[:, None], cop_xy - centre[:2], 0.0)
        moment = np.cross(r, force)
        moment[:, 2] += np.nan_to_num(free)
        plates.append(ForcePlate(f"plate{k}", force, moment, centre, _csv_corners(centre), rate, plate_type=2))
    return plates, float(values[0, 0])


def read_csv_trial(markers_csv, forces_csv=None, *, to_model_axes: bool = True) -> Recording:
    """A trial from markers.csv (+ forces.csv), rotated to model axes like :func:`gaitcli.io.c3d.read_c3d`."""
    markers_csv = Path(markers_csv)
    markers = read_markers_csv(markers_csv)
    notes: list[str] = []
    plates: list[ForcePlate] = []
    if forces_csv is not None:
        forces_csv = Path(forces_csv)
        plates, t0 = read_forces_csv(forces_csv)
        marker_t0 = (markers.first_frame - 1) / markers.rate_hz
        if plates and abs(t0 - marker_t0) > 0.5 / plates[0].rate_hz:
            raise InputError(
                forces_csv, "time_s", f"starts at {t0:g} s but {markers_csv.name} starts at {marker_t0:g} s"
            )
        notes.append(f"plate corners set to a {PLATE_SIZE_M[0]} x {PLATE_SIZE_M[1]} m outline around the mean COP")
        for plate in plates:
            peak = float(plate.force_N[:, 2].max())
            if peak <= LOAD_THRESHOLD_N:
                message = f"{forces_csv.name}: {plate.name} never sees a load (max vertical force {peak:.1f} N)"
                notes.append(message)
                warnings.warn(message, GaitWarning, stacklevel=2)
    if not plates:
        message = f"{markers_csv.name}: no force plates: markers only"
        notes.append(message)
        warnings.warn(message, GaitWarning, stacklevel=2)
    never = [lab for lab, gone in zip(markers.labels, np.isnan(markers.positions_m).all(axis=(0, 2))) if gone]
    if never:
        message = f"{markers_csv.name}: markers never seen (all samples missing): {', '.join(never)}"
        notes.append(message)
        warnings.warn(message, GaitWarning, stacklevel=2)
    recording = Recording(markers, plates, source=markers_csv, lab_to_model=np.eye(3), notes=notes)
    if to_model_axes:
        recording = apply_rotation(recording, infer_lab_to_model(markers.positions_m, plates))
    return recording


# ------------------------------------------------------------------- OpenSim


def _text_lines(path: Path) -> list[str]:
    if not path.is_file():
        raise InputError(path, None, "file not found")
    try:
        return path.read_text().splitlines()
    except UnicodeDecodeError:
        raise InputError(path, None, "not a text file") from None
    except PermissionError:
        raise InputError(path, None, "cannot be read (permission denied)") from None


def _float(path: Path, line_no: int, cell: str, column: str) -> float:
    try:
        return float(cell)
    except ValueError:
        raise InputError(path, column, f"line {line_no}: got {shown(cell)} (expected a number)") from None


def read_trc(path) -> Markers:
    """Markers (metres, axes as stored) from an OpenSim/Vicon .trc file; empty cells are NaN."""
    path = Path(path)
    lines = _text_lines(path)
    if len(lines) < 5 or not lines[0].startswith("PathFileType"):
        raise InputError(path, "header", "not a TRC file (expected 'PathFileType' on line 1)")
    keys = [k for k in lines[1].strip().split("\t") if k.strip()]
    values = [v for v in lines[2].strip().split("\t") if v.strip()]
    if tuple(k.strip() for k in keys) != _TRC_KEYS or len(values) != len(keys):
        raise InputError(path, "header", f"line 2-3: expected the keys {' '.join(_TRC_KEYS)} and one value each")
    meta = dict(zip(_TRC_KEYS, (v.strip() for v in values)))
    unit = meta["Units"].lower()
    if unit not in _LENGTH_M:
        raise InputError(path, "Units", f"got {shown(meta['Units'])} (expected mm, cm or m)")
    rate = _float(path, 3, meta["DataRate"], "DataRate")
    n_markers = int(_float(path, 3, meta["NumMarkers"], "NumMarkers"))
    labels = [s.strip() for s in lines[3].split("\t") if s.strip()]
    if labels[:2] != ["Frame#", "Time"] or len(labels) != n_markers + 2:
        raise InputError(path, "header", f"line 4: expected Frame#, Time and {n_markers} marker labels")
    labels = labels[2:]
    rows = []
    first_frame = None
    for line_no, line in enumerate(lines[5:], start=6):
        if not line.strip():
            if rows:
                break
            continue
        cells = [s.strip() for s in line.rstrip("\r\n").split("\t")]
        if len(cells) < 2 + 3 * n_markers:
            cells += [""] * (2 + 3 * n_markers - len(cells))
        if any(cells[2 + 3 * n_markers:]):
            raise InputError(path, None, f"line {line_no}: more cells than 2 + 3 x {n_markers}")
        if first_frame is None:
            first_frame = int(_float(path, line_no, cells[0], "Frame#"))
        coords = [
            np.nan if c == "" else _float(path, line_no, c, labels[i // 3])
            for i, c in enumerate(cells[2:2 + 3 * n_markers])
        ]
        rows.append(coords)
    if not rows:
        raise InputError(path, None, "no data rows")
    positions = np.array(rows, dtype=float).reshape(len(rows), n_markers, 3) * _LENGTH_M[unit]
    positions = _gaps_beyond_reach(path, labels, positions)
    return Markers(tuple(labels), positions, rate, first_frame=first_frame)


def write_trc(path, markers: Markers, *, units: str = "mm") -> Path:
    """Write markers (coordinates as given, e.g. rotated to OpenSim's y-up first) to an OpenSim .trc file."""
    path = Path(path)
    if units not in _LENGTH_M:
        raise InputError(path, "units", f"got {shown(units)} (expected mm, cm or m)")
    n, m = markers.n_frames, len(markers.labels)
    for label in markers.labels:
        if not label or any(ch.isspace() for ch in label):
            raise InputError(path, label or "label", "marker label is empty or contains whitespace")
    rate = f"{markers.rate_hz:g}"
    lines = [
        f"PathFileType\t4\t(X/Y/Z)\t{path.name}",
        "\t".join(_TRC_KEYS),
        "\t".join([rate, rate, str(n), str(m), units, rate, str(markers.first_frame), str(n)]),
        "\t".join(["Frame#", "Time"] + [f"{label}\t\t" for label in markers.labels]),
        "\t\t" + "\t".join(f"{a}{j + 1}" for j in range(m) for a in "XYZ"),
        "",
    ]
    coords = np.asarray(markers.positions_m, dtype=float).reshape(n, 3 * m) / _LENGTH_M[units]
    time = markers.time_s
    for i in range(n):
        cells = ["" if not np.isfinite(v) else f"{v:.10g}" for v in coords[i]]
        lines.append("\t".join([str(markers.first_frame + i), f"{time[i]:.10g}"] + cells))
    with atomic_path(path) as tmp:
        tmp.write_text("\n".join(lines) + "\n")
    return path


def read_mot(path) -> tuple[tuple[str, ...], np.ndarray]:
    """Column names (``time`` first) and data (rows, columns) of an OpenSim .mot/.sto file."""
    path = Path(path)
    lines = _text_lines(path)
    end = next((i for i, line in enumerate(lines) if line.strip().lower() == "endheader"), None)
    if end is None:
        raise InputError(path, "header", "no 'endheader' line (expected an OpenSim .mot/.sto file)")
    k = end + 1
    while k < len(lines) and not lines[k].strip():
        k += 1
    if k == len(lines):
        raise InputError(path, "header", "no column labels after 'endheader'")
    sep = "\t" if "\t" in lines[k] else None
    names = [s.strip() for s in lines[k].split(sep) if s.strip()]
    if not names or names[0].lower() != "time":
        raise InputError(path, "time", f"line {k + 1}: first column is '{names[0] if names else ''}' (expected time)")
    rows = []
    for line_no, line in enumerate(lines[k + 1:], start=k + 2):
        cells = line.split()
        if not cells:
            break
        if len(cells) != len(names):
            raise InputError(path, None, f"line {line_no}: {len(cells)} cells (expected {len(names)})")
        rows.append([_float(path, line_no, c, names[j]) for j, c in enumerate(cells)])
    return tuple(names), np.array(rows, dtype=float).reshape(len(rows), len(names))


def write_mot(path, time_s, columns: dict[str, np.ndarray], *, in_degrees: bool = False) -> Path:
    """Write an OpenSim .mot (Storage version 1): ``time`` then ``columns`` in the given order."""
    path = Path(path)
    time_s = np.asarray(time_s, dtype=float).ravel()
    names = list(columns)
    for name in names:
        if not name or any(ch.isspace() for ch in name) or name.lower() == "time":
            raise InputError(path, name or "column", "column name is empty, 'time' or contains whitespace")
    data = [np.asarray(columns[name], dtype=float).ravel() for name in names]
    for name, col in zip(names, data):
        if col.shape != time_s.shape:
            raise InputError(path, name, f"{col.size} values (expected {time_s.size}, one per time)")
    table = np.column_stack([time_s] + data) if data else time_s[:, None]
    lines = [
        path.name,
        "version=1",
        f"nRows={table.shape[0]}",
        f"nColumns={table.shape[1]}",
        f"inDegrees={'yes' if in_degrees else 'no'}",
        "endheader",
        "\t".join(["time"] + names),
    ]
    lines += ["\t".join(f"{v:.10g}" for v in row) for row in table]
    with atomic_path(path) as tmp:
        tmp.write_text("\n".join(lines) + "\n")
    return path
