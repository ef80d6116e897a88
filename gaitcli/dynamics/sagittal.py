"""Sagittal export for the muscle stage (4.5.1): per side thigh, knee and ankle angles, hip path, GRF.

The thigh and shank angles are planar, in the model's x–z plane (x forward along
the walk), from the joint centres: the thigh angle is the hip→knee line's angle
from the downward vertical, positive when the knee is in front of the hip; knee
flexion is the thigh angle minus the shank angle (knee→ankle line, positive when
the ankle is in front of the knee). The foot has no such line through joint
centres, so ankle dorsiflexion is the 3-D model's ankle flexion coordinate
(clinical sign): zero in the calibration posture, which for a standing static
trial is the foot flat and ⟂ the shank, the muscle model's neutral (A.9).
"""

from __future__ import annotations

import numpy as np

from gaitcli.kinematics.model import COORDINATES, JOINTS


def _from_vertical(upper, lower):
    """Angle (rad) of the line upper→lower from the downward vertical, positive when lower is in front."""
    d = lower - upper
    return np.arctan2(d[:, 0], -d[:, 2])


def sagittal_columns(time_s, joint_centres_m, q, feet: dict) -> dict[str, np.ndarray]:
    """The columns of ``sagittal.csv`` (4.5.1).

    ``joint_centres_m`` (n, 7, 3) from the model's forward kinematics of the
    coordinates ``q`` (n, 27); ``feet[side]`` with ``force_N`` (n, 3) and ``cop_m``
    (n, 3) of that foot (zero force and NaN COP in swing).
    """
    columns = {"time_s": np.asarray(time_s)}
    for s in ("r", "l"):
        hip = joint_centres_m[:, JOINTS.index(f"hip_{s}")]
        knee = joint_centres_m[:, JOINTS.index(f"knee_{s}")]
        ankle = joint_centres_m[:, JOINTS.index(f"ankle_{s}")]
        thigh = _from_vertical(hip, knee)
        shank = _from_vertical(knee, ankle)
        # Cardan y of the ankle is plantarflexion in the model's signs (3.1)
        dorsiflexion = -np.asarray(q)[:, COORDINATES.index(f"ankle_{s}_flexion")]
        columns[f"hip_x_{s}_m"] = hip[:, 0]
        columns[f"hip_z_{s}_m"] = hip[:, 2]
        columns[f"thigh_angle_{s}_deg"] = np.degrees(thigh)
        columns[f"knee_flexion_{s}_deg"] = np.degrees(thigh - shank)
        columns[f"ankle_dorsiflexion_{s}_deg"] = np.degrees(dorsiflexion)
        load = feet.get(s)
        n = hip.shape[0]
        force = np.zeros((n, 3)) if load is None else np.nan_to_num(np.asarray(load["force_N"]))
        cop = np.full((n, 3), np.nan) if load is None else np.asarray(load["cop_m"])
        columns[f"grf_x_{s}_N"] = force[:, 0]
        columns[f"grf_z_{s}_N"] = force[:, 2]
        columns[f"cop_x_{s}_m"] = cop[:, 0]
    return columns
