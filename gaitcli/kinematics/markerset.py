"""The dissertation's marker set (Table A.6), which body each marker tracks, and lab-label mapping.

Model landmark names are the dissertation's designations with a side suffix
(``ASISr``, ``PSISl``, ``GTr``, ...), the two midline markers ``C7`` and ``ST``,
and the virtual joint centres ``HJCr``, ``KJCr``, ``AJCr`` (and ``l``) that lab
exports (Plug-in Gait, CGM) may provide and that then replace the estimates of
:mod:`gaitcli.kinematics.joint_centres`.

Which markers track which body follows the anatomy of Table A.6 / Fig. A.2
(the dissertation gives no explicit list; this is the assignment its 28 markers
imply): pelvis ASIS, PSIS; thigh GT, MRF, LEF, MEF; shank TT, LM, MM; foot CA,
VM, FM; HAT C7, ST, ACr, ACl. 4 + 2×(4 + 3 + 3) + 4 = 28 markers.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np

from gaitcli.core.validate import one_of
from gaitcli.errors import InputError
from gaitcli.kinematics.model import BODIES
from gaitcli.core.recording import Markers

SIDES = ("r", "l")

BILATERAL = ("VM", "FM", "LM", "MM", "CA", "TT", "LEF", "MEF", "MRF", "GT", "ASIS", "PSIS", "AC")
MIDLINE = ("C7", "ST")

#: the 28 markers of Table A.6 as model landmark names
MARKERS = tuple(f"{d}{s}" for d in BILATERAL for s in SIDES) + MIDLINE
VIRTUAL_JOINT_CENTRES = ("HJCr", "HJCl", "KJCr", "KJCl", "AJCr", "AJCl")
LANDMARKS = MARKERS + VIRTUAL_JOINT_CENTRES

_SEGMENT_DESIGNATIONS = {"thigh": ("GT", "MRF", "LEF", "MEF"), "shank": ("TT", "LM", "MM"), "foot": ("CA", "VM", "FM")}

#: body -> Table A.6 markers fixed to it (the tracking cluster of the SVD pose fit)
SEGMENT_MARKERS: dict[str, tuple[str, ...]] = {
    "pelvis": ("ASISr", "ASISl", "PSISr", "PSISl"),
    "hat": ("C7", "ST", "ACr", "ACl"),
    **{f"{seg}_{s}": tuple(d + s for d in des) for s in SIDES for seg, des in _SEGMENT_DESIGNATIONS.items()},
}
assert sorted(SEGMENT_MARKERS) == sorted(BODIES)
assert sum(len(v) for v in SEGMENT_MARKERS.values()) == len(MARKERS) == 28

#: virtual joint centre -> the two bodies it belongs to (parent, child)
JOINT_CENTRE_BODIES = {
    **{f"HJC{s}": ("pelvis", f"thigh_{s}") for s in SIDES},
    **{f"KJC{s}": (f"thigh_{s}", f"shank_{s}") for s in SIDES},
    **{f"AJC{s}": (f"shank_{s}", f"foot_{s}") for s in SIDES},
}


def tracking_landmarks(body: str) -> tuple[str, ...]:
    """Landmarks that may track ``body``: its Table A.6 markers, then adjacent virtual joint centres.

    A virtual joint centre exported by the lab is fixed in both bodies it joins, so it
    takes part in both clusters when present (needed for marker sets like Plug-in Gait
    that have only two skin markers on the thigh).
    """
    extra = tuple(jc for jc, bodies in JOINT_CENTRE_BODIES.items() if body in bodies)
    return SEGMENT_MARKERS[body] + extra


def body_of_marker(landmark: str) -> str:
    """The body a Table A.6 marker is fixed to."""
    for body, labels in SEGMENT_MARKERS.items():
        if landmark in labels:
            return body
    raise KeyError(landmark)


def required_landmarks(*, virtual_joint_centres: tuple[str, ...] | frozenset = ()) -> tuple[str, ...]:
    """Landmarks a static trial must contain to define the model's geometry.

    Hip centres need ASIS and PSIS (Bell), knee centres LEF and MEF, ankle centres LM
    and MM, the foot CoM CA, VM and FM. A virtual joint centre in
    ``virtual_joint_centres`` removes the markers needed only for that centre (the
    pelvis markers stay: they define the pelvis frame and track it). Markers needed
    only for tracking (GT, MRF, TT, trunk) are not required: a body left with fewer
    than three is locked to its parent.
    """
    virtual = set(virtual_joint_centres)
    needed = ["ASISr", "ASISl", "PSISr", "PSISl"]
    for s in SIDES:
        if f"KJC{s}" not in virtual:
            needed += [f"LEF{s}", f"MEF{s}"]
        if f"AJC{s}" not in virtual:
            needed += [f"LM{s}", f"MM{s}"]
        needed += [f"CA{s}", f"VM{s}", f"FM{s}"]
    return tuple(needed)


def apply_marker_map(markers: Markers, marker_map: Mapping[str, str], *,
                     source: str | Path | None = None) -> Markers:
    """Rename lab marker labels to model landmark names.

    ``marker_map`` maps lab label -> model landmark (e.g. ``{"RASI": "ASISr"}``).
    Labels not in the map are kept unchanged (so a file already using the model's
    names needs no map, and extra technical markers stay available). Raises
    :class:`InputError` naming every mapped lab label the file does not have, an
    unknown landmark name, or a resulting duplicate label.
    """
    missing = [lab for lab in marker_map if lab not in markers.labels]
    if missing:
        raise InputError(source, "marker_map",
                         f"labels not in the marker file: {', '.join(missing)} "
                         f"(the file has: {', '.join(markers.labels)})")
    for lab, landmark in marker_map.items():
        one_of(landmark, LANDMARKS, where=f"marker_map.{lab}", path=source)
    new_labels = tuple(marker_map.get(lab, lab) for lab in markers.labels)
    duplicates = sorted({lab for lab in new_labels if new_labels.count(lab) > 1})
    if duplicates:
        raise InputError(source, "marker_map",
                         f"labels {', '.join(duplicates)} occur more than once after mapping")
    return Markers(new_labels, markers.positions_m, markers.rate_hz, markers.first_frame)


def standing_template(stature_m: float, *, with_virtual_joint_centres: bool = False) -> dict[str, np.ndarray]:
    """Plausible landmark positions (m) of a subject standing upright, facing +x, on the floor z = 0.

    Not anthropometric data: a generic layout built from stature ratios (joint
    heights from de Leva segment lengths: ankle 0.039 H, shank 0.2529 H, thigh
    0.2425 H; inter-ASIS width 0.13 H with a level pelvis, hip centres placed by
    Bell 1990) for tests and the synthetic-trial generator. Virtual joint centres
    (midpoints / Bell) are added on request.
    """
    H = float(stature_m)
    pw = 0.13 * H
    z_ankle, z_knee = 0.039 * H, (0.039 + 0.2529) * H
    z_hip = z_knee + 0.2425 * H
    p: dict[str, np.ndarray] = {}
    mid_asis = np.array([0.19 * pw, 0.0, z_hip + 0.30 * pw])
    for s, sign in (("l", 1.0), ("r", -1.0)):
        y = sign * 0.36 * pw  # hip, knee and ankle centres on one vertical line per leg

        def at(x, dy_lateral, z):
            return np.array([x, y + sign * dy_lateral, z])

        p[f"ASIS{s}"] = mid_asis + [0.0, sign * pw / 2, 0.0]
        p[f"PSIS{s}"] = np.array([mid_asis[0] - 0.09 * H, sign * 0.025 * H, mid_asis[2]])
        p[f"GT{s}"] = at(0.0, 0.04 * H, z_hip - 0.01 * H)
        p[f"MRF{s}"] = at(0.05 * H, 0.0, z_knee + 0.6 * (z_hip - z_knee))
        p[f"LEF{s}"] = at(0.0, 0.025 * H, z_knee)
        p[f"MEF{s}"] = at(0.0, -0.025 * H, z_knee)
        p[f"TT{s}"] = at(0.03 * H, 0.0, z_knee - 0.04 * H)
        p[f"LM{s}"] = at(-0.005 * H, 0.02 * H, z_ankle)
        p[f"MM{s}"] = at(0.0, -0.02 * H, z_ankle + 0.006 * H)
        p[f"CA{s}"] = at(-0.045 * H, 0.0, 0.02 * H)
        p[f"FM{s}"] = at(0.07 * H, -0.018 * H, 0.012 * H)
        p[f"VM{s}"] = at(0.06 * H, 0.022 * H, 0.012 * H)
        p[f"AC{s}"] = np.array([-0.01 * H, sign * 0.1 * H, 0.83 * H])
        if with_virtual_joint_centres:
            p[f"HJC{s}"] = at(0.0, 0.0, z_hip)
            p[f"KJC{s}"] = at(0.0, 0.0, z_knee)
            p[f"AJC{s}"] = (p[f"LM{s}"] + p[f"MM{s}"]) / 2
    p["C7"] = np.array([-0.055 * H, 0.0, 0.86 * H])
    p["ST"] = np.array([0.05 * H, 0.0, 0.835 * H])
    return p


def landmarks_to_markers(landmarks: Mapping[str, np.ndarray], *, rate_hz: float = 100.0) -> Markers:
    """Pack landmark positions (each ``(3,)`` or ``(frames, 3)``) into a :class:`Markers`."""
    labels = tuple(landmarks)
    arrays = [np.atleast_2d(np.asarray(landmarks[k], dtype=float)) for k in labels]
    return Markers(labels, np.stack(arrays, axis=1), rate_hz)
