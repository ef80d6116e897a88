"""Static calibration: from the reference posture to body parameters and marker clusters (3.2, 3.3).

The reference posture is the subject standing on the force plate (3.1.3, step 4),
from ``static.c3d`` or from named frames of the dynamic trial. In it:

* joint centres are located (:mod:`gaitcli.kinematics.joint_centres`);
* each body gets its **reference frame** (3.3, 3.3.3): origin at its CoM, axes
  parallel to the global axes in the reference posture — the body frames of the
  model (:class:`BodyParameters`, forward kinematics, inverse dynamics). Its
  **anatomical frame** (Cappozzo) has the same origin; the constant rotation
  ``reference_to_anatomical[b]`` converts: ``R_anatomical = R_reference @ C_b``;
* the CoMs follow de Leva along the joint-centre lines (thigh HJC→KJC, shank
  KJC→AJC, foot from CA along the foot's long axis); on the global vertical
  through the mid-hip point MIDH lie the pelvis CoM, d2 = (1 − CoM fraction)·L
  above MIDH, and the lumbar joint (OMPH), L above MIDH, with L the lower-trunk
  length (Table A.4 gives these offsets in Y and Z only, i.e. no x offset); the
  HAT CoM lies c2 above the lumbar joint;
* segment inertias are rotated from de Leva's principal axes (the anatomical axes of
  thigh, shank and foot; the global axes for pelvis and HAT) into body axes, then
  disturbances (Tables A.2–A.3, body axes) are added; the CoMs move accordingly;
* every marker is expressed in the frame of the body it is fixed to: the reference
  cluster ``r^i_OMj`` of (3.2).

A thigh, shank or foot with only 2 markers of its own is tracked with its proximal joint
centre as the third point (``chained``), placed in each frame by the parent's pose, as
Plug-in Gait tracks its thigh (HJC, THI, KNE), shank (KJC, TIB, ANK) and foot (AJC, HEE,
TOE); a segment with a Plug-in Gait wand keeps that joint centre in its cluster when medial
markers (KNM, MED) add a third marker of its own. A body other than the pelvis with fewer
points than 3 is ``locked``: tracked as rigidly attached to its parent (zero joint angles),
which is recorded and warned about; with a marker set that names the leg markers (a
preset) a locked leg segment is an error.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from gaitcli.core.events import SIDE_NAMES
from gaitcli.core.numerics import true_runs
from gaitcli.core.recording import Markers
from gaitcli.core.validate import one_of
from gaitcli.errors import GaitWarning, InputError
from gaitcli.kinematics import joint_centres as jcm
from gaitcli.kinematics.anthropometry import (
    SEGMENT_TABLES,
    SegmentInertia,
    normalise_sex,
    plug_in_gait_limb,
    rotate_segment,
    segment_parameters,
)
from gaitcli.kinematics.disturbances import Disturbance, apply_disturbances, resolve_disturbances
from gaitcli.kinematics.markerset import (
    LANDMARKS,
    SEGMENT_MARKERS,
    VIRTUAL_JOINT_CENTRES,
    MarkerSet,
    required_landmarks,
    tracking_landmarks,
)
from gaitcli.kinematics.model import BODIES, JOINT_CHILD, JOINT_PARENT, JOINTS, BodyParameters
from gaitcli.kinematics.pose import MIN_MARKERS
from gaitcli.kinematics.rotations import rot_z

_PURPOSE = {"ASIS": "the pelvis frame and hip joint centres", "PSIS": "the pelvis frame and hip joint centres",
            "LEF": "the knee joint centre", "MEF": "the knee joint centre", "LM": "the ankle joint centre",
            "MM": "the ankle joint centre", "CA": "the foot", "VM": "the foot", "FM": "the foot", "MT2": "the foot"}
#: the medial marker a chord needs in its place: the width subject.yaml or the C3D's PROCESSING group gives
_CHORD_ALTERNATIVE = {"MEF": ("knee", "thigh", "knee_width_mm", "KneeWidth"),
                      "MM": ("ankle", "shank", "ankle_width_mm", "AnkleWidth")}


def _chord_of(name: str, marker_set: MarkerSet | None):
    """(joint, segment, subject.yaml key, PROCESSING parameter) when the missing medial marker ``name`` could be
    replaced by the chord method (the marker set has a wand on that segment), else None."""
    if name[:-1] not in _CHORD_ALTERNATIVE or marker_set is None:
        return None
    joint, segment, key, suffix = _CHORD_ALTERNATIVE[name[:-1]]
    side = name[-1]
    if not marker_set.wands.get(f"{segment}_{side}"):
        return None
    return joint, f"{segment}_{side}", key, f"{'Right' if side == 'r' else 'Left'}{suffix}"


@dataclass
class StaticCalibration:
    """Everything the reference posture fixes for one subject (SI units, global = model axes).

    ``body``: the model's :class:`BodyParameters` (body frames = reference frames).
    ``landmarks_in_body_m[body][landmark]``: (3,) position in that body's frame.
    ``tracking_landmarks[body]``: the cluster fitted per frame (empty when locked).
    ``locked``: bodies tracked as rigidly attached to their parent.
    ``reference_to_anatomical`` (8, 3, 3): ``R_anatomical = R_reference @ C[b]``;
    ``anatomical_from_landmarks[b]`` False where landmarks were missing and a global
    axis stood in (identity for a locked HAT).
    ``joint_centres_m``: static global positions of ``lumbar, HJCr, …, AJCl``.
    ``com_m`` (8, 3): static global CoM positions. ``segments``: mass geometry per body
    in body axes (CoM relative to the de Leva origin landmark).
    ``static_landmarks_m``: the averaged static marker positions used.
    ``static_rotation``: every body's reference frame in the reference posture (the heading the subject faces
    there, about the vertical); body-frame quantities are in these axes, positions in the static's own.
    ``chained[body]``: the proximal joint centre (``HJCr``, ...) in that body's cluster that is no marker of the
    trial but placed in each frame by the parent's pose.
    """

    body: BodyParameters
    landmarks_in_body_m: dict[str, dict[str, np.ndarray]]
    tracking_landmarks: dict[str, tuple[str, ...]]
    locked: tuple[str, ...]
    reference_to_anatomical: np.ndarray
    anatomical_from_landmarks: tuple[bool, ...]
    joint_centres_m: dict[str, np.ndarray]
    com_m: np.ndarray
    segments: dict[str, SegmentInertia]
    static_landmarks_m: dict[str, np.ndarray]
    notes: list[str] = field(default_factory=list)
    chained: dict[str, str] = field(default_factory=dict)
    static_rotation: np.ndarray = field(default_factory=lambda: np.eye(3))

    def cluster(self, body: str) -> np.ndarray:
        """Reference cluster (k, 3) of ``body`` in its frame, rows in ``tracking_landmarks[body]`` order."""
        labels = self.tracking_landmarks[body]
        return np.array([self.landmarks_in_body_m[body][lab] for lab in labels]).reshape(len(labels), 3)

    def markers_in_body(self) -> tuple[dict[int, np.ndarray], dict[int, tuple[str, ...]]]:
        """All landmarks as ``{body index: (k, 3)}`` (the form ``forward.marker_positions`` takes)
        and ``{body index: labels}`` naming the rows."""
        labels = {i: tuple(self.landmarks_in_body_m[b]) for i, b in enumerate(BODIES)}
        arrays = {i: np.array([self.landmarks_in_body_m[b][n] for n in labels[i]]).reshape(-1, 3)
                  for i, b in enumerate(BODIES)}
        return arrays, labels


def static_landmarks(markers: Markers, frames: Sequence[int] | slice | None = None) -> dict[str, np.ndarray]:
    """Mean position (3,) of every marker over ``frames`` (default all), ignoring NaN;
    markers never seen in those frames are left out."""
    pos = markers.positions_m if frames is None else markers.positions_m[frames]
    pos = np.asarray(pos, dtype=float).reshape(-1, len(markers.labels), 3)
    seen = np.all(np.isfinite(pos), axis=-1)  # (frames, markers)
    out = {}
    for i, lab in enumerate(markers.labels):
        if seen[:, i].any():
            out[lab] = pos[seen[:, i], i].mean(axis=0)
    return out


def chord_and_toe_sides(P: Mapping[str, np.ndarray], widths: jcm.JointWidths | None,
                        marker_set: MarkerSet | None = None) -> tuple[tuple, tuple]:
    """The knee and ankle centres the chord method places (no medial marker and no virtual centre of the lab;
    width and wand known), and the sides whose foot is CA and MT2 alone (no fifth metatarsal in the file, or none
    in the marker set)."""
    chord = []
    for s in "rl":
        for joint, jc, medial in (("knee", f"KJC{s}", f"MEF{s}"), ("ankle", f"AJC{s}", f"MM{s}")):
            if (medial not in P and jc not in P and widths is not None
                    and widths.chord_inputs(joint, s, P) is not None):
                chord.append(jc)
    toe = tuple(s for s in "rl" if (f"MT2{s}" in P and not (f"VM{s}" in P and f"FM{s}" in P))
                or (marker_set is not None and f"MT2{s}" in marker_set.landmarks
                    and f"VM{s}" not in marker_set.landmarks))
    return tuple(chord), toe


def _check_wand(name: str, P: Mapping[str, np.ndarray], marker_set: MarkerSet | None, widths, source) -> None:
    """A missing medial marker whose chord has its width but not its wand: the wand is what is missing."""
    chord = _chord_of(name, marker_set)
    if chord is None or widths is None:
        return
    joint, segment, _, _ = chord
    if widths.offset_m(joint, name[-1]) is not None and widths.chord_inputs(joint, name[-1], P) is None:
        labels = marker_set.wands[segment]
        raise InputError(source, labels[0], f"marker missing from the static trial: {' or '.join(labels)} (marker_set "
                                            f"{marker_set.name}: the {SIDE_NAMES[name[-1]]} {segment[:-2]} wand, "
                                            f"tracking the {SIDE_NAMES[name[-1]]} {segment[:-2]}; needed for the "
                                            f"{joint} joint centre by the chord method, as there is no medial "
                                            f"marker {' or '.join(marker_set.landmarks.get(name, ()))})")


def _check_required(P: Mapping[str, np.ndarray], source, marker_set: MarkerSet | None,
                    widths: jcm.JointWidths | None) -> None:
    virtual = tuple(v for v in VIRTUAL_JOINT_CENTRES if v in P)
    chord, toe = chord_and_toe_sides(P, widths, marker_set)
    for name in required_landmarks(virtual_joint_centres=virtual, chord_joint_centres=chord, toe_feet=toe):
        if name not in P:
            _check_wand(name, P, marker_set, widths, source)
            purpose = _PURPOSE[name[:-1]]
            chord = _chord_of(name, marker_set)
            if chord is not None:
                _, segment, key, parameter = chord
                purpose += (f"; without it, the chord method needs {key} in subject.yaml or the C3D's "
                            f"PROCESSING:{parameter} and the {segment[:-2]} wand")
            if marker_set is None:
                raise InputError(source, name, f"marker missing from the static trial (needed for {purpose})")
            raise InputError(source, marker_set.label_of(name) or name, marker_set.missing_message(name, purpose))


#: a leg segment's proximal joint centre (the chained third tracking point)
_PROXIMAL_CENTRE = {"thigh": "HJC", "shank": "KJC", "foot": "AJC"}


def _locked_leg_message(body: str, found: list[str], P: Mapping[str, np.ndarray],
                        marker_set: MarkerSet) -> tuple[str, str]:
    """(label, message) for a leg segment with fewer than 2 markers of its own in the static trial."""
    own = [(marker_set.label_of(n), n) for n in tracking_landmarks(body)
           if n not in VIRTUAL_JOINT_CENTRES and marker_set.label_of(n)]
    own += [(lab, None) for lab in marker_set.tracking.get(body, ())]
    missing = [lab for lab, landmark in own if (landmark or lab) not in P]
    segment, side = body.split("_")
    role = f"tracking the {SIDE_NAMES[side]} {segment}"
    return (missing[0] if missing else body,
            f"marker missing from the static trial: {', '.join(missing) or 'no marker named'} (marker_set "
            f"{marker_set.name}: {role}; with only {', '.join(found) or 'no marker'} the {segment} has fewer than 2 "
            f"markers of its own and would be locked to its parent)")


HIP_METHODS = ("bell1990", "bell1989", "harrington", "hara", "davis", "from_file")


def least_flexed_frames(markers: Markers, *, source: str | Path | None = None, quiet_speed_m_s: float = 0.05,
                        quiet_s: float = 0.5, window_s: float = 1.0) -> tuple[np.ndarray, str]:
    """Frames of a trial to stand in for a static trial (``static_frames: auto``), and how they were chosen.

    Candidates are the frames in which every landmark the calibration needs is seen.
    Each leg's flexion is the angle between the thigh (Bell hip centre → mid-epicondyles,
    or the lab's KJC) and the shank (knee → mid-malleoli, or the lab's AJC). Where the
    subject stood, the quiet window with the least mean flexion of the more flexed leg is
    used; in a walk without standing, the one frame where the more flexed leg is
    straightest (both knees near extension: double support just before a heel strike).

    Parameters
    ----------
    markers : Markers
        The trial, labels renamed to model landmarks.
    source : str or Path, optional
        The trial file, for messages.
    quiet_speed_m_s, quiet_s : float
        The subject stands where the pelvis is slower than ``quiet_speed_m_s`` (m/s) for
        ``quiet_s`` (s) or longer.
    window_s : float
        Longest quiet window averaged, s.

    Returns
    -------
    frames : numpy.ndarray
        0-based frame indices.
    how : str
        One line for the notes.

    Raises
    ------
    InputError
        When no frame shows the landmarks.
    """
    P = {lab: markers.get(lab) for lab in markers.labels}
    virtual = tuple(v for v in VIRTUAL_JOINT_CENTRES if v in P and v[:3] != "HJC")
    # without a medial marker the lateral one stands in for the joint (the flexion angle barely differs)
    lateral_only = tuple(jc for s in "rl" for jc, medial in ((f"KJC{s}", f"MEF{s}"), (f"AJC{s}", f"MM{s}"))
                         if medial not in P)
    toe = tuple(s for s in "rl" if f"MT2{s}" in P and f"VM{s}" not in P)
    needed = required_landmarks(virtual_joint_centres=virtual, chord_joint_centres=lateral_only,
                                toe_feet=toe) + virtual
    absent = [n for n in needed if n not in P]
    if absent:
        raise InputError(source, absent[0], "marker missing from the trial (static_frames: auto looks for frames "
                                            "in which the calibration's markers are seen)")
    seen = np.logical_and.reduce([np.all(np.isfinite(P[n]), axis=-1) for n in needed])
    if not seen.any():
        raise InputError(source, "static_frames", f"auto: no frame in which all of {', '.join(needed)} are seen")
    with np.errstate(invalid="ignore"):
        hips = jcm.hip_joint_centres(P["ASISr"], P["ASISl"], P["PSISr"], P["PSISl"])
        flexion = []
        for s, hip in zip("rl", hips):
            knee = P[f"KJC{s}"] if f"KJC{s}" in virtual else jcm.knee_joint_centre(P[f"LEF{s}"],
                                                                                   P.get(f"MEF{s}", P[f"LEF{s}"]))
            ankle = P[f"AJC{s}"] if f"AJC{s}" in virtual else jcm.ankle_joint_centre(P[f"LM{s}"],
                                                                                     P.get(f"MM{s}", P[f"LM{s}"]),
                                                                                     method="midpoint")
            cos = np.sum(jcm.unit(hip - knee) * jcm.unit(knee - ankle), axis=-1)
            flexion.append(np.arccos(np.clip(cos, -1.0, 1.0)))
        worse = np.where(seen, np.maximum(*flexion), np.inf)
        pelvis = np.mean([P[n] for n in ("ASISr", "ASISl", "PSISr", "PSISl")], axis=0)
        speed = np.linalg.norm(np.gradient(pelvis, 1.0 / markers.rate_hz, axis=0), axis=-1)
    quiet = seen & (speed < quiet_speed_m_s)
    best = None
    for a, b in zip(*true_runs(quiet)):
        if (b - a) / markers.rate_hz < quiet_s:
            continue
        length = min(b - a, max(int(round(window_s * markers.rate_hz)), 1))
        means = np.convolve(worse[a:b], np.ones(length) / length, mode="valid")
        k = int(np.argmin(means))
        if best is None or means[k] < best[0]:
            best = (means[k], np.arange(a + k, a + k + length))
    if best is not None:
        return best[1], (f"auto: {best[1].size} frames of quiet standing (pelvis slower than "
                         f"{quiet_speed_m_s:g} m/s), knees flexed at most {np.degrees(best[0]):.1f}°")
    k = int(np.argmin(worse))
    return np.array([k]), (f"auto: no quiet standing; the frame where the more flexed knee is straightest "
                           f"({np.degrees(worse[k]):.1f}°)")


def calibrate(static: Markers, *, mass_kg: float, stature_m: float, sex: str = "male",
              frames: Sequence[int] | slice | None = None, thigh_length_m=None, shank_length_m=None,
              foot_length_m=None, shoulder_width_m: float | None = None,
              disturbances: Sequence[Disturbance | str] = (), hip_method: str = "bell1990",
              ankle_method: str = "de_leva", extra_tracking_markers: Mapping[str, Sequence[str]] | None = None,
              marker_set: MarkerSet | None = None, leg_length_m: float | None = None,
              widths: jcm.JointWidths | None = None, untracked: Sequence[str] = (),
              segment_inertias: str = "de_leva", source: str | Path | None = None) -> StaticCalibration:
    """Calibrate the 8-body model on the reference posture ``static`` (averaged over ``frames``).

    Parameters
    ----------
    static : Markers
        The reference posture, labels renamed to model landmarks (m).
    mass_kg, stature_m : float
        Body mass (kg) and stature (m).
    sex : str
        de Leva's table (:func:`~gaitcli.kinematics.anthropometry.segment_parameters`).
    frames : sequence of int or slice, optional
        The frames of ``static`` to average (default all).
    thigh_length_m, shank_length_m, foot_length_m, shoulder_width_m : optional
        Given lengths, m; the thigh (HJC–KJC) and shank (KJC–AJC) are measured when not given, the
        others scale with stature (3.2.2).
    disturbances : sequence of Disturbance or str
        Added masses: :class:`Disturbance` objects (body axes, offsets from the body's de Leva CoM) or
        preset names (``"ankle_weight"``, ``"ski_boot:l"``).
    hip_method : str
        ``"bell1990"`` (the dissertation's), ``"bell1989"``, ``"harrington"``, ``"hara"``, ``"davis"``
        or ``"from_file"`` (the lab's ``HJCr``/``HJCl`` points, otherwise ignored).
    ankle_method : str
        ``"de_leva"`` or ``"midpoint"`` (:func:`~gaitcli.kinematics.joint_centres.ankle_joint_centre`).
    extra_tracking_markers : mapping of body to labels, optional
        Lab markers added to a body's cluster (a marker set's tracking markers).
    marker_set : MarkerSet, optional
        Names the lab labels in error messages.
    leg_length_m : float, optional
        For the Harrington, Hara and Davis regressions, m (default ASIS to medial malleolus).
    widths : JointWidths, optional
        Knee and ankle widths, marker diameter and wands for Plug-in Gait's chord method.
    untracked : sequence of str
        Landmarks that place joint centres but track no body (a virtual point the walking trial lacks).
    segment_inertias : str
        ``"de_leva"`` (3.2.2) or ``"plug_in_gait"``: the legs' masses, CoMs and inertias as Plug-in Gait's
        (:data:`~gaitcli.kinematics.anthropometry.PLUG_IN_GAIT_LEGS`; the foot from the ankle centre to the toe).
    source : str or Path, optional
        The static file, for messages.

    Raises
    ------
    InputError
        Naming a marker the model's geometry needs, by the lab label ``marker_set`` gives it.
    """
    sex = normalise_sex(sex)
    one_of(hip_method, HIP_METHODS, where="hip_joint_centre", path=source)
    measured = _reference_landmarks(static, frames, hip_method, marker_set, source)
    _check_required(measured, source, marker_set, widths)
    heading, facing = _facing_rotation(measured)
    P = {k: facing.T @ v for k, v in measured.items()}
    jc = jcm.joint_centres(P, hip_method="bell1990" if hip_method == "from_file" else hip_method,
                           ankle_method=ankle_method, sex=sex, leg_length=leg_length_m, widths=widths, source=source)
    chord, toe = chord_and_toe_sides(P, widths, marker_set)
    notes = _joint_centre_notes(P, chord, hip_method, ankle_method)
    one_of(segment_inertias, SEGMENT_TABLES, where="segment_inertias", path=source)
    segs = _measured_segments(jc, mass_kg, stature_m, sex, thigh_length_m=thigh_length_m,
                              shank_length_m=shank_length_m, foot_length_m=foot_length_m,
                              shoulder_width_m=shoulder_width_m, legs=segment_inertias)
    notes.insert(0, f"de Leva (1996) {sex} table"
                 + ("; the legs Plug-in Gait's" if segment_inertias == "plug_in_gait" else "")
                 + f"; body mass {float(mass_kg):.2f} kg, stature {float(stature_m):.3f} m")
    lumbar = (jc["HJCr"] + jc["HJCl"]) / 2 + segs["pelvis"].length_m * np.array([0.0, 0.0, 1.0])  # OMPH (3.2.1)
    rotation, origin, anatomical, from_landmarks = _segment_frames(P, jc, chord, toe, lumbar)
    if segment_inertias == "plug_in_gait":
        segs = {**segs, **{f"foot_{s}": _plug_in_gait_foot(mass_kg, P, jc, rotation[f"foot_{s}"], s)
                           for s in "rl" if f"MT2{s}" in P}}
    for b, ok in from_landmarks.items():
        if not ok:
            notes.append(f"{b}: anatomical frame incomplete (landmarks missing), global axes used instead")
    notes.append(f"the subject faces {np.degrees(heading):.1f}° from +x in the reference posture: the segments' "
                 "reference frames are parallel to the axes it faces there")
    body, body_segs, com = _body_parameters(segs, rotation, origin, lumbar, jc, disturbances, notes)

    extra = dict(extra_tracking_markers or {})
    for b in extra:
        one_of(b, BODIES, where="extra_tracking_markers", path=source)
    landmarks_in_body, tracking, chained, locked = _tracking_clusters(P, jc, com, extra, untracked, marker_set,
                                                                      source, notes)
    return StaticCalibration(
        body=body, landmarks_in_body_m=landmarks_in_body, tracking_landmarks=tracking, locked=tuple(locked),
        reference_to_anatomical=np.array([anatomical[b] for b in BODIES]),
        anatomical_from_landmarks=tuple(from_landmarks[b] for b in BODIES),
        joint_centres_m={k: facing @ v for k, v in {"lumbar": lumbar, **jc}.items()}, com_m=com @ facing.T,
        segments=body_segs, static_rotation=facing,
        static_landmarks_m={k: v for k, v in measured.items()
                            if k in LANDMARKS or any(k in e for e in extra.values())},
        notes=notes, chained=chained)


def _reference_landmarks(static: Markers, frames, hip_method: str, marker_set: MarkerSet | None,
                         source) -> dict[str, np.ndarray]:
    """The averaged reference-posture landmarks (m, the static's axes): the lab's virtual hip centres kept only for
    ``hip_method: from_file`` (and required then), otherwise left out of the model and of the clusters."""
    P = static_landmarks(static, frames)
    if hip_method != "from_file":
        return {k: v for k, v in P.items() if k not in ("HJCr", "HJCl")}
    for name in ("HJCr", "HJCl"):
        if name not in P:
            label = marker_set.label_of(name) if marker_set is not None else None
            raise InputError(source, label or name, "hip_joint_centre is from_file but the static trial has no "
                                                    "such point (expected the lab's virtual hip joint centre)")
    return P


def _facing_rotation(P: Mapping[str, np.ndarray]) -> tuple[float, np.ndarray]:
    """The heading (rad, about the vertical from +x) the pelvis faces in the reference posture, and ``rot_z`` of it.

    The reference frames are parallel to the axes the subject faces in the static (3.3.3 takes a subject facing
    +x): the static is turned by the transpose until the pelvis faces +x, and its results turned back by it.
    """
    _, pelvis_axes = jcm.pelvis_frame(P["ASISr"], P["ASISl"], P["PSISr"], P["PSISl"])
    heading = float(np.arctan2(pelvis_axes[1, 0], pelvis_axes[0, 0]))
    return heading, rot_z(heading)


def _joint_centre_notes(P: Mapping[str, np.ndarray], chord: tuple, hip_method: str, ankle_method: str) -> list[str]:
    """One note per way a joint centre was placed: the lab's virtual points or estimated, the hip regression, the
    chord method, the malleoli."""
    notes = [f"{name}: {'virtual marker from the lab file' if name in P else 'estimated'}"
             for name in VIRTUAL_JOINT_CENTRES]
    notes.append("hip joint centres: " + {"from_file": "the lab's virtual points (from_file)",
                                          "harrington": "Harrington et al. (2007) regression",
                                          "hara": "Hara et al. (2016) regression",
                                          "davis": "Davis et al. (1991) regression (Plug-in Gait)"}.get(
        hip_method, f"Bell regression ({hip_method})"))
    notes += [f"{name}: Plug-in Gait's chord method (no medial marker)" for name in chord]
    if not all(f"AJC{s}" in P or f"AJC{s}" in chord for s in "rl"):
        notes.append(f"ankle joint centres from the malleoli ({ankle_method})")
    return notes


def _measured_segments(jc: Mapping[str, np.ndarray], mass_kg: float, stature_m: float, sex: str, *,
                       thigh_length_m, shank_length_m, foot_length_m, shoulder_width_m,
                       legs: str) -> dict[str, SegmentInertia]:
    """de Leva's segments (3.2.2; the legs ``legs``'s) with the thigh (HJC–KJC) and shank (KJC–AJC) lengths
    measured per side (m) between the static's joint centres where not given."""
    measured_thigh = tuple(float(np.linalg.norm(jc[f"HJC{s}"] - jc[f"KJC{s}"])) for s in "rl")
    measured_shank = tuple(float(np.linalg.norm(jc[f"KJC{s}"] - jc[f"AJC{s}"])) for s in "rl")
    return segment_parameters(mass_kg, stature_m, sex,
                              thigh_length_m=measured_thigh if thigh_length_m is None else thigh_length_m,
                              shank_length_m=measured_shank if shank_length_m is None else shank_length_m,
                              foot_length_m=foot_length_m, shoulder_width_m=shoulder_width_m, legs=legs)


def _plug_in_gait_foot(mass_kg: float, P: Mapping[str, np.ndarray], jc: Mapping[str, np.ndarray],
                       rotation: np.ndarray, s: str) -> SegmentInertia:
    """Side ``s``'s foot as Plug-in Gait's for body mass ``mass_kg``: from the ankle centre to the toe marker
    (MT2), in the foot's segment axes (``rotation`` turns them into the reference axes) from its model origin, the
    heel (CA)."""
    ankle_to_toe = P[f"MT2{s}"] - jc[f"AJC{s}"]
    length = float(np.linalg.norm(ankle_to_toe))
    foot = plug_in_gait_limb("foot", mass_kg, length, rotation.T @ (ankle_to_toe / length), "HEEL",
                             "ankle centre to toe, measured")
    return replace(foot, com_m=rotation.T @ (jc[f"AJC{s}"] - P[f"CA{s}"]) + foot.com_m)


def _segment_frames(P: Mapping[str, np.ndarray], jc: Mapping[str, np.ndarray], chord: tuple, toe: tuple,
                    lumbar: np.ndarray) -> tuple[dict, dict, dict, dict]:
    """Each body's de Leva axes in the reference (global static) axes, the global position of its de Leva origin
    (m), its anatomical frame (3.3.3) and whether landmarks gave that frame (rather than global axes).

    Pelvis and HAT keep the global axes with their origin at the lumbar joint ``lumbar`` (OMPH, 3.2.1); a leg
    segment's axes are its anatomical frame, origin at its proximal joint centre (the foot's at CA).
    """
    rotation = {"pelvis": np.eye(3), "hat": np.eye(3)}
    origin = {"pelvis": lumbar, "hat": lumbar}
    anatomical = {}
    from_landmarks = {}
    _, anatomical["pelvis"] = jcm.pelvis_frame(P["ASISr"], P["ASISl"], P["PSISr"], P["PSISl"])
    from_landmarks["pelvis"] = True
    for s in "rl":
        leg_rotation, leg_from_landmarks = _leg_frames(P, jc, chord, toe, s)
        rotation.update(leg_rotation)
        from_landmarks.update(leg_from_landmarks)
        origin.update({f"thigh_{s}": jc[f"HJC{s}"], f"shank_{s}": jc[f"KJC{s}"], f"foot_{s}": P[f"CA{s}"]})
        anatomical.update(leg_rotation)
    trunk = ("C7", "ST", "ACr", "ACl")
    from_landmarks["hat"] = all(t in P for t in trunk)
    anatomical["hat"] = jcm.trunk_frame(lumbar, *(P[t] for t in trunk)) if from_landmarks["hat"] else np.eye(3)
    return rotation, origin, anatomical, from_landmarks


def _leg_frames(P: Mapping[str, np.ndarray], jc: Mapping[str, np.ndarray], chord: tuple, toe: tuple,
                s: str) -> tuple[dict[str, np.ndarray], dict[str, bool]]:
    """The anatomical frames (3, 3) of side ``s``'s thigh, shank and foot in the reference posture, and whether both
    epicondyles (malleoli) were markers.

    Without a medial marker the chord's or the lab's joint centre stands in for it: the frame's y lies in the plane
    of the lateral marker and the segment's axis. A foot with CA and MT2 alone takes its y from the shank's.
    """
    epicondyles = (P.get(f"LEF{s}"), P[f"MEF{s}"] if f"MEF{s}" in P
                   else jc[f"KJC{s}"] if f"KJC{s}" in chord or f"KJC{s}" in P else None)
    malleoli = (P.get(f"LM{s}"), P[f"MM{s}"] if f"MM{s}" in P
                else jc[f"AJC{s}"] if f"AJC{s}" in chord or f"AJC{s}" in P else None)
    thigh = jcm.thigh_frame(jc[f"HJC{s}"], jc[f"KJC{s}"], *epicondyles, side=s)
    shank = jcm.shank_frame(jc[f"KJC{s}"], jc[f"AJC{s}"], *malleoli, side=s)
    foot = (jcm.toe_foot_frame(P[f"CA{s}"], P[f"MT2{s}"], shank) if s in toe
            else jcm.foot_frame(P[f"CA{s}"], P[f"VM{s}"], P[f"FM{s}"], side=s))
    return ({f"thigh_{s}": thigh, f"shank_{s}": shank, f"foot_{s}": foot},
            {f"thigh_{s}": all(e is not None for e in epicondyles),
             f"shank_{s}": all(m is not None for m in malleoli), f"foot_{s}": True})


def _body_parameters(segs: Mapping[str, SegmentInertia], rotation: Mapping[str, np.ndarray],
                     origin: Mapping[str, np.ndarray], lumbar: np.ndarray, jc: Mapping[str, np.ndarray],
                     disturbances, notes: list[str]) -> tuple[BodyParameters, dict[str, SegmentInertia], np.ndarray]:
    """The model's bodies: de Leva's segments rotated into body axes plus the disturbances (Tables A.2–A.3), their
    global CoMs (8, 3) m, and each joint from its parent's and child's CoM (m). Appends to ``notes``, which the
    returned :class:`BodyParameters` shares."""
    body_segs = {b: rotate_segment(segs[b], rotation[b]) for b in BODIES}
    items = resolve_disturbances(disturbances, body_segs)
    body_segs = apply_disturbances(body_segs, items)
    notes += [f"disturbance {d.name or 'custom'} on {d.segment}: {d.mass_kg:.3f} kg" for d in items]

    com = np.array([origin[b] + body_segs[b].com_m for b in BODIES])
    joint_pos = {"lumbar": lumbar}
    joint_pos.update({f"hip_{s}": jc[f"HJC{s}"] for s in "rl"})
    joint_pos.update({f"knee_{s}": jc[f"KJC{s}"] for s in "rl"})
    joint_pos.update({f"ankle_{s}": jc[f"AJC{s}"] for s in "rl"})
    joint_in_parent = np.array([joint_pos[j] - com[JOINT_PARENT[i]] for i, j in enumerate(JOINTS)])
    joint_in_child = np.array([joint_pos[j] - com[JOINT_CHILD[i]] for i, j in enumerate(JOINTS)])
    lengths = {b: float(body_segs[b].length_m) for b in BODIES}
    for b in BODIES:
        notes += [f"{b}: {n}" for n in body_segs[b].notes]
    body = BodyParameters(mass_kg=np.array([body_segs[b].mass_kg for b in BODIES]),
                          inertia_kgm2=np.array([body_segs[b].inertia_kgm2 for b in BODIES]),
                          joint_in_parent_m=joint_in_parent, joint_in_child_m=joint_in_child,
                          segment_length_m=lengths, notes=notes)
    return body, body_segs, com


def _tracking_clusters(P: Mapping[str, np.ndarray], jc: Mapping[str, np.ndarray], com: np.ndarray,
                       extra: Mapping[str, Sequence[str]], untracked: Sequence[str], marker_set: MarkerSet | None,
                       source, notes: list[str]) -> tuple[dict, dict, dict, list]:
    """Every body's reference cluster ``r^i_OMj`` (3.2): its landmarks relative to its CoM (m), the landmarks it is
    tracked by, the proximal joint centre chained in where it has two markers (or a wand), and the bodies locked to
    their parent for fewer; appends to ``notes`` and warns for each locked body."""
    landmarks_in_body: dict[str, dict[str, np.ndarray]] = {}
    tracking: dict[str, tuple[str, ...]] = {}
    chained: dict[str, str] = {}
    locked = []
    for i, b in enumerate(BODIES):
        candidates = tracking_landmarks(b) + tuple(extra.get(b, ()))
        names = [n for n in dict.fromkeys(candidates) if n in P and n not in untracked]
        landmarks_in_body[b] = {n: P[n] - com[i] for n in names}
        proximal = _PROXIMAL_CENTRE.get(b[:-2], "") + b[-1]
        # Plug-in Gait's tracking: two markers and the joint centre above; a segment with a Plug-in Gait wand keeps
        # the joint centre when medial markers add a third (wand, KNE and KNM alone span ~0.1 m: a hip moment
        # 0.02 N·m/kg noisier, benchmarks/README.md)
        wand = marker_set is not None and bool(marker_set.wands.get(b))
        if (len(names) == MIN_MARKERS - 1 or (wand and len(names) >= MIN_MARKERS - 1)) \
                and b not in ("pelvis", "hat") and proximal not in names:
            chained[b] = proximal
            names.append(proximal)
            landmarks_in_body[b][proximal] = jc[proximal] - com[i]
            notes.append(f"{b}: tracked by {', '.join(names[:-1])} and the {proximal} placed by the parent's pose")
        if len(names) >= MIN_MARKERS:
            tracking[b] = tuple(names)
            continue
        _check_lockable(b, names, P, marker_set, source)
        tracking[b] = ()
        locked.append(b)
        parent = BODIES[JOINT_PARENT[JOINT_CHILD.index(i)]]
        message = (f"{b}: fewer than {MIN_MARKERS} tracking markers in the static trial (found "
                   f"{', '.join(names) or 'none'}); locked to {parent}")
        notes.append(message)
        warnings.warn(message, GaitWarning, stacklevel=3)  # at calibrate's caller
    return landmarks_in_body, tracking, chained, locked


def _check_lockable(body: str, names: list[str], P: Mapping[str, np.ndarray], marker_set: MarkerSet | None,
                    source) -> None:
    """A body with fewer than ``MIN_MARKERS`` tracking points may be locked to its parent unless it is the pelvis,
    or a leg segment of a marker set that names the leg markers (then a marker is missing)."""
    if marker_set is not None and body not in ("pelvis", "hat"):
        raise InputError(source, *_locked_leg_message(body, names, P, marker_set))
    if body == "pelvis":
        raise InputError(source, "pelvis", f"fewer than {MIN_MARKERS} pelvis markers in the static trial "
                                           f"(found {', '.join(names) or 'none'} of "
                                           f"{', '.join(SEGMENT_MARKERS[body])})")
