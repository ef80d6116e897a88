"""Small ``filter.h5`` and ``idyn.h5`` files with known content, in the layout the stage writers use
(:mod:`gaitcli.signal.outputs`, :mod:`gaitcli.dynamics.outputs`), for drawing figures without running a stage.

The trial: 2.2 s at 100 Hz; right strides 0.1–1.1 s and 1.1–2.1 s, one left stride 0.6–1.6 s (toe offs at 60 %).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from gaitcli.core.container import FootLoad, Trial
from gaitcli.core.events import Events
from gaitcli.core.recording import Markers
from gaitcli.dynamics.sagittal import SagittalExport, SagittalMotion
from gaitcli.io.h5 import Dataset, record_datasets, write_h5
from gaitcli.kinematics.anatomical import ANATOMICAL_ANGLES
from gaitcli.kinematics.conventions import PIG_CONVENTION, PIG_MOMENTS
from gaitcli.kinematics.model import COORDINATES, JOINTS, MOMENTS, BodyParameters
from gaitcli.signal.cycles import Stride

RATE_HZ = 100.0
TIME_S = np.arange(221) / RATE_HZ
STRIDES = [Stride("r", 0.1, 1.1, 0.7), Stride("l", 0.6, 1.6, 1.2), Stride("r", 1.1, 2.1, 1.7)]
MASS_KG = 70.0
#: the frames in which the left foot's load is unknown (a stance off the plates): 30–70 % of the left stride
LEFT_UNKNOWN = (TIME_S >= 0.9) & (TIME_S <= 1.3)


def events() -> Events:
    """Heel strikes at each stride's ends, toe offs inside (the strides above)."""
    rows = [(0.1, "r", "heel_strike"), (1.1, "r", "heel_strike"), (2.1, "r", "heel_strike"),
            (0.7, "r", "toe_off"), (1.7, "r", "toe_off"), (0.6, "l", "heel_strike"), (1.6, "l", "heel_strike"),
            (1.2, "l", "toe_off")]
    return Events([round(t * RATE_HZ) for t, _, _ in rows], [t for t, _, _ in rows], [s for _, s, _ in rows],
                  [k for _, _, k in rows], ["plate"] * len(rows))


def hip_flexion_deg(t: np.ndarray) -> np.ndarray:
    """Both hips' flexion: a 1 s sine of 20° amplitude on a drift of 5°/s (so the two right strides differ)."""
    return 20.0 * np.sin(2 * np.pi * (t - 0.1)) + 5.0 * t


def knee_moment_Nm(t: np.ndarray) -> np.ndarray:
    """Both knees' extensor moment: 7 N·m/s · t (0.1 N·m/kg per second at 70 kg)."""
    return 7.0 * t


HIP_MOMENT_NM = 70.0  # 1 N·m/kg
HIP_POWER_W = 140.0  # 2 W/kg


def write_idyn(path: Path, *, powers: bool = True, moments: str = "plug_in_gait", trial: str = "walk") -> Path:
    """An ``idyn.h5``: every angle zero but the hips' flexion (:func:`hip_flexion_deg`); every moment zero but
    the hips' extensor (:data:`HIP_MOMENT_NM`) and the knees' (:func:`knee_moment_Nm`), unknown for the left leg
    in :data:`LEFT_UNKNOWN`; hip power :data:`HIP_POWER_W` (``powers``); residuals (force x = t N, moment
    y = −t N·m); ``moments``: ``plug_in_gait`` (extensor names) or ``coordinate`` (flexion names)."""
    n = TIME_S.size
    angles = np.zeros((n, len(ANATOMICAL_ANGLES)))
    coordinates = np.zeros((n, len(COORDINATES)))
    for s in ("r", "l"):
        angles[:, ANATOMICAL_ANGLES.index(f"hip_{s}_flexion")] = hip_flexion_deg(TIME_S)
        coordinates[:, COORDINATES.index(f"hip_{s}_flexion")] = hip_flexion_deg(TIME_S)
    names, convention = (PIG_MOMENTS, PIG_CONVENTION) if moments == "plug_in_gait" else (MOMENTS, "coordinate")
    sense = "extensor" if moments == "plug_in_gait" else "flexion"
    shown = np.zeros((n, len(names)))
    for s in ("r", "l"):
        shown[:, names.index(f"hip_{s}_{sense}_moment")] = HIP_MOMENT_NM
        shown[:, names.index(f"knee_{s}_{sense}_moment")] = knee_moment_Nm(TIME_S)
    known = np.ones((n, len(JOINTS)), np.int8)
    known[np.ix_(LEFT_UNKNOWN, [JOINTS.index(j) for j in ("hip_l", "knee_l", "ankle_l")])] = 0
    power = np.zeros((n, len(JOINTS)))
    power[:, [JOINTS.index("hip_r"), JOINTS.index("hip_l")]] = HIP_POWER_W
    data = record_datasets("strides", STRIDES)
    data.update(record_datasets("sagittal", sagittal()))
    data.update({
        "time": Dataset(TIME_S, "s"),
        "angles": Dataset(angles, "deg", {"columns": ",".join(ANATOMICAL_ANGLES), "convention": "anatomical"}),
        "coordinates_clinical": Dataset(coordinates, "m, deg", {"columns": ",".join(COORDINATES)}),
        "joint_moments_shown": Dataset(shown, "N*m", {"columns": ",".join(names), "convention": convention}),
        "joint_moments_clinical": Dataset(np.zeros((n, len(MOMENTS))), "N*m", {"columns": ",".join(MOMENTS)}),
        "joint_moments_known": Dataset(known, "1", {"joints": ",".join(JOINTS)}),
        "residuals/force": Dataset(np.column_stack([TIME_S, np.zeros(n), np.zeros(n)]), "N"),
        "residuals/moment": Dataset(np.column_stack([np.zeros(n), -TIME_S, np.zeros(n)]), "N*m"),
        "segments/mass": Dataset(np.full(8, MASS_KG / 8), "kg", {"body_mass_kg": MASS_KG}),
    })
    if powers:
        data["joint_powers"] = Dataset(power, "W", {"joints": ",".join(JOINTS)})
    return write_h5(path, data, {"trial": trial})


def sagittal() -> SagittalExport:
    """The hand-off record: both legs standing still, the left foot's load unknown in :data:`LEFT_UNKNOWN`."""
    zero = np.zeros(TIME_S.size)
    legs = {s: SagittalMotion(TIME_S, zero, zero, zero, zero, zero, zero, zero, zero, side=s) for s in ("r", "l")}
    parameters = BodyParameters(np.full(8, MASS_KG / 8), np.zeros((8, 3, 3)), np.zeros((7, 3)), np.zeros((7, 3)))
    return SagittalExport(legs, {"r": np.ones(TIME_S.size, bool), "l": ~LEFT_UNKNOWN}, events(), parameters, MASS_KG)


#: the markers of the filter file, in order (the figure shows the first four it prefers that are present)
MARKERS = ("ASISr", "CAr", "FMr", "LMr", "CAl", "FMl", "XTRA")
CUTOFF_HZ = 6.0
ANALOG_RATE_HZ = 1000.0


def write_filter(path: Path, *, right_on_plates: bool = True, trial: str = "walk") -> Path:
    """A ``filter.h5``: marker k at (k, 0, t) m, raw = filtered + 1 mm in x; the right foot on one plate
    (vertical force 700 N in its stances) unless ``right_on_plates`` is False; the left never on a plate;
    one plate whose unfiltered vertical force has 2200 samples at :data:`ANALOG_RATE_HZ`."""
    n = TIME_S.size
    positions = np.zeros((n, len(MARKERS), 3))
    positions[:, :, 0] = np.arange(len(MARKERS))
    positions[:, :, 2] = TIME_S[:, None]
    stance = ((TIME_S >= 0.1) & (TIME_S < 0.7)) | ((TIME_S >= 1.1) & (TIME_S < 1.7))
    force = np.zeros((n, 3))
    force[stance, 2] = 700.0
    cop = np.where(stance[:, None], 0.3, np.nan) * np.ones((n, 3))
    right = (FootLoad(force, cop, np.zeros(n), np.ones(n, bool)) if right_on_plates
             else FootLoad.unmeasured(n, ~stance))
    feet = {"r": right, "l": FootLoad.unmeasured(n, np.ones(n, bool))}
    filtered = Trial(Markers(MARKERS, positions, RATE_HZ, first_frame=1), feet, events())
    raw = positions.copy()
    raw[:, :, 0] += 0.001
    data = record_datasets("trial", filtered)
    data["trial/markers/positions_m"].attrs["cutoff_hz"] = CUTOFF_HZ
    data.update({
        "markers/raw": Dataset(raw, "m"),
        "plates/plate1/force": Dataset(force, "N", {"rate_hz": RATE_HZ}),
        "plates/plate1/cop": Dataset(cop, "m", {"rate_hz": RATE_HZ}),
        "plates/plate1/analog/raw_vertical_force": Dataset(np.full(2200, 690.0), "N", {"rate_hz": ANALOG_RATE_HZ}),
    })
    return write_h5(path, data, {"trial": trial})
