"""Elementary rotations and the two Cardan sequences of the 27-DoF model (3.1).

All functions are vectorised: angles have shape ``(..., 3)`` and matrices
``(..., 3, 3)``. Angles are in radians. A matrix ``R`` maps coordinates in the
rotated (child) frame to the reference (parent) frame: ``v_parent = R @ v_child``.

* Pelvis: Cardan x-y-z, successive rotations about the moving axes,
  ``R = Rx(alpha) @ Ry(beta) @ Rz(gamma)``; angles stored as (alpha, beta, gamma).
* Joints: Cardan y-x-z (joint rotation convention), ``R = Ry(beta) @ Rx(alpha) @ Rz(gamma)``;
  angles stored in the order of the output columns: (flexion about y, adduction
  about x, rotation about z) = (beta, alpha, gamma).
"""

from __future__ import annotations

import numpy as np


def rot_x(angle):
    """Rotation matrices about x, shape ``angle.shape + (3, 3)``."""
    c, s = np.cos(angle), np.sin(angle)
    o, z = np.ones_like(c), np.zeros_like(c)
    return np.stack([np.stack([o, z, z], -1), np.stack([z, c, -s], -1), np.stack([z, s, c], -1)], -2)


def rot_y(angle):
    """Rotation matrices about y, shape ``angle.shape + (3, 3)``."""
    c, s = np.cos(angle), np.sin(angle)
    o, z = np.ones_like(c), np.zeros_like(c)
    return np.stack([np.stack([c, z, s], -1), np.stack([z, o, z], -1), np.stack([-s, z, c], -1)], -2)


def rot_z(angle):
    """Rotation matrices about z, shape ``angle.shape + (3, 3)``."""
    c, s = np.cos(angle), np.sin(angle)
    o, z = np.ones_like(c), np.zeros_like(c)
    return np.stack([np.stack([c, -s, z], -1), np.stack([s, c, z], -1), np.stack([z, z, o], -1)], -2)


def cardan_xyz_to_matrix(angles):
    """Pelvis orientation: ``Rx(a) Ry(b) Rz(c)`` from angles ``(..., 3)`` = (a, b, c)."""
    angles = np.asarray(angles, dtype=float)
    return rot_x(angles[..., 0]) @ rot_y(angles[..., 1]) @ rot_z(angles[..., 2])


def matrix_to_cardan_xyz(R):
    """Inverse of :func:`cardan_xyz_to_matrix`; beta in [-pi/2, pi/2]."""
    R = np.asarray(R, dtype=float)
    beta = np.arcsin(np.clip(R[..., 0, 2], -1.0, 1.0))
    alpha = np.arctan2(-R[..., 1, 2], R[..., 2, 2])
    gamma = np.arctan2(-R[..., 0, 1], R[..., 0, 0])
    return np.stack([alpha, beta, gamma], -1)


def joint_angles_to_matrix(angles):
    """Joint rotation ``Ry(flexion) Rx(adduction) Rz(rotation)`` from ``(..., 3)`` = (flex, add, rot)."""
    angles = np.asarray(angles, dtype=float)
    return rot_y(angles[..., 0]) @ rot_x(angles[..., 1]) @ rot_z(angles[..., 2])


def matrix_to_joint_angles(R):
    """Inverse of :func:`joint_angles_to_matrix`: (flexion, adduction, rotation), adduction in [-pi/2, pi/2]."""
    R = np.asarray(R, dtype=float)
    alpha = np.arcsin(np.clip(-R[..., 1, 2], -1.0, 1.0))
    beta = np.arctan2(R[..., 0, 2], R[..., 2, 2])
    gamma = np.arctan2(R[..., 1, 0], R[..., 1, 1])
    return np.stack([beta, alpha, gamma], -1)
