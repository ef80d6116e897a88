"""Segment masses, centres of mass and inertias from de Leva (1996), 3.2.2, or Plug-in Gait's legs.

mass = fraction · body mass; CoM at a fraction of the segment length from the first
(origin) endpoint; I = m (r L)² about each segment axis (upright posture: x forward,
y left, z up; r_sag about x, r_trans about y, r_long about z; the foot, x along it, as
the dissertation: r_long about x, r_sag about y, r_trans about z). Lengths are de Leva's
scaled by stature unless measured (thigh HJC→KJC, shank KJC→AJC from the static trial).

The trunk is split as Table A.4 does: the **pelvis** is de Leva's lower trunk OMPH→MIDH
(lumbosacral joint at OMPH, hips at MIDH); the **HAT** is head, upper and middle trunk
and both arms crossed over the chest (upper arms hanging from shoulder centres
:data:`SHOULDER_HALF_WIDTH_PER_STATURE` · H either side, forearms and hands across the
chest at elbow height), its mass the remainder of the body mass. Sources, the reading of
the radii's axes and what this reproduces of Tables A.4–A.5: docs/model_constants.md §1.
The added masses of the experiments are in :mod:`gaitcli.kinematics.disturbances`.

A Plug-in Gait session's legs may take Plug-in Gait's own parameters instead (:data:`PLUG_IN_GAIT_LEGS`), so that
its joint moments are the ones Vicon Nexus reports; docs/model_constants.md §1 says where they come from.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from gaitcli.errors import InputError, shown
from gaitcli.kinematics.model import BODIES


@dataclass(frozen=True)
class DeLevaSegment:
    """One row of de Leva (1996) Table 4: mean length (mm), then percentages."""

    length_mm: float
    mass_pct: float
    com_pct: float  # from the first (origin) endpoint
    r_sag_pct: float
    r_trans_pct: float
    r_long_pct: float


def _rows(values: dict[str, tuple]) -> dict[str, DeLevaSegment]:
    return {k: DeLevaSegment(*v) for k, v in values.items()}


#: de Leva (1996) Table 4 (docs/model_constants.md §1); keys name the endpoints used
DE_LEVA = {
    "male": _rows({
        "head": (242.9, 6.94, 50.02, 30.3, 31.5, 26.1),  # VERT->CERV
        "trunk": (531.9, 43.46, 44.86, 37.2, 34.7, 19.1),  # SUPR->MIDH
        "trunk_cerv": (603.3, 43.46, 51.38, 32.8, 30.6, 16.9),  # CERV->MIDH
        "trunk_mids": (515.5, 43.46, 43.10, 38.4, 35.8, 19.7),  # MIDS->MIDH
        "upper_trunk": (170.7, 15.96, 29.99, 71.6, 45.4, 65.9),  # SUPR->XYPH
        "middle_trunk": (215.5, 16.33, 45.02, 48.2, 38.3, 46.8),  # XYPH->OMPH
        "lower_trunk": (145.7, 11.17, 61.15, 61.5, 55.1, 58.7),  # OMPH->MIDH
        "upper_arm": (281.7, 2.71, 57.72, 28.5, 26.9, 15.8),  # SJC->EJC
        "forearm": (268.9, 1.62, 45.74, 27.6, 26.5, 12.1),  # EJC->WJC
        "hand": (86.2, 0.61, 79.00, 62.8, 51.3, 40.1),  # WJC->MET3
        "thigh": (422.2, 14.16, 40.95, 32.9, 32.9, 14.9),  # HJC->KJC
        "shank": (440.3, 4.33, 43.95, 25.1, 24.6, 10.2),  # KJC->AJC
        "shank_lmal": (434.0, 4.33, 44.59, 25.5, 24.9, 10.3),  # KJC->LMAL
        "foot": (258.1, 1.37, 44.15, 25.7, 24.5, 12.4),  # HEEL->TTIP
    }),
    "female": _rows({
        "head": (243.7, 6.68, 48.41, 27.1, 29.5, 26.1),
        "trunk": (529.3, 42.57, 41.51, 35.7, 33.9, 17.1),
        "trunk_cerv": (614.8, 42.57, 49.64, 30.7, 29.2, 14.7),
        "trunk_mids": (497.9, 42.57, 37.82, 37.9, 36.1, 18.2),
        "upper_trunk": (142.5, 15.45, 20.77, 74.6, 50.2, 71.8),
        "middle_trunk": (205.3, 14.65, 45.12, 43.3, 35.4, 41.5),
        "lower_trunk": (181.5, 12.47, 49.20, 43.3, 40.2, 44.4),
        "upper_arm": (275.1, 2.55, 57.54, 27.8, 26.0, 14.8),
        "forearm": (264.3, 1.38, 45.59, 26.1, 25.7, 9.4),
        "hand": (78.0, 0.56, 74.74, 53.1, 45.4, 33.5),
        "thigh": (368.5, 14.78, 36.12, 36.9, 36.4, 16.2),
        "shank": (438.6, 4.81, 43.52, 26.7, 26.3, 9.2),
        "shank_lmal": (432.3, 4.81, 44.16, 27.1, 26.7, 9.3),
        "foot": (228.3, 1.29, 40.14, 29.9, 27.9, 13.9),
    }),
}
REFERENCE_STATURE_M = {"male": 1.741, "female": 1.735}
#: the tables a subject's segments may come from (subject.yaml's ``segment_inertias``)
SEGMENT_TABLES = ("de_leva", "plug_in_gait")


@dataclass(frozen=True)
class PlugInGaitSegment:
    """One leg segment as Plug-in Gait computes its kinetics: percentages of body mass and of segment length."""

    mass_pct: float
    com_pct: float  # from the proximal joint centre (the foot: from the ankle centre towards the toe marker)
    radius_pct: float  # radius of gyration about the CoM, both transverse axes; none about the long axis


#: Plug-in Gait's legs as Vicon Nexus computes their kinetics: Dempster's masses and CoMs; as the radius about the
#: CoM, Dempster's radius about the proximal end for thigh and foot and about the CoM for the shank, the radii that
#: reproduce Vicon's own moments in ../shared/data/pig (benchmarks/fit_pig_inertias.py; docs/model_constants.md §1)
PLUG_IN_GAIT_LEGS = {"thigh": PlugInGaitSegment(10.0, 43.3, 54.0), "shank": PlugInGaitSegment(4.65, 43.3, 30.2),
                     "foot": PlugInGaitSegment(1.45, 50.0, 69.0)}
#: shoulder joint centres either side of the midline, as a fraction of stature (fits Table A.4)
SHOULDER_HALF_WIDTH_PER_STATURE = 0.112


@dataclass(frozen=True, eq=False)
class SegmentInertia:
    """Mass geometry of one body in some axes (segment or body axes; SI units).

    ``com_m`` is the CoM relative to the landmark ``origin`` (de Leva's first
    endpoint: OMPH for pelvis and HAT, HJC, KJC, HEEL), ``inertia_kgm2`` the 3×3
    tensor about the CoM, ``axis`` the unit vector from ``origin`` along the segment
    towards its other end, ``length_m`` the segment length.
    """

    mass_kg: float
    com_m: np.ndarray
    inertia_kgm2: np.ndarray
    length_m: float
    axis: np.ndarray
    origin: str
    notes: tuple[str, ...] = ()


def normalise_sex(sex: str) -> str:
    key = str(sex).strip().lower()
    key = {"m": "male", "f": "female"}.get(key, key)
    if key not in DE_LEVA:
        raise InputError(None, "sex", f"got {shown(sex)} (expected 'male' or 'female')")
    return key


def _positive(value, name: str) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InputError(None, name, f"got {shown(value)} (expected a number > 0)") from None
    if not np.isfinite(v) or v <= 0:
        raise InputError(None, name, f"got {shown(value)} (expected a number > 0)")
    return v


def _per_side(value, name: str) -> tuple[float | None, float | None]:
    """A length given once for both sides or as (right, left); ``None`` = not measured."""
    if value is None:
        return None, None
    if np.ndim(value) == 0:
        v = _positive(value, name)
        return v, v
    right, left = value
    return (None if right is None else _positive(right, name),
            None if left is None else _positive(left, name))


def principal_inertia(mass_kg: float, length_m: float, radii_pct) -> np.ndarray:
    """Diagonal inertia ``m (r L)²`` about the CoM from radii of gyration in % of L."""
    r = np.asarray(radii_pct, dtype=float) / 100.0 * length_m
    return np.diag(mass_kg * r ** 2)


def parallel_axis(mass_kg: float, offset_m) -> np.ndarray:
    """Steiner term ``m (|r|² E − r rᵀ)`` for a point mass at ``offset_m``."""
    r = np.asarray(offset_m, dtype=float)
    return mass_kg * (r @ r * np.eye(3) - np.outer(r, r))


def _hat(table: dict[str, DeLevaSegment], mass_kg: float, scale: float, shoulder_half_width_m: float,
         hat_mass_kg: float) -> SegmentInertia:
    """HAT composite about the lumbar joint (OMPH, origin), arms crossed over the chest."""
    L = {k: row.length_mm / 1000.0 * scale for k, row in table.items()}
    c = {k: row.com_pct / 100.0 for k, row in table.items()}
    z_xyph = L["middle_trunk"]
    z_supr = z_xyph + L["upper_trunk"]
    z_cerv = z_supr + (L["trunk_cerv"] - L["trunk"])
    z_mids = z_supr - (L["trunk"] - L["trunk_mids"])
    z_elbow = z_mids - L["upper_arm"]
    z_vert = z_cerv + L["head"]
    parts = []  # (key, CoM position, long axis: 'z' upright, 'y' horizontal across the chest)
    parts.append(("middle_trunk", [0.0, 0.0, z_xyph - c["middle_trunk"] * L["middle_trunk"]], "z"))
    parts.append(("upper_trunk", [0.0, 0.0, z_supr - c["upper_trunk"] * L["upper_trunk"]], "z"))
    parts.append(("head", [0.0, 0.0, z_vert - c["head"] * L["head"]], "z"))
    for sign in (1.0, -1.0):  # left, right; each forearm reaches across to the other side
        w = shoulder_half_width_m
        parts.append(("upper_arm", [0.0, sign * w, z_mids - c["upper_arm"] * L["upper_arm"]], "z"))
        parts.append(("forearm", [0.0, sign * (w - c["forearm"] * L["forearm"]), z_elbow], "y"))
        parts.append(("hand", [0.0, sign * (w - L["forearm"] - c["hand"] * L["hand"]), z_elbow], "y"))
    parts_mass = sum(table[k].mass_pct for k, _, _ in parts) / 100.0 * mass_kg
    ratio = hat_mass_kg / parts_mass  # the remainder vs. the sum of de Leva parts (1 for males)
    masses = [table[k].mass_pct / 100.0 * mass_kg * ratio for k, _, _ in parts]
    positions = [np.asarray(p, dtype=float) for _, p, _ in parts]
    com = sum(m * p for m, p in zip(masses, positions)) / hat_mass_kg
    inertia = np.zeros((3, 3))
    for (k, _, long_axis), m, p in zip(parts, masses, positions):
        row = table[k]
        radii = (row.r_sag_pct, row.r_trans_pct, row.r_long_pct)
        if long_axis == "y":  # forearm/hand across the chest: long axis y, flexion axis x
            radii = (row.r_trans_pct, row.r_long_pct, row.r_sag_pct)
        inertia += principal_inertia(m, L[k], radii) + parallel_axis(m, p - com)
    return SegmentInertia(hat_mass_kg, com, inertia, z_vert, np.array([0.0, 0.0, 1.0]), "OMPH",
                          ("HAT: head, upper and middle trunk, arms crossed over the chest "
                           f"(shoulder joint centres ±{shoulder_half_width_m:.3f} m)",))


def plug_in_gait_limb(key: str, mass_kg: float, length_m: float, axis: np.ndarray, origin: str,
                      how: str) -> SegmentInertia:
    """A thigh, shank or foot by :data:`PLUG_IN_GAIT_LEGS`: ``length_m`` from ``origin`` along ``axis`` (unit)."""
    row = PLUG_IN_GAIT_LEGS[key]
    m = row.mass_pct / 100.0 * mass_kg
    axis = np.asarray(axis, dtype=float)
    inertia = m * (row.radius_pct / 100.0 * length_m) ** 2 * (np.eye(3) - np.outer(axis, axis))
    return SegmentInertia(m, row.com_pct / 100.0 * length_m * axis, inertia, length_m, axis, origin,
                          (f"{key} length {length_m:.4f} m ({how}), Plug-in Gait's mass, CoM and radius",))


def segment_parameters(mass_kg: float, stature_m: float, sex: str = "male", *,
                       thigh_length_m=None, shank_length_m=None, foot_length_m=None,
                       shoulder_width_m: float | None = None, legs: str = "de_leva") -> dict[str, SegmentInertia]:
    """Mass, CoM and inertia of the 8 bodies in segment axes of the upright posture (3.2.2).

    Parameters
    ----------
    mass_kg, stature_m : float
        Body mass (kg) and stature (m).
    sex : str
        ``"male"`` or ``"female"`` (``"m"``, ``"f"``): which of de Leva's tables.
    thigh_length_m, shank_length_m, foot_length_m : float or (float, float), optional
        Measured HJC–KJC, KJC–AJC and heel–toe-tip lengths, m, for both sides or (right, left);
        None: de Leva's mean length × stature / reference stature.
    shoulder_width_m : float, optional
        Distance between the shoulder joint centres, m (default 2 × 0.112 × stature).
    legs : str
        ``"de_leva"`` or ``"plug_in_gait"`` (:data:`PLUG_IN_GAIT_LEGS`; its foot here runs from the heel along
        the foot, :func:`~gaitcli.kinematics.calibration.calibrate` places it between ankle centre and toe).

    Returns
    -------
    dict of str to SegmentInertia
        In :data:`BODIES` order; the HAT mass is the remainder, so the masses sum to ``mass_kg`` exactly.
    """
    mass_kg = _positive(mass_kg, "mass_kg")
    stature_m = _positive(stature_m, "stature_m")
    sex = normalise_sex(sex)
    if legs not in SEGMENT_TABLES:
        raise ValueError(f"legs: {legs!r} (expected one of {SEGMENT_TABLES})")
    table = DE_LEVA[sex]
    scale = stature_m / REFERENCE_STATURE_M[sex]
    lengths = {"thigh": _per_side(thigh_length_m, "thigh_length_m"),
               "shank": _per_side(shank_length_m, "shank_length_m"),
               "foot": _per_side(foot_length_m, "foot_length_m")}
    half_width = (SHOULDER_HALF_WIDTH_PER_STATURE * stature_m if shoulder_width_m is None
                  else _positive(shoulder_width_m, "shoulder_width_m") / 2)
    down, forward = np.array([0.0, 0.0, -1.0]), np.array([1.0, 0.0, 0.0])

    def limb(key: str, measured: float | None, origin: str, axis: np.ndarray) -> SegmentInertia:
        row = table[key]
        L = measured if measured is not None else row.length_mm / 1000.0 * scale
        how = "measured" if measured is not None else "scaled by stature"
        if legs == "plug_in_gait" and key in PLUG_IN_GAIT_LEGS:
            return plug_in_gait_limb(key, mass_kg, L, axis, origin, how)
        m = row.mass_pct / 100.0 * mass_kg
        radii = (row.r_sag_pct, row.r_trans_pct, row.r_long_pct)
        if key == "foot":  # the dissertation's Table A.5 assignment (x along the foot)
            radii = (row.r_long_pct, row.r_sag_pct, row.r_trans_pct)
        return SegmentInertia(m, row.com_pct / 100.0 * L * axis, principal_inertia(m, L, radii), L, axis,
                              origin, (f"{key} length {L:.4f} m ({how})",))

    out: dict[str, SegmentInertia] = {}
    out["pelvis"] = limb("lower_trunk", None, "OMPH", down)
    leg_segments = {}
    for i, s in enumerate(("r", "l")):
        leg_segments[f"thigh_{s}"] = limb("thigh", lengths["thigh"][i], "HJC", down)
        leg_segments[f"shank_{s}"] = limb("shank", lengths["shank"][i], "KJC", down)
        leg_segments[f"foot_{s}"] = limb("foot", lengths["foot"][i], "HEEL", forward)
    hat_mass = mass_kg - out["pelvis"].mass_kg - sum(seg.mass_kg for seg in leg_segments.values())
    out["hat"] = _hat(table, mass_kg, scale, half_width, hat_mass)
    out.update(leg_segments)
    return {b: out[b] for b in BODIES}


def rotate_segment(segment: SegmentInertia, rotation) -> SegmentInertia:
    """Express ``segment`` in new axes: ``v_new = rotation @ v_old``, ``I_new = R I Rᵀ``."""
    R = np.asarray(rotation, dtype=float)
    return replace(segment, com_m=R @ segment.com_m, axis=R @ segment.axis,
                   inertia_kgm2=R @ segment.inertia_kgm2 @ R.T)
