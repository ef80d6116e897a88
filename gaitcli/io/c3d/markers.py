"""C3D markers: point units, labels and the marker array.

POINT:UNITS (mm, cm, m) → metres; a sample is missing (NaN) where
ezc3d's residual is negative or the stored point is exactly (0, 0, 0), and
(warned) where a coordinate lies beyond ±LAB_REACH_M of the lab origin. Points
listed in POINT:ANGLES/FORCES/MOMENTS/POWERS/SCALARS/REACTIONS (model outputs
of Plug-in Gait style exports) are dropped. Labels are stripped of surrounding
whitespace (inner spaces, as in BTS files, are kept) and of a Vicon subject
prefix ``Subject:``. Repeated labels keep the first and rename the later ones
``<label>_2``, ``<label>_3``, ... (noted and warned).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from gaitcli.core.recording import Markers
from gaitcli.errors import InputError
from gaitcli.io.c3d.header import param, strings, warn

__all__ = ["MODEL_OUTPUT_GROUPS", "LAB_REACH_M", "LENGTH_M", "point_length_m", "read_markers"]

MODEL_OUTPUT_GROUPS = ("ANGLES", "FORCES", "MOMENTS", "POWERS", "SCALARS", "REACTIONS")
"""POINT parameters that list model outputs stored as points (not markers)."""

LAB_REACH_M = 10_000.0
"""A marker coordinate beyond ±10 km of the lab origin is a damaged sample, read as a gap, not a position whose
moments would be astronomical. No capture volume comes near (a long treadmill or overground recording stays
within a kilometre); and there a float C3D coordinate in millimetres resolves a millimetre no better."""

LENGTH_M = {
    "mm": 1e-3, "millimeter": 1e-3, "millimeters": 1e-3, "millimetre": 1e-3, "millimetres": 1e-3,
    "cm": 1e-2, "centimeter": 1e-2, "centimeters": 1e-2, "centimetre": 1e-2, "centimetres": 1e-2,
    "m": 1.0, "meter": 1.0, "meters": 1.0, "metre": 1.0, "metres": 1.0,
}


def point_length_m(path: Path, params, points: np.ndarray, notes: list[str]) -> float:
    """Metres per POINT:UNITS unit; where UNITS is missing, guessed from the coordinates' size (warned)."""
    units = param(params, "POINT", "UNITS", [])
    unit = str(units[0]).strip().lower() if len(units) else ""
    if unit in LENGTH_M:
        length_m = LENGTH_M[unit]
        if length_m != 1.0:
            notes.append(f"POINT:UNITS '{units[0].strip()}' converted to metres")
        return length_m
    if unit:
        raise InputError(path, "POINT:UNITS", f"got '{units[0].strip()}' (expected mm, cm or m)")
    largest = np.nanmax(np.abs(points[:3])) if np.isfinite(points[:3]).any() else 0.0
    length_m = 1e-3 if largest > 50.0 else 1.0
    warn(
        f"{path.name}: POINT:UNITS missing; coordinates up to {largest:.0f} taken as "
        f"{'mm' if length_m == 1e-3 else 'm'}", notes,
    )
    return length_m


#: m: the median distance of a frame's markers from their median point, for one body (0.3–0.6 m for an adult)
BODY_SPREAD_M = (0.02, 3.0)


def check_body_size(path: Path, params, positions_m: np.ndarray) -> None:
    """Refuse markers whose size says POINT:UNITS is wrong (a file in mm labelled m: a body 500 m wide): the
    median over frames of each frame's median marker distance from its median point, against
    :data:`BODY_SPREAD_M`. Only where at least 4 markers are seen in 10 frames (a wand or a lab's fixed markers
    far away do not move the median)."""
    seen = np.isfinite(positions_m).all(axis=2)
    frames = np.flatnonzero(seen.sum(axis=1) >= 4)
    if frames.size < 10:
        return
    step = max(1, frames.size // 200)  # a sample of the frames is enough
    spreads = []
    for k in frames[::step]:
        p = positions_m[k][seen[k]]
        spreads.append(np.median(np.linalg.norm(p - np.median(p, axis=0), axis=1)))
    spread = float(np.median(spreads))
    low, high = BODY_SPREAD_M
    if not low <= spread <= high:
        units = param(params, "POINT", "UNITS", [])
        unit = str(units[0]).strip() if len(units) else ""
        raise InputError(path, "POINT:UNITS", f"got {unit!r}: the markers lie a median {spread:.3g} m from their "
                                              f"centre (expected a body's {low:g}–{high:g} m; the units or the data "
                                              "are damaged)")


# --------------------------------------------------------------------- markers


def _clean_label(label: str) -> tuple[str, str]:
    """(label without surrounding whitespace and 'Subject:' prefix, removed prefix)."""
    text = label.strip()
    prefix = ""
    if ":" in text:
        prefix, text = text.rsplit(":", 1)
        text = text.strip()
    return text, prefix.strip()


def _unique_labels(labels: list[str]) -> tuple[list[str], list[str]]:
    """Keep the first of repeated labels, rename later ones ``<label>_2``, ...; also describe each renaming."""
    taken = set(labels)
    count: dict[str, int] = {}
    out = []
    for label in labels:
        if label not in count:
            count[label] = 1
            out.append(label)
            continue
        k = count[label] + 1
        while f"{label}_{k}" in taken:
            k += 1
        count[label] = k
        taken.add(f"{label}_{k}")
        out.append(f"{label}_{k}")
    changes = []
    for label in dict.fromkeys(labels):
        idx = [i for i, lab in enumerate(labels) if lab == label]
        if len(idx) > 1:
            changes.append(
                f"{label} (points {', '.join(str(i + 1) for i in idx)}) -> {', '.join(out[i] for i in idx)}"
            )
    return out, changes


def read_markers(path: Path, c, length_m: float, notes: list[str]) -> Markers:
    """The markers of ezc3d's ``c`` in metres, lab axes, missing samples NaN, model-output points dropped."""
    params = c["parameters"]
    points = np.asarray(c["data"]["points"], dtype=float)  # (4, markers, frames)
    n_points = points.shape[1]
    raw = strings(params, "POINT", "LABELS")[:n_points]
    raw += [""] * (n_points - len(raw))
    cleaned = [_clean_label(s) for s in raw]
    labels = [text or f"point{i + 1}" for i, (text, _) in enumerate(cleaned)]
    prefixes = sorted({p for _, p in cleaned if p})
    if prefixes:
        notes.append(f"subject prefix {', '.join(repr(p + ':') for p in prefixes)} removed from marker labels")
    unnamed = [f"point{i + 1}" for i, (text, _) in enumerate(cleaned) if not text]
    if unnamed:
        notes.append(f"unlabelled points named {', '.join(unnamed)}")

    outputs = set()
    for group in MODEL_OUTPUT_GROUPS:
        outputs |= {_clean_label(s)[0] for s in strings(params, "POINT", group) if s.strip()}
    keep = [i for i, lab in enumerate(labels) if lab not in outputs]
    if len(keep) < n_points:
        notes.append(
            f"{n_points - len(keep)} model-output points dropped (listed in POINT:"
            f"{'/'.join(g for g in MODEL_OUTPUT_GROUPS if strings(params, 'POINT', g))})"
        )

    positions = np.transpose(points[:3, keep, :], (2, 1, 0)) * length_m  # (frames, markers, 3)
    residuals = np.asarray(c["data"]["meta_points"]["residuals"], dtype=float)
    missing = ~np.isfinite(positions).all(axis=2) | np.all(positions == 0.0, axis=2)
    if residuals.size:
        missing |= residuals[0][keep, :].T < 0
    far = ~missing & (np.abs(np.nan_to_num(positions)) > LAB_REACH_M).any(axis=2)
    missing |= far
    positions[missing] = np.nan

    labels, changes = _unique_labels([labels[i] for i in keep])
    if far.any():
        frames, markers = np.nonzero(far)
        named = ", ".join(dict.fromkeys(labels[m] for m in markers))
        warn(f"{path.name}: {far.sum()} marker samples beyond {LAB_REACH_M:g} m of the lab origin read as gaps "
             f"({named}; first at frame {int(frames.min()) + int(c['header']['points']['first_frame']) + 1})", notes)
    if changes:
        warn(f"{path.name}: duplicate marker labels; kept the first, renamed the others: {'; '.join(changes)}", notes)
    never = [lab for lab, m in zip(labels, missing.all(axis=0)) if m]
    if never and positions.shape[0] > 0:
        warn(f"{path.name}: markers never seen (all samples missing): {', '.join(never)}", notes)

    header = c["header"]["points"]
    return Markers(
        labels=tuple(labels),
        positions_m=positions,
        rate_hz=float(header["frame_rate"]),
        first_frame=int(header["first_frame"]) + 1,
    )
