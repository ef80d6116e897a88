"""Topology and parameters of the 8-body, 27-DoF full-body model (3.2.1, Fig. 3.8).

Bodies and joints are numbered as in the dissertation's coordinate vector (3.1):
pelvis (root, 6 DoF), HAT above the lumbosacral joint, and for each side thigh,
shank, foot below hip, knee and ankle. Every body frame has its origin at the
body's centre of mass; in the reference (standing) posture its axes are parallel
to the model's global axes (x forward, y left, z up).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

BODIES = ("pelvis", "hat", "thigh_r", "shank_r", "foot_r", "thigh_l", "shank_l", "foot_l")
JOINTS = ("lumbar", "hip_r", "knee_r", "ankle_r", "hip_l", "knee_l", "ankle_l")
#: parent body index of each joint; the child body of joint j is body j + 1
JOINT_PARENT = (0, 0, 2, 3, 0, 5, 6)
JOINT_CHILD = (1, 2, 3, 4, 5, 6, 7)

PELVIS_COORDINATES = ("pelvis_x", "pelvis_y", "pelvis_z", "pelvis_rot_x", "pelvis_rot_y", "pelvis_rot_z")
JOINT_AXES = ("flexion", "adduction", "rotation")  # about y, x, z: Cardan y-x-z
COORDINATES = PELVIS_COORDINATES + tuple(f"{j}_{a}" for j in JOINTS for a in JOINT_AXES)
MOMENTS = tuple(f"{j}_{a}_moment" for j in JOINTS for a in JOINT_AXES)
RESIDUALS = ("residual_force_x", "residual_force_y", "residual_force_z",
             "residual_moment_x", "residual_moment_y", "residual_moment_z")

assert len(COORDINATES) == 27 and len(MOMENTS) == 21


@dataclass
class BodyParameters:
    """Inertial and geometric parameters of the 8 bodies (SI units).

    ``mass_kg[b]``; ``inertia_kgm2[b]`` the 3×3 inertia tensor about the centre of
    mass in body axes; ``joint_in_parent_m[j]`` the centre of joint ``j`` in the
    parent body frame and ``joint_in_child_m[j]`` in the child body frame (both
    relative to the respective centre of mass). ``segment_length_m`` and
    ``notes`` document where the numbers came from (de Leva, disturbances).
    """

    mass_kg: np.ndarray  # (8,)
    inertia_kgm2: np.ndarray  # (8, 3, 3)
    joint_in_parent_m: np.ndarray  # (7, 3)
    joint_in_child_m: np.ndarray  # (7, 3)
    segment_length_m: dict = field(default_factory=dict)
    notes: list = field(default_factory=list)

    @property
    def total_mass_kg(self) -> float:
        return float(np.sum(self.mass_kg))
