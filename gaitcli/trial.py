"""Trial folders: discovery of the files, and the ``subject.yaml`` schema.

A trial folder holds ``trial.c3d`` (or the file ``subject.yaml`` names under
``trial:``, or ``markers.csv`` + ``forces.csv``), an optional ``static.c3d`` and
``subject.yaml``. Nothing in it is ever modified.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from gaitcli.io.yamlfile import read_yaml
from gaitcli.core.validate import known_keys, number, one_of
from gaitcli.errors import InputError, shown
from gaitcli.kinematics.disturbances import Disturbance
from gaitcli.kinematics.markerset import MarkerSet, marker_set, marker_set_names

SEXES = ("male", "female")
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
    static: str | None = None
    static_frames: tuple[int, int] | str | None = None  # [first, last] file frames, "auto", or None (static.c3d)
    marker_map: dict[str, str] = field(default_factory=dict)
    disturbances: tuple[Disturbance, ...] = ()  # added masses (Tables A.2–A.3), in segment axes
    marker_set: str | None = None  # a bundled preset (markerset.marker_set_names()); None: Table A.6 labels
    hip_joint_centre: str = "bell"
    # Plug-in Gait's chord method, mm: {"r": ..., "l": ...} (None: from the C3D's PROCESSING group)
    knee_width_mm: dict[str, float] | None = None
    ankle_width_mm: dict[str, float] | None = None
    marker_diameter_mm: float | None = None

    @cached_property
    def markers(self) -> MarkerSet:
        """The preset with ``marker_map`` merged over it: which lab label is which landmark or tracks which body."""
        return marker_set(self.marker_set, self.marker_map)


KEYS = ("mass_kg", "stature_m", "sex", "thigh_length_m", "shank_length_m", "leg_length_m", "trial", "static",
        "static_frames", "marker_set", "marker_map", "hip_joint_centre", "disturbances", "knee_width_mm",
        "ankle_width_mm", "marker_diameter_mm")
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


def subject_from_dict(data: Any, path: str | Path = "subject.yaml") -> Subject:
    """Validate the parsed ``subject.yaml``; every problem is an :class:`InputError` naming the key."""
    if not isinstance(data, dict):
        raise InputError(path, None, "expected a YAML mapping with mass_kg, stature_m and sex")
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
    for key in ("trial", "static"):
        if data.get(key) is not None and not isinstance(data[key], str):
            raise InputError(path, key, f"got {shown(data[key])} (expected a file name)")
    frames = data.get("static_frames")
    if frames is not None and frames != "auto":
        ok = (isinstance(frames, (list, tuple)) and len(frames) == 2
              and all(isinstance(f, int) and not isinstance(f, bool) for f in frames) and 1 <= frames[0] <= frames[1])
        if not ok:
            raise InputError(path, "static_frames", f"got {shown(frames)} (expected [first, last] frame numbers, "
                                                    "1-based, or auto)")
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
    return Subject(mass_kg=mass, stature_m=stature, sex=sex, trial=data.get("trial"), static=data.get("static"),
                   static_frames=frames, marker_map=dict(marker_map), disturbances=tuple(disturbances),
                   marker_set=preset, hip_joint_centre=hip, **lengths, **widths)


def load_subject(path: str | Path) -> Subject:
    """Read and validate ``subject.yaml``."""
    path = Path(path)
    if not path.is_file():
        raise InputError(path, None, "file not found (every trial folder needs a subject.yaml)")
    data = read_yaml(path)
    return subject_from_dict(data, path)


@dataclass(frozen=True)
class TrialFolder:
    """The files of one trial folder, checked to exist."""

    folder: Path
    subject_path: Path
    subject: Subject
    trial_path: Path  # the dynamic C3D, or markers.csv
    forces_path: Path | None = None  # forces.csv when the trial is given as CSV
    static_path: Path | None = None

    @property
    def name(self) -> str:
        return self.folder.name

    def input_files(self) -> list[Path]:
        return [p for p in (self.subject_path, self.trial_path, self.forces_path, self.static_path) if p]


def _named_file(folder: Path, name, key: str) -> Path | None:
    """The file ``subject.yaml`` names under ``key`` (None when it names none): a path relative to the trial
    folder that resolves (symlinks followed) to an existing file inside it."""
    if name is None or name == "":
        return None
    subject = folder / "subject.yaml"
    if not isinstance(name, str):
        raise InputError(subject, key, f"got {shown(name)} (expected a file name inside the trial folder)")
    path = folder / name
    inside = folder.resolve()
    if Path(name).is_absolute() or not path.resolve().is_relative_to(inside):
        raise InputError(subject, key, f"names {shown(name)}, which is outside the trial folder {folder} "
                                       "(expected a file inside it)")
    if not path.is_file():
        raise InputError(subject, key, f"names {shown(name)}, which is not in {folder}")
    return path


def open_trial(folder: str | Path) -> TrialFolder:
    """Find and validate a trial folder's files; raise :class:`InputError` naming what is missing."""
    folder = Path(folder)
    if not folder.is_dir():
        raise InputError(folder, None, "trial folder not found")
    subject = load_subject(folder / "subject.yaml")
    forces = None
    trial = _named_file(folder, subject.trial, "trial")
    if trial is None and (folder / "trial.c3d").is_file():
        trial = folder / "trial.c3d"
    elif trial is None and (folder / "markers.csv").is_file():
        trial = folder / "markers.csv"
        forces = folder / "forces.csv" if (folder / "forces.csv").is_file() else None
    elif trial is None:
        raise InputError(folder / "trial.c3d", None, "file not found (expected trial.c3d, markers.csv, "
                                                     "or `trial:` in subject.yaml)")
    static = _named_file(folder, subject.static, "static")
    if static is None and (folder / "static.c3d").is_file():
        static = folder / "static.c3d"
    return TrialFolder(folder=folder, subject_path=folder / "subject.yaml", subject=subject,
                       trial_path=trial, forces_path=forces, static_path=static)


def sha256(path: str | Path) -> str:
    """SHA-256 of a file's bytes (provenance in HDF5 attributes)."""
    digest = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()
