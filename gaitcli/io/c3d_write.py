"""C3D writer: markers in mm and force plates as FORCE_PLATFORM TYPE 2 (Fx, Fy, Fz, Mx, My, Mz).

Conventions, chosen so that :func:`gaitcli.io.c3d.read_c3d` (and ezc3d's or
OpenSim's plate extraction) return the input wrench exactly:

* Lab axes: ``v_lab = model_to_lab @ v_model`` (identity by default).
* Corners (mm) in C3D order: with ``x = c1 - c2`` and ``y = c1 - c4`` the plate
  axis ``z = x × y`` points into the floor. Corners given in the opposite
  order are written as ``c1, c4, c3, c2``.
* ORIGIN (mm, plate axes) per the C3D specification: the vector from the
  centre of the plate's top surface to the transducer origin. With the plate z
  pointing into the floor a transducer below the surface has ORIGIN z > 0
  (Vicon writes 37.84 mm and 57.15 mm for the AMTI plates of walking2.c3d);
  ezc3d reads a positive-z ORIGIN as its negative, the origin → surface vector.
* Channels: the force the ground exerts on the subject in plate axes (N), and
  its moment about the transducer origin (N·mm),
  ``M_origin = M_centre + F × ORIGIN``. This is what Vicon, Qualisys, BTS and
  the c3d.org samples store: ezc3d's ``force`` is then the ground reaction
  (vertical positive under load) and its ``moment`` the moment about the
  surface centre.
* Analog rate = an integer multiple of the point rate (all plates at one rate).
* Missing marker samples (NaN) are written as ezc3d's missing convention:
  (0, 0, 0) with residual -1. Coordinates are stored as float32.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Mapping
from pathlib import Path

import ezc3d
import numpy as np

from gaitcli.core.events import Events
from gaitcli.core.recording import Analogs, ForcePlate, Markers
from gaitcli.errors import GaitWarning, InputError
from gaitcli.io.atomic import atomic_path
from gaitcli.io.c3d import plate_axes
from gaitcli.io.c3d.events import EVENT_CONTEXTS, EVENT_LABELS
from gaitcli.io.c3d.header import as_text
from gaitcli.io.c3d.long import write_frame_count

__all__ = ["write_c3d", "add_points", "set_events", "DEFAULT_ORIGIN_MM"]

DEFAULT_ORIGIN_MM = (2.0, -1.5, 40.0)
"""Surface centre → transducer origin (mm, plate axes, z into the floor), AMTI-like."""


def _check_rotation(path: Path, R) -> np.ndarray:
    R = np.eye(3) if R is None else np.asarray(R, dtype=float)
    if R.shape != (3, 3) or not np.allclose(R @ R.T, np.eye(3), atol=1e-9) or np.linalg.det(R) < 0:
        raise InputError(path, "model_to_lab", "expected a proper 3x3 rotation matrix")
    return R


def write_c3d(
    path,
    markers: Markers,
    plates: list[ForcePlate],
    *,
    model_to_lab=None,
    origin_mm=DEFAULT_ORIGIN_MM,
    metadata: Mapping[str, float] | None = None,
    analogs: Analogs | None = None,
) -> Path:
    """Write markers (model axes, metres) and plates (model axes, SI) to a C3D file; return its path.

    ``origin_mm``: ORIGIN of every plate (surface centre → transducer origin in
    plate axes, mm). ``metadata``: subject parameters ``{"GROUP:NAME": number}`` (e.g.
    ``PROCESSING:RightKneeWidth`` in mm, as Vicon writes them). ``analogs``: further channels (EMG) after the
    plates', at the plates' analog rate, in their own units. The file appears atomically.
    """
    path = Path(path)
    R = _check_rotation(path, model_to_lab)
    n_frames = markers.n_frames
    point_rate = float(markers.rate_hz)
    up_lab = R @ np.array([0.0, 0.0, 1.0])

    positions_mm = np.asarray(markers.positions_m, dtype=float) @ R.T * 1000.0  # (frames, markers, 3)
    missing = ~np.isfinite(positions_mm).all(axis=2)
    points = np.ones((4, len(markers.labels), n_frames))
    points[:3] = np.transpose(np.where(missing[..., None], 0.0, positions_mm), (2, 1, 0))
    residuals = np.where(missing.T, -1.0, 0.0)[None]

    c = ezc3d.c3d()
    params = c["parameters"]
    params["POINT"]["RATE"]["value"] = np.array([point_rate])
    params["POINT"]["LABELS"]["value"] = list(markers.labels)
    params["POINT"]["DESCRIPTIONS"]["value"] = [""] * len(markers.labels)
    params["POINT"]["UNITS"]["value"] = ["mm"]
    c["header"]["points"]["first_frame"] = int(markers.first_frame) - 1
    c["data"]["points"] = points
    c["data"]["meta_points"]["residuals"] = residuals
    c["data"]["meta_points"]["camera_masks"] = np.zeros((7, len(markers.labels), n_frames), dtype=bool)

    if plates:
        plate_analogs, analog_rate, corners, origins = _plate_channels(
            path, plates, R, up_lab, n_frames, point_rate, np.asarray(origin_mm, dtype=float))
        n = len(plates)
        labels = [f"{c}{k + 1}" for k in range(n) for c in ("Fx", "Fy", "Fz", "Mx", "My", "Mz")]
        params["ANALOG"]["RATE"]["value"] = np.array([analog_rate])
        params["ANALOG"]["LABELS"]["value"] = labels
        params["ANALOG"]["DESCRIPTIONS"]["value"] = [f"force plate {k + 1}" for k in range(n) for _ in range(6)]
        params["ANALOG"]["UNITS"]["value"] = ["N", "N", "N", "Nmm", "Nmm", "Nmm"] * n
        params["ANALOG"]["SCALE"]["value"] = np.ones(6 * n)
        params["ANALOG"]["OFFSET"]["value"] = np.zeros(6 * n, dtype=int)
        fp = params["FORCE_PLATFORM"]
        fp["USED"]["value"] = np.array([n])
        fp["TYPE"]["value"] = np.full(n, 2, dtype=int)
        fp["ZERO"]["value"] = np.array([0, 0])
        fp["CORNERS"]["value"] = corners
        fp["ORIGIN"]["value"] = origins
        fp["CHANNEL"]["value"] = np.arange(1, 6 * n + 1, dtype=int).reshape(n, 6).T
        c["data"]["analogs"] = plate_analogs
    else:
        params["ANALOG"]["RATE"]["value"] = np.array([point_rate if analogs is None else analogs.rate_hz])
        c["data"]["analogs"] = np.zeros((1, 0, n_frames if analogs is None else analogs.n_samples))
    if analogs is not None:
        _append_analogs(path, c, analogs)

    for key, value in (metadata or {}).items():
        group, name = key.split(":")
        c.add_parameter(group, name, [float(value)])
    write_frame_count(c, n_frames)  # more than 65 535 frames: the TRIAL fields hold the count
    return _write_atomically(c, path)


def _append_analogs(path: Path, c, analogs: Analogs) -> None:
    """``analogs``' channels after those already in ``c`` (same rate and samples), labels and units with them."""
    params = c["parameters"]["ANALOG"]
    rate = float(np.asarray(params["RATE"]["value"]).ravel()[0])
    data = c["data"]["analogs"]
    if data.shape[1] and (analogs.rate_hz != rate or analogs.n_samples != data.shape[2]):
        raise InputError(path, "analogs", f"{analogs.n_samples} samples at {analogs.rate_hz:g} Hz (expected the "
                                          f"plates' {data.shape[2]} at {rate:g} Hz)")
    count = data.shape[1]
    for name, values in (("LABELS", analogs.labels), ("DESCRIPTIONS", ("EMG",) * len(analogs.labels)),
                         ("UNITS", analogs.units)):
        before = list(params[name]["value"]) if count else []
        params[name]["value"] = before + list(values)
    params["SCALE"]["value"] = np.concatenate([np.ravel(params["SCALE"]["value"])[:count],
                                               np.ones(len(analogs.labels))])
    params["OFFSET"]["value"] = np.concatenate([np.ravel(params["OFFSET"]["value"])[:count],
                                                np.zeros(len(analogs.labels))]).astype(int)
    c["data"]["analogs"] = np.concatenate([data, analogs.values.T[None]], axis=1)


def _plate_channels(path, plates, R, up_lab, n_frames, point_rate, origin_mm):
    """Analog array (1, 6 n, samples), analog rate, CORNERS (3, 4, n) and ORIGIN (3, n) in mm."""
    rates = {float(p.rate_hz) for p in plates}
    if len(rates) != 1:
        raise InputError(path, "plates", f"plates at different rates {sorted(rates)} (expected one analog rate)")
    analog_rate = rates.pop()
    ratio = analog_rate / point_rate
    if ratio < 1 or abs(ratio - round(ratio)) > 1e-9:
        raise InputError(path, "plates", f"analog rate {analog_rate} Hz is not an integer multiple of {point_rate} Hz")
    n_samples = n_frames * int(round(ratio))
    channels, corners, origins = [], [], []
    for plate in plates:
        if plate.n_samples != n_samples:
            raise InputError(path, plate.name, f"{plate.n_samples} samples (expected {n_samples} = frames x {ratio:g})")
        c_lab = np.asarray(plate.corners_m, dtype=float) @ R.T * 1000.0
        axes = plate_axes(c_lab)
        if np.dot(axes[:, 2], up_lab) > 0:  # plate z must point into the floor
            c_lab = c_lab[[0, 3, 2, 1]]
            axes = plate_axes(c_lab)
        centre_lab = R @ np.asarray(plate.centre_m, dtype=float) * 1000.0
        if not np.allclose(centre_lab, c_lab.mean(axis=0), atol=1e-3):
            raise InputError(path, plate.name, "centre_m is not the mean of corners_m")
        f_plate = np.asarray(plate.force_N, dtype=float) @ R.T @ axes  # rows: R_p^T F
        m_plate = np.asarray(plate.moment_Nm, dtype=float) @ R.T @ axes * 1000.0
        m_origin = m_plate + np.cross(f_plate, origin_mm)
        channels.append(np.concatenate([f_plate, m_origin], axis=1).T)
        corners.append(c_lab.T)
        origins.append(origin_mm)
    analogs = np.concatenate(channels, axis=0)[None]
    return analogs, analog_rate, np.stack(corners, axis=2), np.stack(origins, axis=1)


def add_points(source, target, points: Mapping[str, np.ndarray], *, descriptions: Mapping[str, str] | None = None,
               parameters: Mapping[str, object] | None = None, events: Events | None = None,
               merged: tuple[str, ...] = ()) -> Path:
    """A copy of the C3D file ``source`` at ``target`` with ``points`` ({label: (frames, 3)}, in the units the
    caller names in ``parameters``) in it: a label the file already holds is replaced in place (one label each,
    warned, naming them), the others appended after its own points. Its other points, analogs and parameters stay
    as they were (text parameters in a form the C3D library writes: :func:`writable_text_parameters`; more than
    255 labels or descriptions continue in ``LABELS2``, ``DESCRIPTIONS2``, … as the C3D format has it).
    NaN rows become invalid points (residual −1). ``parameters``: {"GROUP:NAME": value} added or replaced
    (e.g. ``POINT:ANGLE_UNITS``, ``POINT:ANGLES``); for a key in ``merged`` a list value is appended to the file's
    own list instead (its entries kept, none twice). ``events`` (times in s from the file's first frame), where
    given, replace its EVENT group (:func:`set_events`). Written atomically."""
    source, target = Path(source), Path(target)
    c = ezc3d.c3d(str(source), extract_forceplat_data=False)
    writable_text_parameters(c, source)
    analog_lists_per_channel(c)
    data = c["data"]["points"]
    n_old, n_frames = data.shape[1], data.shape[2]
    point = c["parameters"]["POINT"]
    old_labels = [lab.strip() for lab in _point_texts(point, "LABELS")][:n_old]
    old_labels += [""] * (n_old - len(old_labels))
    old_descriptions = _point_texts(point, "DESCRIPTIONS")[:n_old]
    old_descriptions += [""] * (n_old - len(old_descriptions))
    replaced = [lab for lab in points if lab in old_labels]
    appended = [lab for lab in points if lab not in old_labels]
    n = n_old + len(appended)
    values = np.concatenate([data, np.ones((4, len(appended), n_frames))], axis=1)
    residuals = np.concatenate([c["data"]["meta_points"]["residuals"], np.zeros((1, len(appended), n_frames))],
                               axis=1)
    masks = c["data"]["meta_points"]["camera_masks"]
    masks = np.concatenate([masks, np.zeros((masks.shape[0], len(appended), n_frames), bool)], axis=1)
    labels, texts = old_labels + appended, old_descriptions + [""] * len(appended)
    for label, given in points.items():
        given = np.asarray(given, float)
        if given.shape != (n_frames, 3):
            raise ValueError(f"{label}: {given.shape} values for a file of {n_frames} frames")
        j = labels.index(label)
        missing = ~np.isfinite(given).all(axis=1)
        values[:3, j] = np.where(missing[:, None], 0.0, given).T
        values[3, j] = 1.0
        residuals[0, j] = np.where(missing, -1.0, 0.0)
        masks[:, j] = False
        texts[j] = (descriptions or {}).get(label, "")
    c["data"]["points"] = values
    c["data"]["meta_points"]["residuals"] = residuals
    c["data"]["meta_points"]["camera_masks"] = masks
    _set_point_texts(c, "LABELS", labels)
    _set_point_texts(c, "DESCRIPTIONS", texts)
    point["USED"]["value"] = np.array([n])
    for key, value in (parameters or {}).items():
        group, name = key.split(":")
        value = value if isinstance(value, list) else [value]
        if key in merged and name in c["parameters"].get(group, {}):
            own = c["parameters"][group][name]["value"]
            own = [v.strip() for v in own] if isinstance(own, list) else []
            value = own + [v for v in value if v not in own]
        c.add_parameter(group, name, value)
    if events is not None:
        set_events(c, events)
    if replaced:
        warnings.warn(f"{source.name}: its own points {', '.join(replaced)} are replaced by the new ones in the copy "
                      f"{target.name} (one label each)", GaitWarning, stacklevel=2)
    return _write_atomically(c, target)


#: entries per C3D text parameter: its count is one byte, so more continue in NAME2, NAME3, …
C3D_MAX_ENTRIES = 255


def _point_texts(point, name: str) -> list[str]:
    """POINT:NAME followed by NAME2, NAME3, … (more than 255 points)."""
    out, k = list(point.get(name, {}).get("value", [])), 2
    while f"{name}{k}" in point:
        out += list(point[f"{name}{k}"]["value"])
        k += 1
    return out


def _set_point_texts(c, name: str, values: list[str]) -> None:
    """Write POINT:NAME as NAME, NAME2, … of at most 255 entries each, removing any stale continuation."""
    point = c["parameters"]["POINT"]
    k = 2
    while f"{name}{k}" in point:
        del point[f"{name}{k}"]
        k += 1
    chunks = [values[i:i + C3D_MAX_ENTRIES] for i in range(0, max(len(values), 1), C3D_MAX_ENTRIES)]
    for k, chunk in enumerate(chunks):
        c.add_parameter("POINT", name if k == 0 else f"{name}{k + 1}", list(chunk))


def set_events(c, events: Events) -> None:
    """Replace the EVENT group of the ezc3d object ``c`` by ``events`` (times in s from its first frame) as Vicon
    Nexus writes them: LABELS "Foot Strike"/"Foot Off", CONTEXTS "Right"/"Left", TIMES (2, n) minutes and
    seconds from the recording's frame 1 (the first frame at ``(first - 1) / rate``), DESCRIPTIONS the source."""
    rate = float(np.asarray(c["parameters"]["POINT"]["RATE"]["value"]).ravel()[0])
    start_s = int(c["header"]["points"]["first_frame"]) / rate  # ezc3d's first frame is 0-based
    if "EVENT" in c["parameters"]:
        del c["parameters"]["EVENT"]
    c.add_parameter("EVENT", "USED", len(events))
    if not len(events):
        return
    t = np.asarray(events.time_s, float) + start_s
    minutes = np.floor(t / 60.0)
    c.add_parameter("EVENT", "LABELS", [EVENT_LABELS[k] for k in events.kind])
    c.add_parameter("EVENT", "CONTEXTS", [EVENT_CONTEXTS[s] for s in events.side])
    c.add_parameter("EVENT", "TIMES", np.vstack([minutes, t - 60.0 * minutes]))
    c.add_parameter("EVENT", "DESCRIPTIONS", [f"gaitcli ({s})" for s in events.source])
    c.add_parameter("EVENT", "SUBJECTS", [""] * len(events))


def writable_text_parameters(c, source: Path) -> None:
    """Make every text parameter copied from ``source`` a list of strings the C3D library can write.

    ezc3d hands bytes that are not UTF-8 over as surrogate escapes (a Latin-1 'µ' in "µV" as '\\udcb5'), which
    it then cannot write back ("Value in parameters ANALOG:UNITS could not be converted to string"): such text
    is read as Latin-1. A text parameter holding anything else that is not a string is left out (warned).
    """
    params = c["parameters"]
    for group in list(params):
        for name in [n for n in params[group] if n != "__METADATA__"]:
            entry = params[group][name]
            if entry.get("type") != -1:
                continue
            value = entry["value"]
            if isinstance(value, (list, tuple)) and all(isinstance(v, str) for v in value):
                entry["value"] = [as_text(v) for v in value]
            else:
                del params[group][name]
                warnings.warn(f"{source.name}: {group}:{name} left out of the copy (text parameter with values "
                              f"that are not text: {str(value)[:40]})", GaitWarning, stacklevel=3)


#: ANALOG parameters with one entry per channel, and what a missing entry becomes
ANALOG_CHANNEL_LISTS = {"LABELS": "", "DESCRIPTIONS": "", "UNITS": "", "SCALE": 1.0, "OFFSET": 0, "GAIN": 0}


def analog_lists_per_channel(c) -> None:
    """Cut or pad the ANALOG lists of one entry per channel to the channels the file stores, as the C3D library
    insists on writing them: the c3d.org samples (Eb015pr.c3d, dec_real.c3d) describe 32 channels and store 16
    (ANALOG:USED 16). A padded label is ``A<k>`` (1-based)."""
    analog = c["parameters"].get("ANALOG", {})
    n = int(c["data"]["analogs"].shape[1])
    for name, fill in ANALOG_CHANNEL_LISTS.items():
        if name not in analog:
            continue
        value = analog[name]["value"]
        if len(value) == n or (name == "GAIN" and len(value) == 0):
            continue
        if isinstance(value, list):
            value = value[:n] + [f"A{k + 1}" if name == "LABELS" else fill for k in range(len(value), n)]
        else:
            value = np.concatenate([np.asarray(value)[:n], np.full(max(0, n - len(value)), fill,
                                                                   dtype=np.asarray(value).dtype)])
        analog[name]["value"] = value


def _write_atomically(c, path: Path) -> Path:
    """Write the ezc3d object ``c`` to ``path`` atomically (whole or not at all)."""
    with atomic_path(path) as tmp:
        staging = tmp.with_name(tmp.name + ".c3d")  # ezc3d appends .c3d to any other name
        try:
            c.write(str(staging))
            os.replace(staging, tmp)
        finally:
            if staging.exists():
                staging.unlink()
    return path
