"""Recursive Newton–Euler inverse dynamics (Winter's method, 3.4.1), independent of the equations of motion.

Each body's Newton and Euler equations (2.8–2.9) are solved for the unknown wrench at
its proximal joint, starting at the free ends of the tree and moving towards the
pelvis: feet → shanks → thighs, and HAT (free at its top) → lumbar joint. For body
``b`` with proximal joint ``j`` (force ``F_j`` and moment ``τ_j`` of the proximal on
``b`` at the joint centre ``c_j``) and distal joints ``d`` (where ``b`` receives
``−F_d``, ``−τ_d`` at ``c_d``):

    F_j = m a − m g − F_ext + Σ_d F_d
    τ_j = I α + ω × I ω − (c_j − r) × F_j + Σ_d [(c_d − r) × F_d + τ_d] − L_ext

with ``L_ext`` the external moments about the CoM ``r``. What remains at the pelvis
after its three joints and the measured external wrenches is the residual wrench
(force at the pelvis CoM, moment about it), as in (3.22).

Only :func:`gaitcli.kinematics.forward.forward_kinematics` (positions, rotations,
ω, α and CoM accelerations from its recursive propagation) is shared with the
global-Jacobian path in :mod:`gaitcli.dynamics.equations`; the Jacobians are not used.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gaitcli.core.physics import GRAVITY_M_S2
from gaitcli.kinematics.forward import forward_kinematics
from gaitcli.kinematics.model import BODIES, JOINT_CHILD, JOINT_PARENT, JOINTS, BodyParameters


@dataclass
class NewtonEulerResult:
    """Joint reactions (n, 7, 3) of the proximal on the distal body (global axes) and the pelvis residual wrench.

    ``joint_forces_N`` act at the joint centres; ``joint_moments_Nm`` are the net joint
    moments; ``residual_force_N`` (n, 3) at the pelvis CoM and ``residual_moment_Nm``
    (n, 3) about it, global axes.
    """

    joint_forces_N: np.ndarray
    joint_moments_Nm: np.ndarray
    residual_force_N: np.ndarray
    residual_moment_Nm: np.ndarray


def recursive_newton_euler(q, qd, qdd, params: BodyParameters, external=(), *,
                           gravity_m_s2: float = GRAVITY_M_S2) -> NewtonEulerResult:
    """Joint forces and moments and pelvis residuals by the recursive Newton–Euler method (2.8–2.9).

    ``q``, ``qd``, ``qdd`` (n, 27) in m, rad and their time derivatives;
    ``external`` a sequence of :class:`~gaitcli.dynamics.equations.ExternalWrench`
    (force at a global point plus free moment on one body, e.g. the measured GRF
    on a foot); gravity ``gravity_m_s2`` along −z.
    """
    st = forward_kinematics(q, params, qd, qdd)
    n = st.com_m.shape[0]
    mass = np.asarray(params.mass_kg, dtype=float)
    inertia_body = np.asarray(params.inertia_kgm2, dtype=float)
    g_vec = np.array([0.0, 0.0, -gravity_m_s2])

    # external forces and moments about each body's CoM
    f_ext = np.zeros((n, len(BODIES), 3))
    l_ext = np.zeros((n, len(BODIES), 3))
    for w in external:
        force = np.asarray(w.force_N, dtype=float)
        arm = np.asarray(w.point_m, dtype=float) - st.com_m[:, w.body]
        no_load = ~np.any(force != 0.0, axis=1)
        arm[no_load] = 0.0
        f_ext[:, w.body] += force
        l_ext[:, w.body] += np.cross(arm, force)
        if w.moment_Nm is not None:
            l_ext[:, w.body] += np.asarray(w.moment_Nm, dtype=float)

    proximal_joint = {c: j for j, c in enumerate(JOINT_CHILD)}
    distal_joints = {b: [j for j, p in enumerate(JOINT_PARENT) if p == b] for b in range(len(BODIES))}
    F = np.zeros((n, len(JOINTS), 3))
    T = np.zeros((n, len(JOINTS), 3))
    res_f = res_l = None
    # children have larger indices than their parents: descending order visits the tree leaves-first
    for b in range(len(BODIES) - 1, -1, -1):
        R = st.rotation[:, b]
        I_glob = R @ inertia_body[b] @ np.swapaxes(R, 1, 2)
        w_b = st.angular_velocity_rad_s[:, b]
        r_b = st.com_m[:, b]
        net_force = mass[b] * (st.com_acceleration_m_s2[:, b] - g_vec) - f_ext[:, b]
        net_moment = (np.einsum("nij,nj->ni", I_glob, st.angular_acceleration_rad_s2[:, b])
                      + np.cross(w_b, np.einsum("nij,nj->ni", I_glob, w_b)) - l_ext[:, b])
        for d in distal_joints[b]:
            net_force = net_force + F[:, d]
            net_moment = net_moment + np.cross(st.joint_centre_m[:, d] - r_b, F[:, d]) + T[:, d]
        if b in proximal_joint:
            j = proximal_joint[b]
            F[:, j] = net_force
            T[:, j] = net_moment - np.cross(st.joint_centre_m[:, j] - r_b, net_force)
        else:
            res_f, res_l = net_force, net_moment
    return NewtonEulerResult(joint_forces_N=F, joint_moments_Nm=T, residual_force_N=res_f, residual_moment_Nm=res_l)
