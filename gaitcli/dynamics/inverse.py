"""Inverse dynamics of the 27-DoF model: joint moments and pelvis residuals (3.4.1, (3.19–3.22)).

The generalized forces ``Q = M ÿ + k − q`` (3.19) are evaluated with the global
Jacobian (:mod:`gaitcli.dynamics.equations`), ``q`` holding gravity and the
measured external (ground reaction) wrenches.

* Rows 0–5, the residual equations (3.20), give the residual vector ``r`` (3.22):
  the generalized force of a fictitious wrench on the pelvis. Because the pelvis
  frame's origin is its CoM and the pelvis position is the first coordinate block,
  ``J_T,pelvis = [E 0 0…]`` and ``J_R,pelvis = [0 G 0…]`` with ``G`` the pelvis
  Cardan-rate Jacobian (columns ``e_x``, ``Rx e_y``, ``Rx Ry e_z``). A residual force
  ``F`` at the pelvis CoM and moment ``L`` contribute ``r = [F; Gᵀ L]``; hence
  ``residual_force_N = r[0:3]`` and ``residual_moment_Nm = G⁻ᵀ r[3:6]`` (global axes,
  about the pelvis CoM). Rows 3–5 are not moments about orthogonal axes: they are
  projections of ``L`` onto the three non-orthogonal Cardan axes.
* Rows 6–26, the reduced equations (3.21), give the joint moments: the moment
  vector ``τ_j`` that the proximal body exerts on the distal body at joint ``j``
  has the generalized forces ``Q_j = U_jᵀ τ_j``, ``U_j = [S_p e_y, S_p Ry e_x,
  S_p Ry Rx e_z]`` the global flexion, adduction and rotation axes (columns of
  ``J_R`` of the distal body). The 3×3 system is solved per joint and frame in
  closed form, ``τ = (Q₁ u₂×u₃ + Q₂ u₃×u₁ + Q₃ u₁×u₂) / det U`` (singular only in
  gimbal lock, adduction = ±90°).

Joint reaction forces follow from Newton's law for the subtree distal to each joint
(the sum of ``m a − f^e`` over its bodies).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gaitcli.core.physics import GRAVITY_M_S2
from gaitcli.dynamics.equations import (
    CHUNK_FRAMES,
    check_external_wrenches,
    check_motion,
    dalembert_body_wrenches,
    distal_bodies,
    project,
)
from gaitcli.kinematics.forward import N_COORDINATES, N_JOINTS, forward_kinematics
from gaitcli.kinematics.model import JOINT_CHILD, JOINT_PARENT, BodyParameters


@dataclass
class InverseDynamicsResult:
    """Inverse-dynamics output, n frames, SI units (3.19–3.22).

    ``generalized_forces`` (n, 27): ``M ÿ + k − q`` in N (rows 0–2) and N·m per rad
    (other rows), rows 0–5 the residual vector ``r`` (3.22).
    ``joint_moments_global_Nm`` (n, 7, 3): moment of the proximal on the distal body,
    global axes; ``…_distal_Nm`` / ``…_proximal_Nm`` the same vector in the distal /
    proximal body frame. ``joint_forces_N`` (n, 7, 3): force of the proximal on the
    distal body at the joint centre, global axes. ``residual_force_N`` (n, 3) and
    ``residual_moment_Nm`` (n, 3, about the pelvis CoM): the wrench that would have
    to act on the pelvis to make model and data consistent, global axes.
    """

    generalized_forces: np.ndarray
    joint_moments_global_Nm: np.ndarray
    joint_moments_distal_Nm: np.ndarray
    joint_moments_proximal_Nm: np.ndarray
    joint_forces_N: np.ndarray
    residual_force_N: np.ndarray
    residual_moment_Nm: np.ndarray


def express_in(vectors_global, rotation):
    """Global vectors (..., 3) expressed in the frames ``rotation`` (..., 3, 3) (body → global): ``Sᵀ v``."""
    return np.einsum("...ji,...j->...i", rotation, vectors_global)


def moments_about(moments_global_Nm, forces_global_N, joint_centres_m, points_m):
    """The joint moments (n, 7, 3) N·m about other points (n, 7, 3) m: ``M_P = M_J + (J − P) × F``, with ``M_J``
    the moment of the proximal on the distal body about the model's joint centre ``J`` and ``F`` the force it
    exerts there (global axes). The same force system, its moment taken about ``P`` (a lab's joint centre)."""
    lever = np.asarray(joint_centres_m, dtype=float) - np.asarray(points_m, dtype=float)
    return np.asarray(moments_global_Nm, dtype=float) + np.cross(lever, np.asarray(forces_global_N, dtype=float))


def solve_axis_projections(axes_columns, projections):
    """Vector ``τ`` (n, 3) with ``axes_columns[:, :, k] · τ = projections[:, k]`` for k = 0, 1, 2.

    ``axes_columns`` (n, 3, 3) holds three (non-orthogonal) axes as columns; closed-form
    inverse of the transpose, NaN-propagating and without exceptions.
    """
    u1, u2, u3 = axes_columns[:, :, 0], axes_columns[:, :, 1], axes_columns[:, :, 2]
    c23, c31, c12 = np.cross(u2, u3), np.cross(u3, u1), np.cross(u1, u2)
    det = np.sum(u1 * c23, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        total = projections[:, 0, None] * c23 + projections[:, 1, None] * c31 + projections[:, 2, None] * c12
        return total / det[:, None]


def inverse_dynamics(q, qd, qdd, params: BodyParameters, external=(), *,
                     gravity_m_s2: float = GRAVITY_M_S2) -> InverseDynamicsResult:
    """Joint moments (3.21) and pelvis residuals (3.22) from coordinates and their derivatives.

    Frames are processed in blocks, so memory does not grow with ``n`` beyond the outputs.

    Parameters
    ----------
    q, qd, qdd : array_like
        (n, 27) coordinates (m, rad) and their first and second time derivatives.
    params : BodyParameters
        The calibrated bodies.
    external : sequence of ExternalWrench
        The measured external loads (ground reactions at the centre of pressure plus free moments).
    gravity_m_s2 : float
        Acts along −z.
    """
    q, qd, qdd = check_motion(q, qd, qdd)
    n = q.shape[0]
    external = check_external_wrenches(external, n)
    Q = np.empty((n, N_COORDINATES))
    tau = np.empty((n, N_JOINTS, 3))
    tau_distal = np.empty((n, N_JOINTS, 3))
    tau_proximal = np.empty((n, N_JOINTS, 3))
    joint_force = np.empty((n, N_JOINTS, 3))
    res_moment = np.empty((n, 3))
    subtrees = distal_bodies()
    for start in range(0, n, CHUNK_FRAMES):
        sl = slice(start, start + CHUNK_FRAMES)
        states = forward_kinematics(q[sl], params, qd[sl], jacobians=True)
        force, moment = dalembert_body_wrenches(states, qdd[sl], params, [w.frames(sl) for w in external],
                                                gravity_m_s2=gravity_m_s2)
        Qc = project(states, force, moment)  # (3.19): M ÿ + k − q
        Q[sl] = Qc
        JR = states.jacobian_rotation
        res_moment[sl] = solve_axis_projections(JR[:, 0, :, 3:6], Qc[:, 3:6])  # (3.22)
        for j in range(N_JOINTS):
            k, c, p = 6 + 3 * j, JOINT_CHILD[j], JOINT_PARENT[j]
            t = solve_axis_projections(JR[:, c, :, k:k + 3], Qc[:, k:k + 3])  # (3.21)
            tau[sl, j] = t
            tau_distal[sl, j] = express_in(t, states.rotation[:, c])
            tau_proximal[sl, j] = express_in(t, states.rotation[:, p])
            joint_force[sl, j] = force[:, subtrees[j]].sum(axis=1)
    return InverseDynamicsResult(
        generalized_forces=Q,
        joint_moments_global_Nm=tau,
        joint_moments_distal_Nm=tau_distal,
        joint_moments_proximal_Nm=tau_proximal,
        joint_forces_N=joint_force,
        residual_force_N=Q[:, 0:3].copy(),
        residual_moment_Nm=res_moment,
    )


def required_external_wrench(q, qd, qdd, params: BodyParameters, *, point_m=None, gravity_m_s2: float = GRAVITY_M_S2):
    """Whole-body external wrench the ground must supply for zero residuals: (force_N (n, 3), moment_Nm (n, 3)).

    Force ``F = Σ m_i (a_i + g e_z)``; moment about ``point_m`` (global, (n, 3) or
    (3,), default the global origin) ``L = Σ (r_i − P) × m_i (a_i + g e_z) + I_i α_i +
    ω_i × I_i ω_i``: the rates of change of linear and angular momentum plus the
    weight's wrench. Applying ``F`` at ``P`` plus the free moment ``L`` on any body
    leaves zero pelvis residual (3.22).
    """
    q, qd, qdd = check_motion(q, qd, qdd)
    states = forward_kinematics(q, params, qd, qdd)
    P = np.zeros(3) if point_m is None else np.asarray(point_m, dtype=float)
    mass = np.asarray(params.mass_kg, dtype=float)
    linear = mass[None, :, None] * states.com_acceleration_m_s2
    linear[:, :, 2] += mass * gravity_m_s2
    S = states.rotation
    inertia = np.einsum("nbij,bjk,nblk->nbil", S, np.asarray(params.inertia_kgm2, dtype=float), S)
    w = states.angular_velocity_rad_s
    spin = (np.einsum("nbij,nbj->nbi", inertia, states.angular_acceleration_rad_s2)
            + np.cross(w, np.einsum("nbij,nbj->nbi", inertia, w)))
    lever = states.com_m - np.reshape(P, (-1, 1, 3))
    return linear.sum(axis=1), (np.cross(lever, linear) + spin).sum(axis=1)
