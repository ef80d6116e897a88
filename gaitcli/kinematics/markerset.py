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
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from gaitcli.core.events import SIDE_NAMES
from gaitcli.core.recording import Markers
from gaitcli.core.validate import known_keys, one_of
from gaitcli.errors import InputError
from gaitcli.io.yamlfile import read_yaml
from gaitcli.kinematics.model import BODIES

SIDES = ("r", "l")

BILATERAL = ("VM", "FM", "LM", "MM", "CA", "TT", "LEF", "MEF", "MRF", "GT", "ASIS", "PSIS", "AC")
MIDLINE = ("C7", "ST")

#: the 28 markers of Table A.6 as model landmark names
MARKERS = tuple(f"{d}{s}" for d in BILATERAL for s in SIDES) + MIDLINE
#: landmarks beyond Table A.6 that clinical sets place: the second metatarsal head (Plug-in Gait's TOE), on the foot
EXTRA_MARKERS = ("MT2r", "MT2l")
VIRTUAL_JOINT_CENTRES = ("HJCr", "HJCl", "KJCr", "KJCl", "AJCr", "AJCl")
LANDMARKS = MARKERS + EXTRA_MARKERS + VIRTUAL_JOINT_CENTRES

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
    """Landmarks that may track ``body``: its Table A.6 markers, the foot's MT2, then adjacent virtual joint centres.

    A virtual joint centre exported by the lab is fixed in both bodies it joins, so it
    takes part in both clusters when present (needed for marker sets like Plug-in Gait
    that have only two skin markers on the thigh).
    """
    extra = tuple(jc for jc, bodies in JOINT_CENTRE_BODIES.items() if body in bodies)
    toe = tuple(m for m in EXTRA_MARKERS if body == f"foot_{m[-1]}")
    return SEGMENT_MARKERS[body] + toe + extra


def body_of_marker(landmark: str) -> str:
    """The body a Table A.6 marker (or MT2) is fixed to."""
    for body, labels in SEGMENT_MARKERS.items():
        if landmark in labels:
            return body
    if landmark in EXTRA_MARKERS:
        return f"foot_{landmark[-1]}"
    raise KeyError(landmark)


def required_landmarks(*, virtual_joint_centres: tuple[str, ...] | frozenset = (),
                       chord_joint_centres: tuple[str, ...] | frozenset = (),
                       toe_feet: tuple[str, ...] | frozenset = ()) -> tuple[str, ...]:
    """Landmarks a static trial must contain to define the model's geometry.

    Hip centres need ASIS and PSIS (Bell), knee centres LEF and MEF, ankle centres LM
    and MM, the foot CoM CA, VM and FM. A virtual joint centre in
    ``virtual_joint_centres`` removes the markers needed only for that centre (the
    pelvis markers stay: they define the pelvis frame and track it); a knee or ankle
    centre in ``chord_joint_centres`` (Plug-in Gait's chord method) needs only the
    lateral marker; a side in ``toe_feet`` has a foot of CA and MT2 (no VM, FM).
    Markers needed only for tracking (GT, MRF, TT, trunk) are not required: a body
    left with fewer than three is locked to its parent.
    """
    virtual, chord = set(virtual_joint_centres), set(chord_joint_centres)
    needed = ["ASISr", "ASISl", "PSISr", "PSISl"]
    for s in SIDES:
        for jc, lateral, medial in ((f"KJC{s}", f"LEF{s}", f"MEF{s}"), (f"AJC{s}", f"LM{s}", f"MM{s}")):
            if jc not in virtual:
                needed += [lateral] if jc in chord else [lateral, medial]
        needed += [f"CA{s}", f"MT2{s}"] if s in toe_feet else [f"CA{s}", f"VM{s}", f"FM{s}"]
    return tuple(needed)


#: what each Table A.6 designation (and virtual point) is, for messages naming a lab's marker
LANDMARK_DESCRIPTIONS = {
    "ASIS": "anterior superior iliac spine", "PSIS": "posterior superior iliac spine", "GT": "greater trochanter",
    "MRF": "rectus femoris (mid-thigh)", "LEF": "lateral femoral epicondyle", "MEF": "medial femoral epicondyle",
    "TT": "tibial tuberosity", "LM": "lateral malleolus", "MM": "medial malleolus", "CA": "posterior calcaneus",
    "VM": "lateral (fifth) metatarsal head", "FM": "medial (first) metatarsal head", "AC": "acromioclavicular joint",
    "C7": "seventh cervical vertebra", "ST": "manubrium of the sternum", "MT2": "second metatarsal head (toe marker)",
    "HJC": "hip joint centre",
    "KJC": "knee joint centre", "AJC": "ankle joint centre",
}
MARKER_SETS_DIR = Path(__file__).resolve().parent / "marker_sets"
_PRESET_SECTIONS = ("name", "description", "anatomical", "virtual_joint_centres", "tracking", "wands")


def describe_landmark(landmark: str) -> str:
    """``'ASISr'`` → ``'right anterior superior iliac spine'``."""
    if landmark in MIDLINE:
        return LANDMARK_DESCRIPTIONS[landmark]
    side = SIDE_NAMES[landmark[-1]]
    return f"{side} {LANDMARK_DESCRIPTIONS[landmark[:-1]]}"


@dataclass(frozen=True)
class MarkerSet:
    """Which lab labels are which model landmarks, and which lab markers only track a body.

    ``landmarks[landmark]``: the lab labels that may carry that landmark (anatomical
    or virtual joint centre), in order of preference: the first one a file has is
    used. ``tracking[body]``: lab labels of markers fixed to ``body`` that are no
    anatomical landmark (wands, clusters, plates); they join its SVD cluster.
    ``name``: the preset (``cleveland``, ...) or ``"marker_map"``. ``wands[body]``: those of its tracking
    markers that are Plug-in Gait wands, which with the lateral marker span the plane of the chord method.
    """

    name: str
    landmarks: Mapping[str, tuple[str, ...]]
    tracking: Mapping[str, tuple[str, ...]] = field(default_factory=dict)
    wands: Mapping[str, tuple[str, ...]] = field(default_factory=dict)

    def merged(self, marker_map: Mapping[str, str], *, source=None) -> MarkerSet:
        """This set with subject.yaml's ``marker_map`` {lab label: landmark or body} over it: a mapped label
        becomes the only label of its landmark (or a tracking marker of its body) and leaves any other role."""
        if not marker_map:
            return self
        landmarks = {k: tuple(lab for lab in v if lab not in marker_map) for k, v in self.landmarks.items()}
        tracking = {k: tuple(lab for lab in v if lab not in marker_map) for k, v in self.tracking.items()}
        for lab, target in marker_map.items():
            one_of(target, LANDMARKS + BODIES, where=f"marker_map.{lab}", path=source)
        targets = [t for t in marker_map.values() if t not in BODIES]
        twice = sorted({t for t in targets if targets.count(t) > 1})
        if twice:
            labs = [lab for lab, t in marker_map.items() if t in twice]
            raise InputError(source, "marker_map", f"labels {', '.join(labs)} map to the same landmark "
                                                   f"{', '.join(twice)} (it occurs more than once after mapping)")
        for lab, target in marker_map.items():
            if target in BODIES:
                tracking[target] = tracking.get(target, ()) + (lab,)
            else:
                landmarks[target] = (lab,)
        name = self.name if self.name == "marker_map" else f"{self.name} with marker_map"
        return MarkerSet(name, landmarks, tracking, self.wands)

    def label_of(self, landmark: str, labels=None) -> str | None:
        """The lab label that carries ``landmark`` (the first of ``labels`` that is a candidate, when given)."""
        candidates = self.landmarks.get(landmark, ())
        if labels is None:
            return candidates[0] if candidates else None
        return next((lab for lab in candidates if lab in labels), None)

    def missing_message(self, landmark: str, purpose: str) -> str:
        """One line for a landmark a file lacks: which lab label(s) this set expects, what it is, what it is for."""
        candidates = self.landmarks.get(landmark, ())
        if self.name == "dissertation" or candidates == (landmark,):
            label = landmark
        else:
            label = " or ".join(candidates) if candidates else f"no label for {landmark}"
        return (f"marker missing from the static trial: {label} (marker_set {self.name}: the "
                f"{describe_landmark(landmark)}, {landmark}; needed for {purpose})")

    def lab_labels(self, labels) -> dict[str, str]:
        """{landmark: the lab label of ``labels`` that :meth:`apply` renames to it}."""
        chosen = {landmark: next((lab for lab in candidates if lab in labels), None)
                  for landmark, candidates in self.landmarks.items()}
        return {landmark: lab for landmark, lab in chosen.items() if lab is not None}

    def apply(self, markers: Markers, *, source: str | Path | None = None,
              explicit: Mapping[str, str] | None = None) -> Markers:
        """Rename the file's lab labels to model landmarks (one column per landmark found; a lab label that
        carries two landmarks, e.g. one sacral marker for both PSIS, is copied). Labels not used as
        landmarks keep their names (tracking markers, unused ones). Raises :class:`InputError` naming every
        label of ``explicit`` (subject.yaml's marker_map) the file does not have, or a label that would occur
        twice."""
        missing = [lab for lab in (explicit or {}) if lab not in markers.labels]
        if missing:
            raise InputError(source, "marker_map",
                             f"labels not in the marker file: {', '.join(missing)} "
                             f"(the file has: {', '.join(markers.labels)})")
        chosen = self.lab_labels(markers.labels)
        used = set(chosen.values())
        kept = [lab for lab in markers.labels if lab not in used]
        new_labels = tuple(chosen) + tuple(kept)
        duplicates = sorted({lab for lab in new_labels if new_labels.count(lab) > 1})
        if duplicates:
            raise InputError(source, "marker_map",
                             f"labels {', '.join(duplicates)} occur more than once after mapping")
        columns = [markers.index(lab) for lab in chosen.values()] + [markers.index(lab) for lab in kept]
        return Markers(new_labels, markers.positions_m[:, columns, :], markers.rate_hz, markers.first_frame)


def _label_lists(data, where: str, keys, path) -> dict[str, tuple[str, ...]]:
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise InputError(path, where, f"got {type(data).__name__} (expected a mapping of name → list of labels)")
    out = {}
    for key, labels in data.items():
        one_of(key, keys, where=where, path=path)
        labels = [labels] if isinstance(labels, str) else labels
        if not isinstance(labels, list) or not labels or not all(isinstance(lab, str) and lab for lab in labels):
            raise InputError(path, f"{where}.{key}", f"got {labels!r} (expected a list of lab labels)")
        out[key] = tuple(labels)
    return out


def read_marker_set(path: str | Path) -> MarkerSet:
    """A marker-set YAML file (``marker_sets/*.yaml``): ``anatomical`` and ``virtual_joint_centres``
    {landmark: [lab labels]}, ``tracking`` and ``wands`` {body: [lab labels]} (wands also track)."""
    path = Path(path)
    data = read_yaml(path)
    if not isinstance(data, dict):
        raise InputError(path, None, "expected a mapping with anatomical, virtual_joint_centres and tracking")
    known_keys(data, _PRESET_SECTIONS, path=path)
    landmarks = _label_lists(data.get("anatomical"), "anatomical", MARKERS + EXTRA_MARKERS, path)
    landmarks.update(_label_lists(data.get("virtual_joint_centres"), "virtual_joint_centres",
                                  VIRTUAL_JOINT_CENTRES, path))
    tracking = _label_lists(data.get("tracking"), "tracking", BODIES, path)
    wands = _label_lists(data.get("wands"), "wands", BODIES, path)
    for body, labels in wands.items():
        tracking[body] = tuple(dict.fromkeys(labels + tracking.get(body, ())))
    return MarkerSet(str(data.get("name", path.stem)), landmarks, tracking, wands)


def marker_set_names() -> tuple[str, ...]:
    """The bundled presets (``marker_set:`` in subject.yaml)."""
    return tuple(sorted(p.stem for p in MARKER_SETS_DIR.glob("*.yaml")))


def marker_set(name: str | None = None, marker_map: Mapping[str, str] | None = None, *,
               source: str | Path | None = None) -> MarkerSet:
    """The preset ``name`` (default: the dissertation's Table A.6 labels) with ``marker_map`` merged over it."""
    one_of(name or "dissertation", marker_set_names(), where="marker_set", path=source)
    return read_marker_set(MARKER_SETS_DIR / f"{name or 'dissertation'}.yaml").merged(marker_map or {},
                                                                                    source=source)


def apply_marker_map(markers: Markers, marker_map: Mapping[str, str], *,
                     source: str | Path | None = None) -> Markers:
    """Rename lab labels to model landmarks by ``marker_map`` alone {lab label: landmark}; other labels are kept
    (so a file already using the model's names needs no map). See :meth:`MarkerSet.apply` for the errors."""
    for lab, landmark in marker_map.items():
        one_of(landmark, LANDMARKS, where=f"marker_map.{lab}", path=source)
    return MarkerSet("marker_map", {}).merged(marker_map, source=source).apply(markers, source=source,
                                                                              explicit=marker_map)


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

        def at(x, dy_lateral, z, y=y, sign=sign):
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


def with_fixed_points(markers: Markers, points: Mapping[str, np.ndarray]) -> Markers:
    """``markers`` with each of ``points`` ({label: (3,) m}) as a trajectory standing still in every frame (a label
    already there is replaced)."""
    keep = [i for i, lab in enumerate(markers.labels) if lab not in points]
    fixed = np.stack([np.broadcast_to(np.asarray(v, float), (markers.n_frames, 3)) for v in points.values()], axis=1)
    return Markers(tuple(markers.labels[i] for i in keep) + tuple(points),
                   np.concatenate([markers.positions_m[:, keep], fixed], axis=1), markers.rate_hz, markers.first_frame)


def landmarks_to_markers(landmarks: Mapping[str, np.ndarray], *, rate_hz: float = 100.0) -> Markers:
    """Pack landmark positions (each ``(3,)`` or ``(frames, 3)``) into a :class:`Markers`."""
    labels = tuple(landmarks)
    arrays = [np.atleast_2d(np.asarray(landmarks[k], dtype=float)) for k in labels]
    return Markers(labels, np.stack(arrays, axis=1), rate_hz)
