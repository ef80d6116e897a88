"""The subject: the ``subject.yaml`` schema and what a Vicon subject file (``.vsk``) adds to it.

The ``.vsk``'s parameters are the subject's measurements below ``subject.yaml``
and above the C3D's ``PROCESSING`` group; without ``subject.yaml`` the ``.vsk``
describes the subject alone (:func:`subject_from_vsk`). Finding these files in a
trial folder is :mod:`gaitcli.run.trial`'s.
"""

from __future__ import annotations

import dataclasses
import re
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from gaitcli.core.validate import known_keys, number, one_of
from gaitcli.emg.channels import sided_muscle
from gaitcli.errors import InputError, shown
from gaitcli.io.vsk import VskSubject
from gaitcli.io.yamlfile import read_yaml
from gaitcli.kinematics.anthropometry import SEGMENT_TABLES
from gaitcli.kinematics.disturbances import Disturbance
from gaitcli.kinematics.markerset import MarkerSet, marker_set, marker_set_names

SEXES = ("male", "female")
#: the largest frame number a subject file may name (a C3D counts frames in 32 bits)
MAX_FRAME = 2**31 - 1
SEGMENTS = ("pelvis", "hat", "thigh_r", "shank_r", "foot_r", "thigh_l", "shank_l", "foot_l")


@dataclass(frozen=True)
class Subject:
    """The subject and the trial's bookkeeping, as validated from ``subject.yaml``."""

    mass_kg: float | None
    stature_m: float
    sex: str
    thigh_length_m: float | None = None
    shank_length_m: float | None = None
    leg_length_m: float | None = None  # ASIS to medial malleolus, for the Harrington and Hara hip centres
    trial: str | None = None
    static: str | None = None  # a file name; in a session folder also a glob matching one file
    trials: tuple[str, ...] = ()  # a session's walks: globs in its folder (empty: every C3D but the static)
    static_frames: tuple[int, int] | str | None = None  # [first, last] file frames, "auto", or None (static.c3d)
    marker_map: dict[str, str] = field(default_factory=dict)
    disturbances: tuple[Disturbance, ...] = ()  # added masses (Tables A.2–A.3), in segment axes
    marker_set: str | None = None  # a bundled preset (markerset.marker_set_names()); None: Table A.6 labels
    hip_joint_centre: str = "bell"
    segment_inertias: str | None = None  # de_leva or plug_in_gait; None: by the marker set (:attr:`segment_table`)
    # Plug-in Gait's chord method, mm: {"r": ..., "l": ...} (None: from the C3D's PROCESSING group)
    knee_width_mm: dict[str, float] | None = None
    ankle_width_mm: dict[str, float] | None = None
    marker_diameter_mm: float | None = None
    vsk: str | None = None  # the Vicon subject file subject.yaml names (None: the folder's only .vsk, if any)
    # the .vsk's parameters {"PROCESSING:<NAME>": value} (mm, kg, rad), merged over the C3D's subject data
    measurements: dict[str, float] = field(default_factory=dict)
    measurements_source: str | None = None  # the file they came from (the .vsk's name)
    emg: dict[str, str] = field(default_factory=dict)  # EMG channel label → sided muscle (emg/channels.py)
    emg_mvc: str | None = None  # a C3D in the trial folder with maximal contractions of the same EMG channels
    mass_source: str = "subject.yaml"  # where mass_kg came from
    notes: tuple[str, ...] = ()  # where the subject's numbers came from, and what was assumed

    @cached_property
    def markers(self) -> MarkerSet:
        """The preset with ``marker_map`` merged over it: which lab label is which landmark or tracks which body."""
        return marker_set(self.marker_set, self.marker_map)

    @property
    def segment_table(self) -> str:
        """Where the legs' masses, CoMs and inertias come from: ``segment_inertias``, or Plug-in Gait's in a Plug-in
        Gait session (so that its moments are Vicon's) and de Leva's otherwise (3.2.2)."""
        if self.segment_inertias is not None:
            return self.segment_inertias
        return "plug_in_gait" if self.marker_set == "plug_in_gait" else "de_leva"


KEYS = ("mass_kg", "stature_m", "sex", "thigh_length_m", "shank_length_m", "leg_length_m", "trial", "static",
        "static_frames", "marker_set", "marker_map", "hip_joint_centre", "segment_inertias", "disturbances",
        "knee_width_mm", "ankle_width_mm", "marker_diameter_mm", "vsk", "trials", "emg", "emg_mvc")
#: hip joint centre methods (``hip_joint_centre:``): Bell et al. (1990), as the dissertation; Harrington et al.
#: (2007); Hara et al. (2016); Davis et al. (1991, Plug-in Gait's); functional (SCORE, Ehrig et al. 2006, from the
#: trial's hip motion); the lab's points
HIP_JOINT_CENTRES = ("bell", "harrington", "hara", "davis", "score", "from_file")
#: keys that older `gait synth` versions wrote and nothing reads; now a comment in subject.yaml
RETIRED_KEYS = ("condition", "disturbed_side")
DISTURBANCE_KEYS = ("segment", "mass_kg", "inertia_kgm2", "com_offset_m", "name")


def _number(path, where, value, *, low=None, high=None, expected="a number") -> float:
    return number(value, where=where, path=path, low=low, high=high, low_open=low is not None, expected=expected)


def _vector3(path, where, value) -> tuple[float, float, float]:
    if not isinstance(value, (list, tuple)) or len(value) != 3:
        raise InputError(path, where, f"got {shown(value)} (expected a list of 3 numbers)")
    return tuple(_number(path, where, v, expected="a list of 3 numbers") for v in value)


def _per_side_mm(path, key, value, *, low: float, high: float) -> dict[str, float] | None:
    """A width in mm for both sides (one number) or ``[right, left]``."""
    if value is None:
        return None
    values = value if isinstance(value, (list, tuple)) else [value, value]
    if len(values) != 2:
        raise InputError(path, key, f"got {shown(value)} (expected a width in mm, or [right, left])")
    return {s: _number(path, key, v, low=low, high=high, expected=f"a width in mm, {low:g}–{high:g}, or [right, left]")
            for s, v in zip("rl", values)}


def subject_from_dict(data: Any, path: str | Path = "subject.yaml", vsk: VskSubject | None = None,
                      vsk_name: str | None = None) -> Subject:
    """Validate the parsed ``subject.yaml``; every problem is an :class:`InputError` naming the key. ``vsk``
    (named ``vsk_name``, the trial folder's Vicon subject file) gives the keys subject.yaml leaves out
    (:func:`vsk_keys`), each said in the subject's notes."""
    if not isinstance(data, dict):
        raise InputError(path, None, "expected a YAML mapping with mass_kg, stature_m and sex")
    filled: dict[str, str] = {}
    if vsk is not None:
        given, notes = vsk_keys(vsk, vsk_name or vsk.source.name)
        filled = {key: notes[key] for key in given if data.get(key) is None}
        data = {**data, **{key: given[key] for key in filled}}
    for key in RETIRED_KEYS:
        if key in data:
            raise InputError(path, key, "no longer read (it described the synthetic experiment; expected the line "
                                        "as a comment, '# condition: …', as `gait synth` now writes it)")
    known_keys(data, KEYS, path=path)
    for key in ("stature_m", "sex"):
        if key not in data:
            raise InputError(path, key, "missing (required)")
    mass = data.get("mass_kg", "auto")
    if mass == "auto":
        mass = None  # estimated from the force plates by the idyn stage
    else:
        mass = _number(path, "mass_kg", mass, low=0, high=500, expected="a body mass in kg, > 0 and ≤ 500, or 'auto'")
    stature = data["stature_m"]
    if isinstance(stature, (int, float)) and not isinstance(stature, bool) and 40 <= stature <= 260:
        raise InputError(path, "stature_m", f"got {stature:g} (expected metres, e.g. {stature / 100:.2f}; "
                                            "this looks like centimetres)")
    stature = _number(path, "stature_m", stature, low=0.4, high=2.6, expected="a stature in metres between 0.4 and 2.6")
    sex = one_of(data["sex"], SEXES, where="sex", path=path)
    lengths = {}
    for key in ("thigh_length_m", "shank_length_m"):
        if data.get(key) is not None:
            lengths[key] = _number(path, key, data[key], low=0.1, high=0.8, expected="a length in metres, 0.1–0.8")
    if data.get("leg_length_m") is not None:
        lengths["leg_length_m"] = _number(path, "leg_length_m", data["leg_length_m"], low=0.3, high=1.5,
                                          expected="a leg length in metres (ASIS to medial malleolus), 0.3–1.5")
    for key in ("trial", "static", "vsk"):
        if data.get(key) is not None and not isinstance(data[key], str):
            raise InputError(path, key, f"got {shown(data[key])} (expected a file name)")
    trials = data.get("trials")
    trials = [trials] if isinstance(trials, str) else trials
    if trials is not None and (not isinstance(trials, list) or not trials
                               or not all(isinstance(t, str) and t.strip() for t in trials)):
        raise InputError(path, "trials", f"got {shown(data['trials'])} (expected a file name or glob, e.g. "
                                         "'Walking *.c3d', or a list of them)")
    frames = data.get("static_frames")
    if frames is not None and frames != "auto":
        ok = (isinstance(frames, (list, tuple)) and len(frames) == 2
              and all(isinstance(f, int) and not isinstance(f, bool) for f in frames)
              and 1 <= frames[0] <= frames[1] <= MAX_FRAME)
        if not ok:
            raise InputError(path, "static_frames", f"got {shown(frames)} (expected [first, last] frame numbers, "
                                                    f"1-based and at most {MAX_FRAME:,}, or auto)")
        frames = (int(frames[0]), int(frames[1]))
    marker_map = data.get("marker_map") or {}
    if not isinstance(marker_map, dict) or not all(isinstance(k, str) and isinstance(v, str)
                                                   for k, v in marker_map.items()):
        raise InputError(path, "marker_map", "expected a mapping of lab label → model landmark or body (text → text)")
    preset = data.get("marker_set")
    if preset is not None:
        preset = one_of(preset, marker_set_names(), where="marker_set", path=path)
    marker_set(preset, marker_map, source=path)  # every landmark and body of the map named, or one error
    hip = one_of(data.get("hip_joint_centre", "bell"), HIP_JOINT_CENTRES, where="hip_joint_centre", path=path)
    inertias = data.get("segment_inertias")
    if inertias is not None:
        inertias = one_of(inertias, SEGMENT_TABLES, where="segment_inertias", path=path)
    disturbances = []
    items = data.get("disturbances") or []
    if not isinstance(items, list):
        raise InputError(path, "disturbances", "expected a list of {segment, mass_kg, inertia_kgm2, com_offset_m}")
    for i, item in enumerate(items):
        where = f"disturbances[{i}]"
        if not isinstance(item, dict):
            raise InputError(path, where, "expected a mapping with segment and mass_kg")
        known_keys(item, DISTURBANCE_KEYS, where=f"{where}.", path=path)
        if not isinstance(item.get("name", ""), str):
            raise InputError(path, f"{where}.name", f"got {shown(item['name'])} (expected text)")
        segment = one_of(item.get("segment"), SEGMENTS, where=f"{where}.segment", path=path)
        disturbances.append(Disturbance(
            segment=segment,
            mass_kg=_number(path, f"{where}.mass_kg", item.get("mass_kg"), low=0, high=50,
                            expected="an added mass in kg, > 0 and ≤ 50"),
            # principal moments about the added mass's own centre, segment axes (Table A.2)
            inertia_kgm2=np.diag(_vector3(path, f"{where}.inertia_kgm2", item.get("inertia_kgm2", [0, 0, 0]))),
            com_offset_m=np.array(_vector3(path, f"{where}.com_offset_m", item.get("com_offset_m", [0, 0, 0]))),
            name=str(item.get("name", "")),
        ))
    widths = {"knee_width_mm": _per_side_mm(path, "knee_width_mm", data.get("knee_width_mm"), low=40, high=200),
              "ankle_width_mm": _per_side_mm(path, "ankle_width_mm", data.get("ankle_width_mm"), low=30, high=150)}
    if data.get("marker_diameter_mm") is not None:
        widths["marker_diameter_mm"] = _number(path, "marker_diameter_mm", data["marker_diameter_mm"], low=0,
                                               high=40, expected="a marker diameter in mm, > 0 and ≤ 40")
    emg = data.get("emg") or {}
    if not isinstance(emg, dict) or not all(isinstance(k, str) for k in emg):
        raise InputError(path, "emg", f"got {shown(emg)} (expected a mapping of EMG channel label → muscle and side, "
                                      "e.g. RTIBA: tibialis_anterior_r)")
    emg = {label.strip(): sided_muscle(muscle, f"emg.{label}", path) for label, muscle in emg.items()}
    return Subject(mass_kg=mass, stature_m=stature, sex=sex, trial=data.get("trial"), static=data.get("static"),
                   trials=tuple(trials or ()), vsk=data.get("vsk"), static_frames=frames, marker_map=dict(marker_map),
                   disturbances=tuple(disturbances), marker_set=preset, hip_joint_centre=hip,
                   segment_inertias=inertias, emg=emg,
                   emg_mvc=data.get("emg_mvc"), **lengths, **widths,
                   notes=tuple(filled.values()))


def load_subject(path: str | Path) -> Subject:
    """Read and validate ``subject.yaml``."""
    path = Path(path)
    if not path.is_file():
        raise InputError(path, None, "file not found (every trial folder needs a subject.yaml or a Vicon .vsk)")
    data = read_yaml(path)
    return subject_from_dict(data, path)


#: the .vsk parameters the stages read (``Recording.subject_metadata`` keys), the subject.yaml key that takes
#: their place, and the range a value must be in to be used (the .vsk's units: kg, mm)
VSK_MEASUREMENTS = (
    (("Bodymass",), "mass_kg", 0, 500, "a body mass in kg, > 0 and ≤ 500"),
    (("Height",), "stature_m", 400, 2600, "a height in mm, > 400 and ≤ 2600"),
    (("RightLegLength", "LeftLegLength"), "leg_length_m", 300, 1500, "a leg length in mm, > 300 and ≤ 1500"),
    (("RightKneeWidth", "LeftKneeWidth"), "knee_width_mm", 40, 200, "a width in mm, > 40 and ≤ 200"),
    (("RightAnkleWidth", "LeftAnkleWidth"), "ankle_width_mm", 30, 150, "a width in mm, > 30 and ≤ 150"),
    (("MarkerDiameter",), "marker_diameter_mm", 0, 40, "a marker diameter in mm, > 0 and ≤ 40"),
)


def _is_plug_in_gait(model: str) -> bool:
    """Whether a .vsk's model name is Vicon's Plug-in Gait ("PlugInGait FullBody Ai", "Plug-in Gait Lower Body")."""
    return re.sub(r"[^a-z]", "", model.lower()).startswith("plugingait")


def _checked_measurements(vsk: VskSubject, given: Subject | None) -> list[str]:
    """The measurements of :data:`VSK_MEASUREMENTS` the stages will use (those ``given``, subject.yaml's subject,
    does not give), checked to be in range; each as "NAME value" for the notes."""
    used = []
    for names, key, *_ in VSK_MEASUREMENTS:
        if given is not None and getattr(given, key) is not None:
            continue
        for parameter in names:
            if (value := _checked_value(vsk, parameter)) is not None:
                used.append(f"{parameter} {value:g}")
    return used


def _checked_value(vsk: VskSubject, parameter: str) -> float | None:
    """The .vsk's ``parameter`` (one of :data:`VSK_MEASUREMENTS`), checked to be in its range; None when absent."""
    _, _, low, high, expected = next(row for row in VSK_MEASUREMENTS if parameter in row[0])
    value = vsk.value(parameter)
    if value is not None:
        number(value, where=parameter, path=vsk.source, low=low, high=high, low_open=True, expected=expected)
    return value


def vsk_keys(vsk: VskSubject, name: str) -> tuple[dict[str, Any], dict[str, str]]:
    """The subject.yaml keys the .vsk ``name`` gives, as subject.yaml would spell them, and a note for each:
    ``stature_m`` from Height (mm → m, checked as :data:`VSK_MEASUREMENTS`), ``marker_set`` plug_in_gait and
    ``hip_joint_centre`` davis when its model is Plug-in Gait, and ``sex`` male (a .vsk records none: assumed).
    (Bodymass is a measurement: ``mass_kg`` left out is the .vsk's, :func:`with_measurements`.)"""
    keys, notes = {}, {}
    if (height := vsk.value("Height")) is not None:
        _checked_value(vsk, "Height")
        keys["stature_m"] = height / 1000.0
        notes["stature_m"] = f"{name}'s Height: stature_m {height / 1000.0:g} (subject.yaml gives none)"
    if _is_plug_in_gait(vsk.model):
        for key, value in (("marker_set", "plug_in_gait"), ("hip_joint_centre", "davis")):
            keys[key] = value
            notes[key] = f"{name}'s model {shown(vsk.model)}: {key} {value} (subject.yaml gives none)"
    keys["sex"] = "male"
    notes["sex"] = (f"{name} records no sex: male assumed (de Leva's male segment tables; subject.yaml gives "
                    "none, `sex:` there says otherwise)")
    return keys, notes


def subject_from_vsk(vsk: VskSubject, name: str) -> Subject:
    """The subject a .vsk describes when the trial folder has no subject.yaml: mass from Bodymass (kg; absent: as
    ``mass_kg: auto``), stature from Height (mm → m), Plug-in Gait's marker set and Davis hip joint centres when
    its model is Plug-in Gait, and sex male (a .vsk records none: de Leva's male tables, said in the notes)."""
    used = _checked_measurements(vsk, None)
    height = vsk.value("Height")
    if height is None:
        raise InputError(vsk.source, "Height", "missing (expected the subject's height in mm, or a subject.yaml "
                                               "with stature_m and sex)")
    mass = vsk.value("Bodymass")
    pig = _is_plug_in_gait(vsk.model)
    subject = Subject(mass_kg=mass, stature_m=height / 1000.0, sex="male",
                      marker_set="plug_in_gait" if pig else None, hip_joint_centre="davis" if pig else "bell",
                      mass_source=f"{name}'s Bodymass")
    described = (f"subject: {name}, no subject.yaml: body mass "
                 + (f"{mass:g} kg from Bodymass" if mass is not None else "not recorded (estimated as mass_kg: auto)")
                 + f", stature {height / 1000.0:g} m from Height"
                 + (f"; marker set plug_in_gait and Davis hip joint centres for its model {shown(vsk.model)}"
                    if pig else f"; its model {shown(vsk.model)} is not Plug-in Gait: the dissertation's marker "
                                "labels and Bell hip joint centres"))
    sex = (f"sex: {name} records none, male assumed (de Leva's male segment tables); a subject.yaml with sex "
           "(and stature_m) says otherwise")
    return with_measurements(subject, vsk, name, used=used, notes=(described, sex))


def with_measurements(subject: Subject, vsk: VskSubject, name: str, *, used: list[str] | None = None,
                      notes: tuple[str, ...] = ()) -> Subject:
    """``subject`` (subject.yaml's, or ``used`` and ``notes`` given: :func:`subject_from_vsk`'s) with the .vsk's
    parameters as its measurements, checked where the stages will use them, and a note saying where they went."""
    below = used is None
    if below:
        used = _checked_measurements(vsk, subject)
    merged = (f"subject measurements: {name} ({shown(vsk.model)}): {len(vsk.parameters)} parameters as "
              "PROCESSING:<NAME> (mm, kg, rad), over the C3D files' PROCESSING group"
              + (", under subject.yaml's keys" if below else "")
              + (f"; used: {', '.join(used)}" if used else ""))
    return dataclasses.replace(subject, vsk=name, measurements=dict(vsk.parameters), measurements_source=name,
                               notes=subject.notes + notes + (merged,))
