"""Joint powers: the rate of work of each joint's moment on the relative rotation of its two segments.

``P = M · (ω_child − ω_parent)`` (W), with ``M`` the moment the proximal segment exerts on the distal one and the
segments' angular velocities (global axes): the 8-body model's, or those of the lab's own segment frames
(:func:`frame_angular_velocity`, Plug-in Gait's). The sagittal
power is the part about the flexion axis: the components of ``M`` and of the relative angular velocity along the
distal segment's anatomical medio-lateral (y) axis, multiplied. Positive power: the joint's muscles generate
energy (concentric); negative: they absorb it.
"""

from __future__ import annotations

import numpy as np

from gaitcli.kinematics.model import JOINT_CHILD, JOINT_PARENT


def frame_angular_velocity(rotation: np.ndarray, rate_hz: float) -> np.ndarray:
    """(n, 3) rad/s, global axes: the angular velocity of a frame sampled as rotations (n, 3, 3) at ``rate_hz``,
    ``ω̃ = Ṙ Rᵀ`` with Ṙ by central differences (one-sided at the ends); NaN next to a NaN frame."""
    R = np.asarray(rotation, dtype=float)
    skew = np.gradient(R, 1.0 / rate_hz, axis=0) @ np.swapaxes(R, -1, -2)
    return 0.5 * np.stack([skew[:, 2, 1] - skew[:, 1, 2], skew[:, 0, 2] - skew[:, 2, 0],
                           skew[:, 1, 0] - skew[:, 0, 1]], axis=-1)


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
