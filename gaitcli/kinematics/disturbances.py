"""Disturbances: the rigid masses added to the model's bodies in the experiments (3.1.1, Tables A.2–A.3).

The dissertation's added masses (:data:`DISTURBANCE_TABLE`: shoes, weight band, knee
orthosis, vario shoes, ski boot), the experiments' presets that place them
(:func:`preset_disturbances`), and their addition to a segment by the parallel-axis
theorem (:func:`combine`).

Axes and units: SI throughout (kg, m, kg m²). The table's moments of inertia are
about the added mass's own CoM, about axes X, Y, Z parallel to the global frame in
the reference posture (x forward, y left, z up). A :class:`Disturbance` is expressed
in the axes of the segments it is added to (its ``com_offset_m`` relative to the
body's CoM before it is added); :func:`preset_disturbances` places the presets in the
axes of the segments it is given (the calibration passes body axes).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from gaitcli.core.validate import one_of
from gaitcli.errors import InputError, shown
from gaitcli.kinematics.anthropometry import SegmentInertia, parallel_axis


@dataclass(frozen=True, eq=False)
class Disturbance:
    """A rigid mass added to a body: ``com_offset_m`` from the body's CoM before it is added,
    ``inertia_kgm2`` (3×3) about its own CoM, both in the body's axes (Table A.2: axes
    parallel to the global frame in the reference posture)."""

    segment: str
    mass_kg: float
    inertia_kgm2: np.ndarray
    com_offset_m: np.ndarray = field(default_factory=lambda: np.zeros(3))
    name: str = ""


def _as_tensor(inertia_kgm2) -> np.ndarray:
    a = np.asarray(inertia_kgm2, dtype=float)
    if a.shape == (3,):
        a = np.diag(a)
    if a.shape != (3, 3):
        raise InputError(None, "inertia_kgm2", f"got shape {a.shape} (expected 3 values or a 3x3 tensor)")
    return a


def combine(segment: SegmentInertia, mass_kg: float, inertia_kgm2, com_offset_m) -> SegmentInertia:
    """Rigidly attach a mass to ``segment`` (parallel-axis theorem).

    ``com_offset_m`` is the added mass's CoM relative to the segment's CoM,
    ``inertia_kgm2`` (3 diagonal values or 3×3) about its own CoM, both in the
    segment's axes. The combined CoM moves by ``c = m₂ o / (m₁ + m₂)`` and
    ``I = I₁ + m₁ P(−c) + I₂ + m₂ P(o − c)`` with ``P(r) = |r|² E − r rᵀ``.
    """
    m2 = float(mass_kg)
    if not np.isfinite(m2) or m2 < 0:
        raise InputError(None, "mass_kg", f"got {shown(mass_kg)} (expected a number >= 0)")
    I2 = _as_tensor(inertia_kgm2)
    o = np.asarray(com_offset_m, dtype=float).reshape(3)
    m1 = segment.mass_kg
    m = m1 + m2
    c = m2 * o / m
    inertia = segment.inertia_kgm2 + parallel_axis(m1, -c) + I2 + parallel_axis(m2, o - c)
    return replace(segment, mass_kg=m, com_m=segment.com_m + c, inertia_kgm2=inertia)


def add_disturbance(params: Mapping[str, SegmentInertia], segment: str, mass_kg: float, inertia_kgm2,
                    com_offset_m=(0.0, 0.0, 0.0), *, name: str = "disturbance") -> dict[str, SegmentInertia]:
    """Return a copy of ``params`` with a disturbance added to body ``segment`` (see :func:`combine`)."""
    one_of(segment, tuple(params), where="disturbances.segment")
    out = dict(params)
    seg = combine(params[segment], mass_kg, inertia_kgm2, com_offset_m)
    out[segment] = replace(seg, notes=seg.notes + (f"+ {name} {float(mass_kg):.3f} kg",))
    return out


def apply_disturbances(params: Mapping[str, SegmentInertia],
                       disturbances: Iterable[Disturbance]) -> dict[str, SegmentInertia]:
    """Add each :class:`Disturbance` in turn (offsets relative to the CoM before each one)."""
    out = dict(params)
    for d in disturbances:
        out = add_disturbance(out, d.segment, d.mass_kg, d.inertia_kgm2, d.com_offset_m,
                              name=d.name or "disturbance")
    return out


#: Tables A.2–A.3: mass (kg) and moments of inertia about X, Y, Z (kg m²), axes of the reference posture
DISTURBANCE_TABLE = {
    "shoes_subject1": (0.319, (0.0, 0.0017, 0.0017)),
    "shoes_subject2": (0.279, (0.0, 0.0014, 0.0014)),
    "weight_band": (1.719, (0.0043, 0.0043, 0.0041)),
    "knee_orthosis": (0.924, (0.026, 0.021, 0.0061)),
    "vario_shoe_right": (0.999, (0.014, 0.015, 0.0055)),
    "vario_shoe_left": (0.497, (0.0013, 0.0040, 0.0027)),
    "ski_boot": (2.431, (0.020, 0.033, 0.012)),
}
#: where the dissertation says only "fixed to the shank just above the ankle joint" (3.1.2):
#: the band's CoM is taken 0.07 m proximal of the ankle joint centre on the shank axis
WEIGHT_BAND_ABOVE_ANKLE_M = 0.07

PRESETS = ("normal", "ankle_weight", "knee_orthosis", "ankle_fixed", "ski_boot", "shoes_subject1", "shoes_subject2")
PRESET_ALIASES = {"weight_band": "ankle_weight", "fixation_shoe": "ankle_fixed", "vario": "ankle_fixed",
                  "orthosis": "knee_orthosis", "weight": "ankle_weight", "ski": "ski_boot"}


def _table_disturbance(key: str, segment: str, offset, inertia=None, mass=None) -> Disturbance:
    m, diag = DISTURBANCE_TABLE[key]
    return Disturbance(segment, m if mass is None else mass,
                       np.diag(diag) if inertia is None else inertia, np.asarray(offset, dtype=float), key)


def preset_disturbances(name: str, segments: Mapping[str, SegmentInertia], *, side: str = "r") -> list[Disturbance]:
    """The disturbances of one experiment of 3.1.1 (Tables A.2–A.3), placed on ``segments``.

    ``segments`` fixes the geometry (lengths, axes, CoMs) the locations refer to, in the
    axes the disturbances should be expressed in. The disturbed side is ``side``
    (the dissertation's experiments disturb the right leg). Locations the
    dissertation does not give:

    * ``ankle_weight``: the weight band on the shank, its CoM on the shank axis
      :data:`WEIGHT_BAND_ABOVE_ANKLE_M` above the ankle joint centre;
    * ``knee_orthosis``: split into a thigh half and a shank half, each of half the
      mass with its CoM on the segment axis a distance ``a = l/4`` from the knee,
      where ``l = sqrt(12 I_t / m)`` is the length of a uniform rod with the table's
      mean transverse inertia ``I_t``; each half gets ``(I_x − m a²)/2``,
      ``(I_y − m a²)/2``, ``I_z/2`` so that with the knee straight the two halves
      recombine exactly to the table's mass, CoM (at the knee) and inertia;
    * ``ankle_fixed`` (vario shoes): the fixing shoe on the disturbed foot and the
      other shoe of the pair on the other foot, at the foot CoM;
    * ``ski_boot``: on the disturbed foot at the foot CoM;
    * ``shoes_subject1/2`` (the usual shoes of experiment 1): one on each foot, at the foot CoM;
    * ``normal``: no disturbance (barefoot model).
    """
    key = PRESET_ALIASES.get(name, name)
    if key not in PRESETS:
        one_of(name, PRESETS + tuple(PRESET_ALIASES), where="disturbance")
    one_of(side, ("r", "l"), where="side")
    other = "l" if side == "r" else "r"
    zero = np.zeros(3)
    if key == "normal":
        return []
    if key == "ankle_weight":
        shank = segments[f"shank_{side}"]
        at = shank.axis * (shank.length_m - WEIGHT_BAND_ABOVE_ANKLE_M)
        return [_table_disturbance("weight_band", f"shank_{side}", at - shank.com_m)]
    if key == "knee_orthosis":
        m, (ix, iy, iz) = DISTURBANCE_TABLE["knee_orthosis"]
        rod_length = np.sqrt(12.0 * (ix + iy) / 2.0 / m)
        a = rod_length / 4.0
        half = np.diag([(ix - m * a * a) / 2.0, (iy - m * a * a) / 2.0, iz / 2.0])
        thigh, shank = segments[f"thigh_{side}"], segments[f"shank_{side}"]
        at_thigh = thigh.axis * (thigh.length_m - a)
        at_shank = shank.axis * a
        return [_table_disturbance("knee_orthosis", f"thigh_{side}", at_thigh - thigh.com_m, half, m / 2),
                _table_disturbance("knee_orthosis", f"shank_{side}", at_shank - shank.com_m, half, m / 2)]
    if key == "ankle_fixed":
        return [_table_disturbance("vario_shoe_right", f"foot_{side}", zero),
                _table_disturbance("vario_shoe_left", f"foot_{other}", zero)]
    if key == "ski_boot":
        return [_table_disturbance("ski_boot", f"foot_{side}", zero)]
    return [_table_disturbance(key, f"foot_{s}", zero) for s in ("r", "l")]


def resolve_disturbances(items: Sequence[Disturbance | str], segments: Mapping[str, SegmentInertia]
                         ) -> list[Disturbance]:
    """Turn a mix of :class:`Disturbance` objects and preset names (``"ankle_weight"``,
    ``"ski_boot:l"`` for the left side) into a flat list of disturbances."""
    out: list[Disturbance] = []
    for item in items:
        if isinstance(item, Disturbance):
            out.append(item)
        else:
            name, _, side = str(item).partition(":")
            out.extend(preset_disturbances(name, segments, side=side or "r"))
    return out
