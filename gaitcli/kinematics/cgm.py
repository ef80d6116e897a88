"""The Conventional Gait Model (CGM 1.0) as Vicon's Plug-in Gait computes it: segment frames per frame from the
markers and the subject's measurements, and the static offsets of the foot.

Davis et al. (1991) hip centres, the chord method for the knee and ankle centres, Kadaba et al. (1990) segment
axes; the definitions follow Vicon's Plug-in Gait reference guide as the open implementation pyCGM reproduces it.
Positions in m (model axes: x forward, y left, z up); a frame is an (n, 3, 3) rotation whose columns are the
segment's x, y, z axes in model coordinates.

Segment axes (all sides alike): x anterior, y left, z up. Plug-in Gait builds its foot frame with x up, y left
and z from the toe towards the heel (:data:`~gaitcli.kinematics.anatomical.PIG_FOOT_AXES`); it is returned
turned to the common axes, and :func:`~gaitcli.kinematics.anatomical.anatomical_angles` turns it back.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from gaitcli.kinematics.anatomical import PIG_FOOT_AXES
from gaitcli.kinematics.joint_centres import (
    chord_joint_centre,
    davis_hip_joint_centres,
    pelvis_frame,
    shank_frame,
    thigh_frame,
    unit,
)
from gaitcli.kinematics.rotations import rot_x, rot_y, rot_z

SIDES = ("r", "l")
_SIDE_WORDS = {"r": ("R", "Right"), "l": ("L", "Left")}


@dataclass(frozen=True)
class CgmMeasurements:
    """The subject measurements Plug-in Gait takes (m and rad; per side ``{"r": …, "l": …}``).

    ``asis_trochanter_m`` None: Davis's regression 0.1288·LL − 48.56 mm; ``inter_asis_m`` None: measured between
    the ASIS markers. ``thigh_rotation_rad``/``shank_rotation_rad``: Plug-in Gait's rotation offsets, the chord
    planes of the knee and ankle centres turned about the chord from the wands' to the knee alignment device's
    (:func:`kad_rotation_offsets`). ``flat_foot``: the foot's long axis in the static is made horizontal (the sole is
    flat on the floor), ``sole_delta_m`` raising the ankle centre for a shoe's heel.
    """

    leg_length_m: Mapping[str, float]
    knee_width_m: Mapping[str, float]
    ankle_width_m: Mapping[str, float]
    marker_diameter_m: float = 0.014
    inter_asis_m: float | None = None
    asis_trochanter_m: Mapping[str, float] | None = None
    tibial_torsion_rad: Mapping[str, float] = field(default_factory=lambda: {"r": 0.0, "l": 0.0})
    thigh_rotation_rad: Mapping[str, float] = field(default_factory=lambda: {"r": 0.0, "l": 0.0})
    shank_rotation_rad: Mapping[str, float] = field(default_factory=lambda: {"r": 0.0, "l": 0.0})
    flat_foot: bool = False
    sole_delta_m: Mapping[str, float] = field(default_factory=lambda: {"r": 0.0, "l": 0.0})

    @property
    def marker_radius_m(self) -> float:
        return self.marker_diameter_m / 2


def processing_value(metadata: Mapping[str, float], side: str | None, name: str) -> float | None:
    """A subject measurement from a C3D ``PROCESSING`` group or a .vsk (Vicon's units), spelt either way Vicon
    spells it (``RKneeWidth``, ``RightKneeWidth``); None when absent."""
    prefixes = ("",) if side is None else _SIDE_WORDS[side]
    for prefix in prefixes:
        value = metadata.get(f"PROCESSING:{prefix}{name}")
        if value is not None and np.isfinite(value):
            return float(value)
    return None


@dataclass(frozen=True)
class FootOffsets:
    """Plug-in Gait's static foot offsets per side (rad): the rotation that takes the foot frame built on the ankle
    centre and the toe to the one built on the heel and the toe in the static trial, as ``Ry(plantarflexion) ·
    Rx(rotation)`` about the first frame's axes."""

    plantarflexion_rad: Mapping[str, float]
    rotation_rad: Mapping[str, float]


@dataclass
class CgmFrames:
    """Per-frame segment frames (n, 3, 3) by segment name (``pelvis``, ``thigh_r`` …), and the joint centres
    (n, 3) ``HJCr``, ``KJCr``, ``AJCr`` … they were built on."""

    rotation: dict[str, np.ndarray]
    joint_centres_m: dict[str, np.ndarray]


def _foot_frame(ankle, toe, flexion_axis) -> np.ndarray:
    """Plug-in Gait's foot axes: z from the toe to ``ankle``, x = flexion axis × z (up), y = z × x."""
    z = unit(ankle - toe)
    x = unit(np.cross(flexion_axis, z))
    return np.stack([x, np.cross(z, x), z], axis=-1)


def leg_frames(P: Mapping[str, np.ndarray], m: CgmMeasurements) -> CgmFrames:
    """Pelvis, thigh, shank and the uncorrected foot (ankle centre → toe) per frame from Plug-in Gait's markers,
    by model landmark: ``ASISr/l``, ``PSISr/l`` (both the sacrum where there is one), ``LEFr`` (KNE), ``LMr`` (ANK),
    ``MT2r`` (TOE), the wands ``THIr``/``TIBr`` and, optionally, the lab's own hip centres ``HJCr/l``."""
    _, pelvis = pelvis_frame(P["ASISr"], P["ASISl"], P["PSISr"], P["PSISl"])
    legs = np.array([m.leg_length_m["r"], m.leg_length_m["l"]], dtype=float)
    trochanter = None if m.asis_trochanter_m is None else (m.asis_trochanter_m["r"], m.asis_trochanter_m["l"])
    hips = davis_hip_joint_centres(P["ASISr"], P["ASISl"], P["PSISr"], P["PSISl"], leg_length_m=float(legs.mean()),
                                   marker_radius_m=m.marker_radius_m, asis_trochanter_m=trochanter,
                                   inter_asis_m=m.inter_asis_m)
    rotation, centres = {"pelvis": pelvis}, {}
    r = m.marker_radius_m
    for side, hip in zip(SIDES, hips):
        knee = chord_joint_centre(hip, P[f"THI{side}"], P[f"LEF{side}"], m.knee_width_m[side] / 2 + r,
                                  m.thigh_rotation_rad[side])
        ankle = chord_joint_centre(knee, P[f"TIB{side}"], P[f"LM{side}"], m.ankle_width_m[side] / 2 + r,
                                   m.shank_rotation_rad[side])
        # the chord's joint centre stands in for the medial marker: x is normal to the wand's plane
        shank = shank_frame(knee, ankle, P[f"LM{side}"], ankle, side=side) @ rot_z(-m.tibial_torsion_rad[side])
        rotation[f"thigh_{side}"] = thigh_frame(hip, knee, P[f"LEF{side}"], knee, side=side)
        rotation[f"shank_{side}"] = shank
        rotation[f"foot_{side}"] = _foot_frame(ankle, P[f"MT2{side}"], shank[..., 1])
        centres.update({f"HJC{side}": hip, f"KJC{side}": knee, f"AJC{side}": ankle})
    return CgmFrames(rotation, centres)


def static_foot_offsets(static: Mapping[str, np.ndarray], m: CgmMeasurements) -> FootOffsets:
    """Plug-in Gait's static offsets from the standing posture's mean landmarks: the uncorrected foot frame
    (:func:`leg_frames`) against the foot frame on the heel and the toe (``CAr``: HEE), the heel raised to the
    toe's height with ``flat_foot``."""
    frames = leg_frames(static, m)
    plantarflexion, rotation = {}, {}
    for side in SIDES:
        heel = np.array(static[f"CA{side}"], dtype=float)
        toe = np.asarray(static[f"MT2{side}"], dtype=float)
        ankle = frames.joint_centres_m[f"AJC{side}"]
        if m.flat_foot:
            heel[..., 2] = toe[..., 2]
            ankle = ankle + np.array([0.0, 0.0, m.sole_delta_m[side]])
        flexion_axis = frames.rotation[f"shank_{side}"][..., 1]
        uncorrected = _foot_frame(ankle, toe, flexion_axis)
        heel_toe = _foot_frame(heel, toe, flexion_axis)
        w = np.einsum("...ji,...j->...i", uncorrected, heel_toe[..., 2])  # the heel–toe axis in the first frame
        plantarflexion[side] = float(np.arctan2(w[..., 0], w[..., 2]))
        rotation[side] = float(np.arcsin(np.clip(-w[..., 1], -1.0, 1.0)))
    return FootOffsets(plantarflexion, rotation)


def anatomical_frames(frames: CgmFrames, offsets: FootOffsets) -> dict[str, np.ndarray]:
    """Pelvis, thigh, shank and foot frames (n, 3, 3; x forward, y left, z up): each uncorrected foot frame
    turned by its static offsets, then from Plug-in Gait's foot axes to the common ones."""
    out = {b: R for b, R in frames.rotation.items() if not b.startswith("foot")}
    for s in SIDES:
        vicon = frames.rotation[f"foot_{s}"] @ rot_y(offsets.plantarflexion_rad[s]) @ rot_x(offsets.rotation_rad[s])
        out[f"foot_{s}"] = vicon @ PIG_FOOT_AXES.T
    return out


#: a knee alignment device's markers per side: KAX on its arm along the knee flexion axis (lateral), KD1 and KD2 on
#: the two arms orthogonal to it; the three arms are of one length and mutually orthogonal, their hub on the knee
KAD_MARKERS = {"r": ("RKAX", "RKD1", "RKD2"), "l": ("LKAX", "LKD1", "LKD2")}


def kad_hub(kax, kd1, kd2, lateral) -> np.ndarray:
    """The hub (m) of a knee alignment device, where the knee marker KNE sits: the corner of the cube whose three
    edges from it end at KAX, KD1 and KD2 (edge L = mean marker distance / √2), at L/√3 from the markers'
    centroid along the triangle's normal, on the side away from ``lateral`` (a lateral direction of that leg)."""
    kax, kd1, kd2 = (np.asarray(a, dtype=float) for a in (kax, kd1, kd2))
    edge = np.mean([np.linalg.norm(a - b, axis=-1) for a, b in ((kax, kd1), (kax, kd2), (kd1, kd2))], axis=0)
    edge = np.asarray(edge / np.sqrt(2.0))[..., None]
    normal = unit(np.cross(kd1 - kax, kd2 - kax))
    normal = normal * np.sign(np.sum(normal * lateral, axis=-1, keepdims=True))  # the lateral one
    return (kax + kd1 + kd2) / 3 - normal * edge / np.sqrt(3.0)


def with_kad_hubs(static: Mapping[str, np.ndarray]) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """``static`` (mean positions by label and landmark) with ``LEFr``/``LEFl`` at the hub of a knee alignment
    device where one is worn (its three markers present, :data:`KAD_MARKERS`), and the device's ``KAXr``/``KAXl``
    (empty without a device)."""
    out, kad = dict(static), {}
    sides = [s for s in SIDES if all(label in static for label in KAD_MARKERS[s])]
    if not sides:
        return out, kad
    _, pelvis = pelvis_frame(static["ASISr"], static["ASISl"], static["PSISr"], static["PSISl"])
    for side in sides:
        kax, kd1, kd2 = (np.asarray(static[label], dtype=float) for label in KAD_MARKERS[side])
        out[f"LEF{side}"] = kad_hub(kax, kd1, kd2, pelvis[:, 1] * (1.0 if side == "l" else -1.0))
        kad[f"KAX{side}"] = kax
    return out, kad


def _turn(u, v_from, v_to) -> float:
    """Signed angle (rad) about the unit ``u`` from ``v_from`` to ``v_to`` (their components normal to u)."""
    a = v_from - np.dot(v_from, u) * u
    b = v_to - np.dot(v_to, u) * u
    return float(np.arctan2(np.dot(u, np.cross(a, b)), np.dot(a, b)))


def kad_rotation_offsets(static: Mapping[str, np.ndarray], kad: Mapping[str, np.ndarray],
                         m: CgmMeasurements) -> CgmMeasurements:
    """Plug-in Gait's thigh and shank rotation offsets from a knee alignment device in the standing posture.

    ``static``: the mean landmarks (:func:`plug_in_gait_landmarks`, ``LEFr`` at the device's hub); ``kad``:
    ``KAXr``, ``KAXl`` (the device's axis markers). The device's knee centre is the chord's with KAX as the wand
    (the knee flexion axis from the hub through KAX), its ankle centre the chord's with KAX too (no tibial torsion
    in the static); each offset is the angle about the chord from the wand's plane to the device's, which the
    walk, without the device, applies to the THI and TIB chords (:func:`leg_frames`)."""
    frames = leg_frames(static, m)
    thigh, shank = dict(m.thigh_rotation_rad), dict(m.shank_rotation_rad)
    r = m.marker_radius_m
    for side in SIDES:
        if f"KAX{side}" not in kad:
            continue
        hip, kax = frames.joint_centres_m[f"HJC{side}"], np.asarray(kad[f"KAX{side}"], dtype=float)
        hub, ankle_marker = np.asarray(static[f"LEF{side}"], float), np.asarray(static[f"LM{side}"], float)
        knee = chord_joint_centre(hip, kax, hub, m.knee_width_m[side] / 2 + r)
        ankle = chord_joint_centre(knee, kax, ankle_marker, m.ankle_width_m[side] / 2 + r)
        thigh[side] = _turn(unit(hip - hub), hub - np.asarray(static[f"THI{side}"], float), knee - hub)
        shank[side] = _turn(unit(knee - ankle_marker), ankle_marker - np.asarray(static[f"TIB{side}"], float),
                            ankle - ankle_marker)
    return dataclasses.replace(m, thigh_rotation_rad=thigh, shank_rotation_rad=shank)


#: Plug-in Gait's markers by model landmark (the marker set maps RASI → ASISr, …) and its wands by segment
PIG_LANDMARKS = tuple(f"{n}{s}" for n in ("ASIS", "PSIS", "LEF", "LM", "MT2", "CA") for s in SIDES)
PIG_WANDS = {"THI": "thigh", "TIB": "shank"}


def plug_in_gait_landmarks(positions: Mapping[str, np.ndarray],
                           wands: Mapping[str, tuple[str, ...]]) -> dict[str, np.ndarray] | None:
    """The landmarks and wands (``THIr``, ``TIBr`` …) :func:`leg_frames` takes, from ``positions`` (label →
    array) and the wands' labels per segment (``{"thigh_r": ("RTHI",), …}``); None when one is missing."""
    P = {n: positions[n] for n in PIG_LANDMARKS if n in positions}
    for key, segment in PIG_WANDS.items():
        for s in SIDES:
            label = next((lab for lab in wands.get(f"{segment}_{s}", ()) if lab in positions), None)
            if label is not None:
                P[f"{key}{s}"] = positions[label]
    needed = PIG_LANDMARKS + tuple(f"{k}{s}" for k in PIG_WANDS for s in SIDES)
    return P if all(n in P for n in needed) else None


@dataclass(frozen=True)
class PlugInGait:
    """What Plug-in Gait's frames need beyond the trial's markers: the measurements, the static foot offsets and
    each segment's wand labels (``{"thigh_r": ("RTHI",), …}``)."""

    measurements: CgmMeasurements
    offsets: FootOffsets
    wands: Mapping[str, tuple[str, ...]]

    def segments(self, positions: Mapping[str, np.ndarray]) -> CgmFrames | None:
        """Anatomical frames (n, 3, 3) of pelvis, thighs, shanks and feet per frame of ``positions`` and the joint
        centres (n, 3) they were built on, or None when a landmark is missing."""
        P = plug_in_gait_landmarks(positions, self.wands)
        if P is None:
            return None
        legs = leg_frames(P, self.measurements)
        return CgmFrames(anatomical_frames(legs, self.offsets), legs.joint_centres_m)


def measurements_from(metadata: Mapping[str, float], *, leg_length_m: float | None = None,
                      knee_width_m: Mapping[str, float] | None = None, ankle_width_m: Mapping[str, float] | None = None,
                      marker_diameter_m: float = 0.014) -> CgmMeasurements | None:
    """Plug-in Gait's measurements from a C3D ``PROCESSING`` group or .vsk (``metadata``, Vicon's mm and rad),
    the given values (subject.yaml) first; None when a leg length or a knee or ankle width is unknown."""
    def sided(name, given, scale=1e-3):
        values = {s: (given or {}).get(s, None) for s in SIDES}
        for s in SIDES:
            if values[s] is None:
                v = processing_value(metadata, s, name)
                values[s] = None if v is None else v * scale
        return values

    legs = sided("LegLength", None if leg_length_m is None else {s: leg_length_m for s in SIDES})
    knees, ankles = sided("KneeWidth", knee_width_m), sided("AnkleWidth", ankle_width_m)
    if any(v is None for d in (legs, knees, ankles) for v in d.values()):
        return None
    trochanter = sided("AsisTrocanterDistance", None)
    inter_asis = processing_value(metadata, None, "InterAsisDistance")
    torsion = sided("TibialTorsion", None, scale=1.0)
    return CgmMeasurements(
        leg_length_m=legs, knee_width_m=knees, ankle_width_m=ankles, marker_diameter_m=marker_diameter_m,
        inter_asis_m=None if inter_asis is None else inter_asis * 1e-3,
        asis_trochanter_m=None if any(v is None for v in trochanter.values()) else trochanter,
        tibial_torsion_rad={s: v or 0.0 for s, v in torsion.items()})
