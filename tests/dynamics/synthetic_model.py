"""Synthetic model, motion and external wrenches with known truth for the dynamics tests.

Body parameters are realistic in size (adult of about 75 kg) but perturbed at random
and have full, non-diagonal inertia tensors; the motion moves all 27 coordinates as
sums of sines, so ``q``, ``q̇`` and ``q̈`` are known analytically.
"""

from __future__ import annotations

import numpy as np

from gaitcli.dynamics.equations import ExternalWrench
from gaitcli.kinematics.model import BodyParameters
from gaitcli.kinematics.rotations import cardan_xyz_to_matrix

_MASS_KG = np.array([11.0, 38.0, 9.5, 3.4, 1.1, 9.5, 3.4, 1.1])
_PRINCIPAL_KGM2 = np.array([[0.10, 0.09, 0.08], [1.6, 1.4, 0.35], [0.15, 0.15, 0.03], [0.045, 0.045, 0.005],
                            [0.001, 0.004, 0.004], [0.15, 0.15, 0.03], [0.045, 0.045, 0.005], [0.001, 0.004, 0.004]])
_JOINT_IN_PARENT_M = np.array([[-0.02, 0.0, 0.06], [0.0, -0.085, -0.06], [0.0, 0.0, -0.24], [0.0, 0.0, -0.24],
                               [0.0, 0.085, -0.06], [0.0, 0.0, -0.24], [0.0, 0.0, -0.24]])
_JOINT_IN_CHILD_M = np.array([[0.0, 0.0, -0.30], [0.0, 0.0, 0.19], [0.0, 0.0, 0.18], [-0.06, 0.0, 0.05],
                              [0.0, 0.0, 0.19], [0.0, 0.0, 0.18], [-0.06, 0.0, 0.05]])


def random_parameters(rng) -> BodyParameters:
    """Masses ±10 %, principal moments ±10 % in randomly rotated principal axes, joint centres ±1 cm."""
    mass = _MASS_KG * rng.uniform(0.9, 1.1, 8)
    axes = cardan_xyz_to_matrix(rng.uniform(-np.pi, np.pi, (8, 3)))
    principal = _PRINCIPAL_KGM2 * rng.uniform(0.95, 1.05, (8, 3))
    inertia = np.einsum("bij,bj,bkj->bik", axes, principal, axes)
    return BodyParameters(mass_kg=mass, inertia_kgm2=inertia,
                          joint_in_parent_m=_JOINT_IN_PARENT_M + rng.uniform(-0.01, 0.01, (7, 3)),
                          joint_in_child_m=_JOINT_IN_CHILD_M + rng.uniform(-0.01, 0.01, (7, 3)))


def sine_motion(rng, t):
    """``(q, qd, qdd)`` (n, 27) at times ``t``: offsets plus two sines per coordinate, pelvis walking at 1.3 m/s."""
    n_coord = 27
    offset = np.r_[0.0, 0.0, 0.95, rng.uniform(-0.2, 0.2, 24)]
    amp = np.r_[0.03, 0.03, 0.02, rng.uniform(0.05, 0.6, 24)][:, None] * rng.uniform(0.5, 1.0, (n_coord, 2))
    freq = rng.uniform(0.5, 2.0, (n_coord, 2))
    phase = rng.uniform(0, 2 * np.pi, (n_coord, 2))
    w = 2 * np.pi * freq
    arg = w[None] * t[:, None, None] + phase[None]
    q = offset + np.sum(amp * np.sin(arg), -1)
    qd = np.sum(amp * w * np.cos(arg), -1)
    qdd = -np.sum(amp * w**2 * np.sin(arg), -1)
    q[:, 0] += 1.3 * t
    qd[:, 0] += 1.3
    return q, qd, qdd


def random_wrenches(rng, t, bodies=(4, 7, 1, 2)):
    """An arbitrary smooth external wrench on each of ``bodies`` (default both feet, HAT and right thigh)."""
    out = []
    for b in bodies:
        base = rng.normal(0, 1, (3, 3))
        s = np.sin(2 * np.pi * rng.uniform(0.5, 2) * t)[:, None]
        force = np.array([50.0, 30.0, 400.0]) * (base[0] + s * base[1])
        point = np.array([0.3, 0.2, 0.5]) * (base[2] + s * base[0]) + np.array([1.0 * t.mean(), 0.0, 0.5])
        moment = 5.0 * (base[1] - s * base[2])
        out.append(ExternalWrench(b, force, point, moment))
    return out
