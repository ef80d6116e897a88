"""C3D reader: markers and force plates in SI units, lab axes mapped to model axes.

Markers: POINT:UNITS (mm, cm, m) → metres; a sample is missing (NaN) where
ezc3d's residual is negative or the stored point is exactly (0, 0, 0). Points
listed in POINT:ANGLES/FORCES/MOMENTS/POWERS/SCALARS/REACTIONS (model outputs
of Plug-in Gait style exports) are dropped. Labels are stripped of surrounding
whitespace (inner spaces, as in BTS files, are kept) and of a Vicon subject
prefix ``Subject:``. Repeated labels keep the first and rename the later ones
``<label>_2``, ``<label>_3``, ... (noted and warned).

Force plates use ezc3d's force-platform module (ezc3d 1.7), whose outputs are,
for plate types 2, 3 and 4, and all in lab axes (the plate axes come from the
corners: x = c1 - c2, y = c1 - c4, z = x × y, which points into the floor for
C3D's corner order):

* ``force``: the six (type 3: eight) analog channels rotated to lab axes,
  ``R_plate @ F_channels``, no sign change, in FORCE_PLATFORM:UNITS (N);
* ``moment``: the moment of that force about the centre of the top surface
  (the mean of the four corners), ``R_plate @ (M_channels + F × o)`` where
  ``o`` is FORCE_PLATFORM:ORIGIN negated if its z is positive, i.e. taken as
  the vector from the transducer origin to the surface centre in plate axes
  (z down, so z ≤ 0); units N·(POINT:UNITS);
* ``center_of_pressure``: ``centre + R_plate @ (-M_y/F_z, M_x/F_z, 0)`` with
  plate-axis moments about the surface centre, POINT:UNITS (type 3 adds
  Kistler's FPCOPPOLY correction);
* ``Tz``: the moment about the COP, ``R_plate @ (M + F × r)``, whose only
  plate-axis component is the free moment along the plate's z (into the floor).

Type 1 (channels Fx, Fy, Fz, COPx, COPy, Tz): ezc3d's ``moment`` there is
``F × r - Tz``, the negative of the other types' convention, so the moment about
the centre is rebuilt here as ``r × F + Tz`` from ezc3d's COP and Tz.

OpenSim 4 reads plates through the same module: its std_cop_walking2_grfs.sto
equals ezc3d's force, COP and Tz to the printed digits, and std_walking2_grfs.sto
(wrench "at the plate origin") holds ezc3d's moment about the surface centre.

``ForcePlate`` stores the force the ground exerts on the subject. Every shared
file already yields that from ezc3d (vertical component positive under load);
a plate whose loaded force points away from the markers' side of its surface
is negated (force and moment; the COP is unchanged) and this is noted.
FORCE_PLATFORM:ZERO, where it names a valid frame range, is applied as a
baseline subtraction of force and moment (types 2-4; linear in the channels).
"""

from __future__ import annotations

import struct
import warnings
from pathlib import Path

import ezc3d
import numpy as np

from gaitcli.errors import GaitWarning, InputError
from gaitcli.io.axes import LOAD_THRESHOLD_N, apply_rotation, infer_lab_to_model
from gaitcli.core.recording import ForcePlate, Markers, Recording

__all__ = ["read_c3d", "MODEL_OUTPUT_GROUPS"]

MODEL_OUTPUT_GROUPS = ("ANGLES", "FORCES", "MOMENTS", "POWERS", "SCALARS", "REACTIONS")
"""POINT parameters that list model outputs stored as points (not markers)."""

_LENGTH_M = {
    "mm": 1e-3, "millimeter": 1e-3, "millimeters": 1e-3, "millimetre": 1e-3, "millimetres": 1e-3,
    "cm": 1e-2, "centimeter": 1e-2, "centimeters": 1e-2, "centimetre": 1e-2, "centimetres": 1e-2,
    "m": 1.0, "meter": 1.0, "meters": 1.0, "metre": 1.0, "metres": 1.0,
}
_FORCE_N = {"n": 1.0, "nt": 1.0, "newton": 1.0, "newtons": 1.0, "kn": 1e3}
_BASELINE_MAX_N = 100.0
"""A FORCE_PLATFORM:ZERO baseline above this vertical force is a load, not an offset: not applied."""
_MIPS_MESSAGE = (
    "cannot read C3D: MIPS/SGI processor format is not supported; expected Intel or DEC (re-export the file)"
)


def read_c3d(path, *, to_model_axes: bool = True) -> Recording:
    """Read a C3D trial into a :class:`Recording` (metres, newtons, N·m).

    With ``to_model_axes`` the lab → model rotation from
    :func:`gaitcli.io.axes.infer_lab_to_model` is applied and stored in
    ``lab_to_model``; without it the data stay in lab axes, ``lab_to_model`` is
    the identity and the inferred rotation is given in ``notes``.
    Raises :class:`InputError` for a missing, non-C3D, truncated or MIPS file.
    """
    path = Path(path)
    header_frames = _check_file(path)
    try:
        c = ezc3d.c3d(str(path))
    except Exception as exc:  # ezc3d raises RuntimeError/OSError/ValueError with multi-line text
        raise InputError(path, None, f"cannot read C3D: {_one_line(exc)}") from None
    n_frames = c["data"]["points"].shape[2]
    if header_frames is not None and n_frames < header_frames:
        raise InputError(path, "data", f"cannot read C3D: file is truncated ({n_frames} of {header_frames} frames)")

    params = c["parameters"]
    notes: list[str] = []
    length_m = _point_length_m(path, params, c["data"]["points"], notes)
    markers = _markers(path, c, length_m, notes)
    plates = _plates(path, c, length_m, markers, notes)
    if not plates:
        _warn(f"{path.name}: no usable force plates: markers only", notes)

    recording = Recording(markers=markers, plates=plates, source=path, lab_to_model=np.eye(3), notes=notes)
    R = infer_lab_to_model(markers.positions_m, plates)
    rows = "; ".join(" ".join(f"{v + 0.0:+.4f}" for v in row) for row in R)
    if to_model_axes:
        recording = apply_rotation(recording, R)
        recording.notes.append(f"lab axes rotated to model axes, lab_to_model rows: [{rows}]")
    else:
        recording.notes.append(f"data kept in lab axes; inferred lab_to_model rows: [{rows}]")
    return recording


# ---------------------------------------------------------------- file checks


def _one_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    return text.removesuffix(": iostream error") or type(exc).__name__


def _check_file(path: Path) -> int | None:
    """Validate the header before ezc3d sees the file (a cut parameter section makes ezc3d hang).

    Returns the frame count the header announces (None when its 16-bit frame
    numbers cannot be trusted).
    """
    if not path.exists():
        raise InputError(path, None, "file not found")
    if not path.is_file():
        raise InputError(path, None, "not a file (expected a C3D file)")
    size = path.stat().st_size
    with open(path, "rb") as f:
        head = f.read(512)
        if size < 512:
            raise InputError(path, "header", f"not a C3D file: {size} bytes, shorter than the 512-byte header")
        if head[1] != 0x50:
            raise InputError(path, "header", f"not a C3D file: byte 2 is 0x{head[1]:02X}, expected 0x50")
        param_block = head[0]
        if param_block < 2:
            raise InputError(path, "header", f"not a C3D file: parameter block number {param_block} (expected >= 2)")
        param_offset = (param_block - 1) * 512
        f.seek(param_offset)
        param_head = f.read(4)
    if len(param_head) < 4:
        raise InputError(path, "parameters", f"cannot read C3D: file is truncated ({size} bytes, no parameter section)")
    processor = param_head[3] - 83
    if processor == 3:
        raise InputError(path, "processor", _MIPS_MESSAGE)
    if processor not in (1, 2):
        raise InputError(
            path, "processor", f"not a C3D file: processor byte {param_head[3]} (expected 84 Intel or 85 DEC)"
        )
    n_param_blocks = param_head[2]
    if size < param_offset + 512 * n_param_blocks:
        raise InputError(
            path, "parameters",
            f"cannot read C3D: file is truncated ({size} bytes, the parameter section needs "
            f"{param_offset + 512 * n_param_blocks})",
        )
    n_points, n_analog, first, last = struct.unpack("<4H", head[2:10])
    data_block = struct.unpack("<H", head[16:18])[0]
    if data_block <= param_block:
        raise InputError(path, "header", f"not a C3D file: data block {data_block} is not after the parameters")
    if processor == 1:
        is_float = struct.unpack("<f", head[12:16])[0] < 0
    else:  # DEC F-float: the sign bit is the top bit of the first 16-bit word
        is_float = bool(head[13] & 0x80)
    if last < first:
        return None
    n_frames = last - first + 1
    need = (data_block - 1) * 512 + n_frames * (4 * n_points + n_analog) * (4 if is_float else 2)
    if size < need:
        raise InputError(
            path, "data",
            f"cannot read C3D: file is truncated ({size} bytes, the header's {n_frames} frames need {need})",
        )
    return n_frames


def _warn(message: str, notes: list[str]) -> None:
    notes.append(message)
    warnings.warn(message, GaitWarning, stacklevel=3)


# ------------------------------------------------------------------ parameters


def _param(params, group: str, name: str, default=None):
    try:
        return params[group][name]["value"]
    except KeyError:
        return default


def _strings(params, group: str, name: str) -> list[str]:
    """A CHAR parameter and its continuations (NAME2, NAME3, ...) as one list."""
    out = list(_param(params, group, name, []) or [])
    k = 2
    while _param(params, group, f"{name}{k}") is not None:
        out += list(_param(params, group, f"{name}{k}"))
        k += 1
    return [str(s) for s in out]


def _point_length_m(path: Path, params, points: np.ndarray, notes: list[str]) -> float:
    units = _param(params, "POINT", "UNITS", [])
    unit = str(units[0]).strip().lower() if len(units) else ""
    if unit in _LENGTH_M:
        length_m = _LENGTH_M[unit]
        if length_m != 1.0:
            notes.append(f"POINT:UNITS '{units[0].strip()}' converted to metres")
        return length_m
    if unit:
        raise InputError(path, "POINT:UNITS", f"got '{units[0].strip()}' (expected mm, cm or m)")
    largest = np.nanmax(np.abs(points[:3])) if np.isfinite(points[:3]).any() else 0.0
    length_m = 1e-3 if largest > 50.0 else 1.0
    _warn(
        f"{path.name}: POINT:UNITS missing; coordinates up to {largest:.0f} taken as "
        f"{'mm' if length_m == 1e-3 else 'm'}", notes,
    )
    return length_m


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


def _markers(path: Path, c, length_m: float, notes: list[str]) -> Markers:
    params = c["parameters"]
    points = np.asarray(c["data"]["points"], dtype=float)  # (4, markers, frames)
    n_points = points.shape[1]
    raw = _strings(params, "POINT", "LABELS")[:n_points]
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
        outputs |= {_clean_label(s)[0] for s in _strings(params, "POINT", group) if s.strip()}
    keep = [i for i, lab in enumerate(labels) if lab not in outputs]
    if len(keep) < n_points:
        notes.append(
            f"{n_points - len(keep)} model-output points dropped (listed in POINT:"
            f"{'/'.join(g for g in MODEL_OUTPUT_GROUPS if _strings(params, 'POINT', g))})"
        )

    positions = np.transpose(points[:3, keep, :], (2, 1, 0)) * length_m  # (frames, markers, 3)
    residuals = np.asarray(c["data"]["meta_points"]["residuals"], dtype=float)
    missing = ~np.isfinite(positions).all(axis=2) | np.all(positions == 0.0, axis=2)
    if residuals.size:
        missing |= residuals[0][keep, :].T < 0
    positions[missing] = np.nan

    labels, changes = _unique_labels([labels[i] for i in keep])
    if changes:
        _warn(f"{path.name}: duplicate marker labels; kept the first, renamed the others: {'; '.join(changes)}", notes)
    never = [lab for lab, m in zip(labels, missing.all(axis=0)) if m]
    if never and positions.shape[0] > 0:
        _warn(f"{path.name}: markers never seen (all samples missing): {', '.join(never)}", notes)

    header = c["header"]["points"]
    return Markers(
        labels=tuple(labels),
        positions_m=positions,
        rate_hz=float(header["frame_rate"]),
        first_frame=int(header["first_frame"]) + 1,
    )


# ---------------------------------------------------------------------- plates


def plate_axes(corners: np.ndarray) -> np.ndarray:
    """Plate axes (3, 3), columns x, y, z in lab coordinates, from corners (4, 3) as ezc3d builds them."""
    x = corners[0] - corners[1]
    y = corners[0] - corners[3]
    z = np.cross(x, y)
    y = np.cross(z, x)
    return np.stack([v / np.linalg.norm(v) for v in (x, y, z)], axis=1)


def _moment_length_m(unit: str) -> float | None:
    """Length part of a moment unit such as 'Nmm', 'ntmm', 'N.m' in metres, or None if unrecognised."""
    u = unit.strip().lower()
    for ch in " .*·-_":
        u = u.replace(ch, "")
    for prefix in ("newton", "nt", "n"):
        if u.startswith(prefix):
            return _LENGTH_M.get(u[len(prefix):])
    return None


def _plate_values(params, name: str, block: int | None, index: int):
    """Values of plate ``index`` in a FORCE_PLATFORM parameter (flat, column-major as stored), or None.

    ``block`` values per plate; None takes the parameter's first dimension (CHANNEL).
    """
    value = _param(params, "FORCE_PLATFORM", name)
    if value is None:
        return None
    a = np.asarray(value)
    if block is None:
        block = a.shape[0] if a.ndim >= 2 else a.size
    flat = a.ravel(order="F")
    if flat.size < block * (index + 1):
        return None
    return flat[block * index:block * (index + 1)]


def _plates(path: Path, c, length_m: float, markers: Markers, notes: list[str]) -> list[ForcePlate]:
    params = c["parameters"]
    used = _param(params, "FORCE_PLATFORM", "USED", [0])
    n_used = int(used[0]) if len(used) else 0
    analogs = c["data"]["analogs"]
    if n_used == 0 or analogs.shape[1] == 0:
        return []
    force_units = _param(params, "FORCE_PLATFORM", "UNITS", [])
    force_unit = str(force_units[0]).strip() if len(force_units) else "N"
    if force_unit.lower() not in _FORCE_N:
        raise InputError(path, "FORCE_PLATFORM:UNITS", f"got '{force_unit}' (expected N)")
    force_scale = _FORCE_N[force_unit.lower()]
    types = np.asarray(_param(params, "FORCE_PLATFORM", "TYPE", []), dtype=int).ravel()
    analog_units = _strings(params, "ANALOG", "UNITS")
    n_frames = c["data"]["points"].shape[2]
    n_samples = analogs.shape[2]
    rate_hz = float(c["header"]["points"]["frame_rate"]) * (n_samples / max(n_frames, 1))
    seen = np.isfinite(markers.positions_m).all(axis=2)
    marker_mean_lab = markers.positions_m[seen].mean(axis=0) / length_m if seen.any() else None

    plates = []
    for i in range(n_used):
        name = f"plate{i + 1}"
        try:
            pf = ezc3d.c3d.PlatForm(ezc3d.ezc3d.ForcePlatform(i, c.c3d_swig))
        except Exception as exc:
            type_text = f" (TYPE {types[i]})" if i < types.size else ""
            _warn(
                f"{path.name}: plate {i + 1}{type_text} refused: {_one_line(exc)}; supported FORCE_PLATFORM:TYPE 1-4",
                notes,
            )
            continue
        plate_type = int(types[i]) if i < types.size else 2
        force = np.asarray(pf["force"], dtype=float).T
        moment = np.asarray(pf["moment"], dtype=float).T
        corners = np.asarray(pf["corners"], dtype=float).T
        centre = corners.mean(axis=0)
        axes = plate_axes(corners)
        normal = axes[:, 2]

        if plate_type == 1:
            r = np.nan_to_num(np.asarray(pf["center_of_pressure"], dtype=float).T - centre)
            moment = np.cross(r, force) + np.nan_to_num(np.asarray(pf["Tz"], dtype=float).T)
        elif plate_type in (2, 4):
            channels = _plate_values(params, "CHANNEL", None, i)
            if channels is not None and len(analog_units) >= int(max(channels[3:6])):
                units = {analog_units[int(ch) - 1] for ch in channels[3:6]}
                scales = {_moment_length_m(u) for u in units}
                if len(scales) == 1 and None not in scales and scales != {length_m}:
                    k = scales.pop() / length_m
                    lever = axes @ np.asarray(pf["origin"], dtype=float)
                    moment = k * moment + (1.0 - k) * np.cross(force, lever)
                    notes.append(f"{name}: moment channels in {sorted(units)[0]} rescaled to POINT:UNITS")
        elif plate_type == 3:
            poly = _plate_values(params, "FPCOPPOLY", 12, i)
            if poly is not None and np.any(np.asarray(poly, dtype=float) != 0):
                moment = _kistler_corrected_moment(pf, force, moment, centre, normal, force_scale)
                notes.append(f"{name}: Kistler FPCOPPOLY COP correction kept where loaded")

        moment, force, baseline_note = _zero_baseline(params, i, force, moment, normal, n_samples, n_frames,
                                                      force_scale, plate_type)
        if baseline_note:
            notes.append(f"{name}: {baseline_note}")

        up = -normal
        if marker_mean_lab is not None and np.dot(marker_mean_lab - centre, normal) > 0:
            up = normal
        vertical = force_scale * force @ up
        loaded = np.abs(vertical) > LOAD_THRESHOLD_N
        if loaded.any() and vertical[loaded].sum() < 0:
            force, moment, vertical = -force, -moment, -vertical
            notes.append(f"{name}: force pointed into the floor under load; negated to ground-on-subject")
        peak = float(np.nanmax(vertical)) if vertical.size else 0.0
        if not np.isfinite(force).all() or not np.isfinite(moment).all():
            bad = int((~np.isfinite(force).all(axis=1) | ~np.isfinite(moment).all(axis=1)).sum())
            notes.append(f"{name}: {bad} samples with non-finite analog data")
        if not peak > LOAD_THRESHOLD_N:
            _warn(f"{path.name}: plate {i + 1} never sees a load (max vertical force {peak:.1f} N)", notes)

        plates.append(
            ForcePlate(
                name=name,
                force_N=force * force_scale,
                moment_Nm=moment * force_scale * length_m,
                centre_m=centre * length_m,
                corners_m=corners * length_m,
                rate_hz=rate_hz,
                plate_type=plate_type,
            )
        )
    return plates


def _kistler_corrected_moment(pf, force, moment, centre, normal, force_scale) -> np.ndarray:
    """Moment about the centre that carries ezc3d's FPCOPPOLY-corrected COP where the plate is loaded.

    ``M = r × F + (Tz · n) n`` with ``r`` = corrected COP − centre; elsewhere ezc3d's moment.
    """
    cop = np.asarray(pf["center_of_pressure"], dtype=float).T
    tz = np.asarray(pf["Tz"], dtype=float).T @ normal
    loaded = (np.abs(force_scale * force @ normal) > LOAD_THRESHOLD_N) & np.isfinite(cop).all(axis=1)
    rebuilt = np.cross(np.nan_to_num(cop - centre), force) + np.nan_to_num(tz)[:, None] * normal
    return np.where(loaded[:, None], rebuilt, moment)


def _zero_baseline(params, index, force, moment, normal, n_samples, n_frames, force_scale, plate_type):
    """Subtract the FORCE_PLATFORM:ZERO frame range mean (types 2-4); returns (moment, force, note)."""
    zero = np.asarray(_param(params, "FORCE_PLATFORM", "ZERO", []), dtype=int).ravel()
    if zero.size < 2 or plate_type == 1:
        return moment, force, ""
    first, last = int(zero[0]), int(zero[1])
    if first < 1 or last < first or last > n_frames or n_frames == 0:
        return moment, force, ""
    per_frame = n_samples // n_frames
    window = slice((first - 1) * per_frame, last * per_frame)
    f0 = np.nanmean(force[window], axis=0)
    m0 = np.nanmean(moment[window], axis=0)
    if abs(force_scale * np.dot(f0, normal)) > _BASELINE_MAX_N:
        return moment, force, f"FORCE_PLATFORM:ZERO frames {first}-{last} carry a load; baseline not subtracted"
    size_N = force_scale * np.linalg.norm(f0)
    return moment - m0, force - f0, f"FORCE_PLATFORM:ZERO baseline (frames {first}-{last}, {size_N:.1f} N) subtracted"
