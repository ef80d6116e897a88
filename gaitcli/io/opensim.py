"""OpenSim's text formats: marker trajectories (``.trc``) and motions / storage files (``.mot``, ``.sto``).

As OpenSim documents them ("Marker (.trc) Files", "Motion (.mot) Files", "Storage (.sto) Files"):

* ``.trc``: a tab-separated header ``PathFileType 4 (X/Y/Z) NAME``; the keys ``DataRate CameraRate NumFrames
  NumMarkers Units OrigDataRate OrigDataStartFrame OrigNumFrames`` and their values; the row ``Frame# Time``
  and the marker names (each over its three columns); the row ``X1 Y1 Z1 X2 …``; a blank line; then one row
  per frame. Missing markers are empty cells.
* ``.mot`` / ``.sto``: the name, ``version=1``, ``nRows=``, ``nColumns=``, ``inDegrees=yes|no``,
  ``endheader``, then the tab-separated column labels (``time`` first) and the rows.

Arrays and labels only: no model knowledge (OpenSim's axes are the caller's business).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from gaitcli.errors import InputError
from gaitcli.io.atomic import atomic_path

TRC_KEYS = ("DataRate", "CameraRate", "NumFrames", "NumMarkers", "Units", "OrigDataRate", "OrigDataStartFrame",
            "OrigNumFrames")
#: digits written: 0.001 mm for marker positions, 8 significant digits elsewhere
TRC_FORMAT, MOT_FORMAT = "%.5f", "%.8g"


def write_trc(path: str | Path, labels, positions_mm, rate_hz: float, *, first_frame: int = 1) -> Path:
    """Marker positions (frames, markers, 3) in mm (NaN: not seen) as an OpenSim ``.trc`` file, atomically."""
    path = Path(path)
    positions_mm = np.asarray(positions_mm, float)
    n, k = positions_mm.shape[:2]
    lines = [f"PathFileType\t4\t(X/Y/Z)\t{path.name}", "\t".join(TRC_KEYS),
             "\t".join(str(v) for v in (f"{rate_hz:g}", f"{rate_hz:g}", n, k, "mm", f"{rate_hz:g}", first_frame, n)),
             "Frame#\tTime\t" + "\t".join(f"{lab}\t\t" for lab in labels).rstrip("\t"),
             "\t\t" + "\t".join(f"X{j + 1}\tY{j + 1}\tZ{j + 1}" for j in range(k)), ""]
    for i in range(n):
        cells = ["" if not np.isfinite(v) else TRC_FORMAT % v for v in positions_mm[i].ravel()]
        lines.append("\t".join([str(first_frame + i), "%.5f" % (i / rate_hz)] + cells))
    with atomic_path(path) as tmp:
        tmp.write_text("\n".join(lines) + "\n")
    return path


def read_trc(path: str | Path) -> tuple[dict, tuple[str, ...], np.ndarray, np.ndarray]:
    """(header {key: text}, marker labels, time (frames,), positions (frames, markers, 3) in the file's units)."""
    path = Path(path)
    lines = path.read_text().splitlines()
    if len(lines) < 6 or not lines[0].startswith("PathFileType"):
        raise InputError(path, None, "not a TRC file (expected PathFileType in the first line)")
    header = dict(zip(lines[1].split("\t"), lines[2].split("\t")))
    labels = tuple(c for c in lines[3].split("\t")[2:] if c)
    rows = [line.split("\t") for line in lines[6:] if line.strip()]
    values = np.array([[float(c) if c else np.nan for c in r[1:2 + 3 * len(labels)]] for r in rows])
    return header, labels, values[:, 0], values[:, 1:].reshape(len(rows), len(labels), 3)


def write_motion(path: str | Path, columns: dict, *, in_degrees: bool, name: str | None = None) -> Path:
    """Columns (``time`` first, each (n,)) as an OpenSim motion or storage file (``.mot``/``.sto``), atomically."""
    path = Path(path)
    labels = list(columns)
    if labels[0] != "time":
        raise ValueError("an OpenSim motion's first column is time")
    table = np.column_stack([np.asarray(columns[c], float) for c in labels])
    lines = [name or path.stem, "version=1", f"nRows={table.shape[0]}", f"nColumns={table.shape[1]}",
             f"inDegrees={'yes' if in_degrees else 'no'}", "endheader", "\t".join(labels)]
    lines += ["\t".join(MOT_FORMAT % v for v in row) for row in table]
    with atomic_path(path) as tmp:
        tmp.write_text("\n".join(lines) + "\n")
    return path


def read_motion(path: str | Path) -> tuple[dict, dict[str, np.ndarray]]:
    """(header {key: value, "name": first line}, {label: (n,)}) of a ``.mot``/``.sto`` file."""
    path = Path(path)
    lines = path.read_text().splitlines()
    try:
        end = lines.index("endheader")
    except ValueError:
        raise InputError(path, None, "not an OpenSim motion (expected a header ending in endheader)") from None
    header = {"name": lines[0]}
    header.update(dict(line.split("=", 1) for line in lines[1:end] if "=" in line))
    labels = lines[end + 1].split("\t")
    table = np.array([[float(c) for c in line.split("\t")] for line in lines[end + 2:] if line.strip()])
    return header, {label: table[:, k] for k, label in enumerate(labels)}
