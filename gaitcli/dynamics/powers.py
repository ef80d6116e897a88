"""Joint powers: the rate of work of each joint's moment on the relative rotation of its two segments.

``P = M · (ω_child − ω_parent)`` (W), with ``M`` the moment the proximal segment exerts on the distal one and the
angular velocities of the 8-body model (global axes, the same vectors the inverse dynamics used). The sagittal
power is the part about the flexion axis: the components of ``M`` and of the relative angular velocity along the
distal segment's anatomical medio-lateral (y) axis, multiplied. Positive power: the joint's muscles generate
energy (concentric); negative: they absorb it.
"""

from __future__ import annotations

import numpy as np

from gaitcli.kinematics.model import JOINT_CHILD, JOINT_PARENT


def relative_angular_velocity(angular_velocity_rad_s: np.ndarray) -> np.ndarray:
    """(n, 7, 3) rad/s: each joint's child minus parent body angular velocity, global axes."""
    w = np.asarray(angular_velocity_rad_s, dtype=float)
    return w[:, list(JOINT_CHILD)] - w[:, list(JOINT_PARENT)]


def joint_powers(moments_global_Nm: np.ndarray, angular_velocity_rad_s: np.ndarray) -> np.ndarray:
    """Total joint power (n, 7), W: ``M · (ω_child − ω_parent)``."""
    return np.einsum("nji,nji->nj", np.asarray(moments_global_Nm, dtype=float),
                     relative_angular_velocity(angular_velocity_rad_s))


def sagittal_powers(moments_global_Nm: np.ndarray, angular_velocity_rad_s: np.ndarray,
                    flexion_axes: np.ndarray) -> np.ndarray:
    """Sagittal joint power (n, 7), W: ``(M · e)(Δω · e)`` with ``e`` (n, 7, 3) each joint's flexion axis
    (the distal segment's anatomical y axis) in global axes."""
    e = np.asarray(flexion_axes, dtype=float)
    m = np.einsum("nji,nji->nj", np.asarray(moments_global_Nm, dtype=float), e)
    w = np.einsum("nji,nji->nj", relative_angular_velocity(angular_velocity_rad_s), e)
    return m * w
