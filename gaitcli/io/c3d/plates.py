"""C3D force platforms: corners, origin, calibration, Kistler correction and baseline.

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

from pathlib import Path

import ezc3d
import numpy as np

from gaitcli.core.recording import ForcePlate, Markers
from gaitcli.errors import InputError
from gaitcli.io.axes import LOAD_THRESHOLD_N
from gaitcli.io.c3d.header import one_line, param, strings, warn
from gaitcli.io.c3d.markers import LENGTH_M

__all__ = ["PLATFORM_SAMPLES", "plate_axes", "platform_outputs", "plates_from"]

_FORCE_N = {"n": 1.0, "nt": 1.0, "newton": 1.0, "newtons": 1.0, "kn": 1e3}
_BASELINE_MAX_N = 100.0
"""A FORCE_PLATFORM:ZERO baseline above this vertical force is a load, not an offset: not applied."""


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
            return LENGTH_M.get(u[len(prefix):])
    return None


def _plate_values(params, name: str, block: int | None, index: int):
    """Values of plate ``index`` in a FORCE_PLATFORM parameter (flat, column-major as stored), or None.

    ``block`` values per plate; None takes the parameter's first dimension (CHANNEL).
    """
    value = param(params, "FORCE_PLATFORM", name)
    if value is None:
        return None
    a = np.asarray(value)
    if block is None:
        block = a.shape[0] if a.ndim >= 2 else a.size
    flat = a.ravel(order="F")
    if flat.size < block * (index + 1):
        return None
    return flat[block * index:block * (index + 1)]


#: what ezc3d's force-platform module gives per plate, sample by sample (each (3, samples)), and once
PLATFORM_SAMPLES = ("force", "moment", "center_of_pressure", "Tz")
PLATFORM_GEOMETRY = ("corners", "origin")


def platform_outputs(c) -> list[dict[str, np.ndarray] | str]:
    """Per plate of FORCE_PLATFORM:USED, ezc3d's force-platform outputs of ``c`` (:data:`PLATFORM_SAMPLES`,
    :data:`PLATFORM_GEOMETRY`) as arrays, or why the module refused the plate."""
    used = param(c["parameters"], "FORCE_PLATFORM", "USED", [0])
    n_used = int(used[0]) if len(used) else 0
    if n_used == 0 or c["data"]["analogs"].shape[1] == 0:
        return []
    out: list[dict[str, np.ndarray] | str] = []
    for i in range(n_used):
        try:
            pf = ezc3d.c3d.PlatForm(ezc3d.ezc3d.ForcePlatform(i, c.c3d_swig))
        except Exception as exc:  # ezc3d raises RuntimeError/ValueError with its own text
            out.append(one_line(exc))
            continue
        out.append({k: np.asarray(pf[k], dtype=float) for k in PLATFORM_SAMPLES + PLATFORM_GEOMETRY})
    return out


def plates_from(path: Path, params, outputs: list[dict[str, np.ndarray] | str], *, frame_rate_hz: float,
                n_frames: int, length_m: float, markers: Markers, notes: list[str]) -> list[ForcePlate]:
    """The usable force plates from ezc3d's force-platform ``outputs`` (:func:`platform_outputs`, over the
    whole trial) in SI units and lab axes; refused or unloaded plates are warned."""
    if not outputs:
        return []
    force_units = param(params, "FORCE_PLATFORM", "UNITS", [])
    force_unit = str(force_units[0]).strip() if len(force_units) else "N"
    if force_unit.lower() not in _FORCE_N:
        raise InputError(path, "FORCE_PLATFORM:UNITS", f"got '{force_unit}' (expected N)")
    force_scale = _FORCE_N[force_unit.lower()]
    types = np.asarray(param(params, "FORCE_PLATFORM", "TYPE", []), dtype=int).ravel()
    analog_units = strings(params, "ANALOG", "UNITS")
    n_samples = next((pf["force"].shape[1] for pf in outputs if not isinstance(pf, str)), 0)
    rate_hz = frame_rate_hz * (n_samples / max(n_frames, 1))
    seen = np.isfinite(markers.positions_m).all(axis=2)
    marker_mean_lab = markers.positions_m[seen].mean(axis=0) / length_m if seen.any() else None

    plates = []
    for i, pf in enumerate(outputs):
        name = f"plate{i + 1}"
        if isinstance(pf, str):
            type_text = f" (TYPE {types[i]})" if i < types.size else ""
            warn(f"{path.name}: plate {i + 1}{type_text} refused: {pf}; supported FORCE_PLATFORM:TYPE 1-4", notes)
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
            warn(f"{path.name}: plate {i + 1} never sees a load (max vertical force {peak:.1f} N)", notes)

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
    zero = np.asarray(param(params, "FORCE_PLATFORM", "ZERO", []), dtype=int).ravel()
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
