"""Anatomical joint angles: Cardan angles between the segments' anatomical frames, as a lab's software reports them.

Every joint is the rotation of the distal frame in the proximal one, decomposed as flexion about the proximal
medio-lateral axis, then a rotation about the floating axis, then about the distal segment's own axis (Grood &
Suntay's joint coordinate system, Cardan y-x-z in the model's segment axes). The pelvis and the foot's
progression are taken against the progression frame (the model axes: x along the walk, z up). Angles are zero
only where the anatomical frames are aligned, not in the standing posture, so a standing contracture or
pelvic tilt stays in the curves.

Two ankle conventions:

* ``plug_in_gait``: Vicon's foot frame (x up, y left, z from toe to heel); the ankle's second rotation is about
  the floating axis (foot rotation), the third about the foot's long axis (inversion; Vicon's AnkleAngles Y is
  its negative, the rotation about the toe → heel axis), dorsiflexion zero with the foot's long axis
  perpendicular to the shank;
* ``isb``: the foot frame x forward, z up (Wu et al. 2002): inversion about the floating axis, then rotation
  about the foot's vertical axis.

All angles in rad with the clinical senses on both sides: hip and knee flexion, ankle dorsiflexion, adduction,
ankle inversion (the sole turned medially) and internal rotation positive; the pelvis as Plug-in Gait reports the
right side (anterior tilt, right side up, right side forward positive; the left side's obliquity and rotation are
the negatives); foot progression internal (toes in) positive.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from gaitcli.kinematics.rotations import matrix_to_joint_angles

ANKLE_CONVENTIONS = ("plug_in_gait", "isb")
#: the columns of Plug-in Gait's foot frame (x up, y left, z toe → heel) in segment axes x forward, y left, z up
PIG_FOOT_AXES = np.array([[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])

PELVIS_ANGLES = ("pelvis_tilt", "pelvis_obliquity", "pelvis_rotation")
#: the pelvis angles a left stride reports negated (Plug-in Gait's LPelvisAngles: the left side up or forward
#: positive), so that each side's cycle reads like the other's and like a normal band
MIRRORED_ON_LEFT = ("pelvis_obliquity", "pelvis_rotation")
SIDE_ANGLES = ("hip_{s}_flexion", "hip_{s}_adduction", "hip_{s}_rotation",
               "knee_{s}_flexion", "knee_{s}_adduction", "knee_{s}_rotation",
               "ankle_{s}_flexion", "ankle_{s}_inversion", "ankle_{s}_rotation", "foot_{s}_progression")
#: the columns of :func:`anatomical_angles` (ankle flexion: dorsiflexion positive)
ANATOMICAL_ANGLES = PELVIS_ANGLES + tuple(c.format(s=s) for s in ("r", "l") for c in SIDE_ANGLES)
SEGMENTS = ("pelvis", "thigh_r", "shank_r", "foot_r", "thigh_l", "shank_l", "foot_l")


def _cardan(proximal: np.ndarray, distal: np.ndarray) -> np.ndarray:
    """(n, 3) Cardan y-x-z angles (about y, about the floating x, about the distal z) of ``distal`` in
    ``proximal``."""
    return matrix_to_joint_angles(np.swapaxes(proximal, -1, -2) @ distal)


def anatomical_angles(frames: Mapping[str, np.ndarray], *, ankle: str = "isb") -> np.ndarray:
    """Anatomical angles (..., 23) in :data:`ANATOMICAL_ANGLES` order, rad, from the segments' anatomical frames
    ``frames[segment]`` (..., 3, 3; columns x forward, y left, z up in model axes, the foot too)."""
    pelvis = frames["pelvis"]
    progression = np.broadcast_to(np.eye(3), pelvis.shape)
    tilt, obliquity, rotation = np.moveaxis(_cardan(progression, pelvis), -1, 0)
    columns = [tilt, -obliquity, rotation]
    for side in ("r", "l"):
        s = 1.0 if side == "r" else -1.0
        thigh, shank, foot = (frames[f"{b}_{side}"] for b in ("thigh", "shank", "foot"))
        hip = _cardan(pelvis, thigh)
        knee = _cardan(thigh, shank)
        columns += [-hip[..., 0], s * hip[..., 1], s * hip[..., 2], knee[..., 0], s * knee[..., 1], s * knee[..., 2]]
        vicon_foot = foot @ PIG_FOOT_AXES
        if ankle == "plug_in_gait":
            # about y, the floating axis (≈ the shank's), the foot's long axis (z, toe → heel: −inversion)
            a = _cardan(shank, vicon_foot)
            columns += [-a[..., 0] - np.pi / 2, -s * a[..., 2], s * a[..., 1]]
        else:
            a = _cardan(shank, foot)
            columns += [-a[..., 0], s * a[..., 1], s * a[..., 2]]
        columns.append(s * _cardan(progression, vicon_foot)[..., 1])
    return np.stack(columns, axis=-1)
