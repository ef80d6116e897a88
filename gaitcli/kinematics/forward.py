"""Forward kinematics of the 8-body, 27-DoF model (2.1.1, 3.2.1).

Given the generalized coordinates ``q`` (frames, 27) in the order of
:data:`gaitcli.kinematics.model.COORDINATES` (3.1), this module returns for every
body its rotation matrix ``S_i`` (body → global), the position ``r_i`` of its
centre of mass (2.2), the joint centres and, given ``qd`` and ``qdd``, the angular
velocity and acceleration (global) and the centre-of-mass velocity and
acceleration. On request it also assembles the global Jacobians of translation
``J_T`` (2.3) and rotation ``J_R`` (2.4) and the local accelerations (2.6–2.7),
i.e. the accelerations at ``qdd = 0``, which are what the equations of motion
(2.10–2.13) are built from.

Two code paths are kept apart on purpose: the velocities and accelerations are
propagated recursively from the pelvis outwards (each Cardan rotation axis ``u``
is fixed in the frame preceding it, so ``d(u)/dt = ω_before × u``), while the
Jacobians are assembled column by column from the same axes. The tests check the
recursion against finite differences of ``S`` and ``r`` (2.5) and the Jacobians
against the recursion (``ω = J_R q̇``, ``α = J_R q̈ + ᾱ``).

Conventions: body frames have their origin at the body's centre of mass; pelvis
``S_1 = Rx Ry Rz`` of the pelvis angles; for joint ``j`` with parent ``p`` and
child ``c``, ``S_c = S_p Ry(flexion) Rx(adduction) Rz(rotation)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gaitcli.errors import InputError
from gaitcli.kinematics.model import BODIES, COORDINATES, JOINT_CHILD, JOINT_PARENT, JOINTS, BodyParameters
from gaitcli.kinematics.rotations import rot_x, rot_y, rot_z

N_BODIES = len(BODIES)
N_JOINTS = len(JOINTS)
N_COORDINATES = len(COORDINATES)


@dataclass
class BodyStates:
    """Per-frame state of the 8 bodies; all vectors in global axes, SI units.

    ``rotation`` (n, 8, 3, 3) maps body to global coordinates (``S_i``); ``com_m``
    (n, 8, 3) the centres of mass (2.2); ``joint_centre_m`` (n, 7, 3). Velocity and
    acceleration fields are ``None`` unless ``qd`` (and ``qdd``) were given.
    ``jacobian_translation`` ``J_T`` (n, 8, 3, 27) (2.3) and ``jacobian_rotation``
    ``J_R`` (n, 8, 3, 27) (2.4) and the local accelerations at ``qdd = 0``
    (``local_*``, (2.6–2.7)) are ``None`` unless ``jacobians=True``.
    """

    rotation: np.ndarray
    com_m: np.ndarray
    joint_centre_m: np.ndarray
    angular_velocity_rad_s: np.ndarray | None = None
    angular_acceleration_rad_s2: np.ndarray | None = None
    com_velocity_m_s: np.ndarray | None = None
    com_acceleration_m_s2: np.ndarray | None = None
    jacobian_translation: np.ndarray | None = None
    jacobian_rotation: np.ndarray | None = None
    local_angular_acceleration_rad_s2: np.ndarray | None = None
    local_com_acceleration_m_s2: np.ndarray | None = None


def _cross(a, b):
    """Cross product along the last axis (faster than ``np.cross`` on small stacks)."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], -1)


def _cross_columns(a, J):
    """``a × J[:, :, k]`` for every column ``k``: ``a`` (n, 3), ``J`` (n, 3, m) → (n, 3, m)."""
    a0, a1, a2 = a[:, 0, None], a[:, 1, None], a[:, 2, None]
    J0, J1, J2 = J[:, 0], J[:, 1], J[:, 2]
    return np.stack([a1 * J2 - a2 * J1, a2 * J0 - a0 * J2, a0 * J1 - a1 * J0], 1)


def _as_frames(x, name, width=N_COORDINATES):
    x = np.asarray(x, dtype=float)
    if x.ndim == 1:
        x = x[None, :]
    if x.ndim != 2 or x.shape[1] != width:
        raise InputError(None, name, f"got shape {x.shape} (expected (frames, {width}))")
    return x


def _pelvis_rotation_and_axes(q):
    """Pelvis ``S_1 = Rx Ry Rz`` (n, 3, 3) and its global Cardan axes ``e_x, Rx e_y, Rx Ry e_z`` (n, 3, 3) as rows."""
    rx = rot_x(q[:, 3])
    rxy = rx @ rot_y(q[:, 4])
    axes = np.empty((q.shape[0], 3, 3))
    axes[:, 0] = (1.0, 0.0, 0.0)
    axes[:, 1] = rx[:, :, 1]
    axes[:, 2] = rxy[:, :, 2]
    return rxy @ rot_z(q[:, 5]), axes


def _rotations_and_axes(q):
    """Body rotations ``S_i`` (n, 8, 3, 3) and the global rotation axes of the 24 Cardan coordinates.

    ``axes[:, k]`` (n, 24, 3) is the unit axis of coordinate ``COORDINATES[3 + k]``: for the
    pelvis ``e_x``, ``Rx e_y``, ``Rx Ry e_z``; for joint ``j`` with parent ``p``
    ``S_p e_y``, ``S_p Ry e_x``, ``S_p Ry Rx e_z``.
    """
    n = q.shape[0]
    R = np.empty((n, N_BODIES, 3, 3))
    axes = np.empty((n, N_COORDINATES - 3, 3))
    R[:, 0], axes[:, 0:3] = _pelvis_rotation_and_axes(q)
    for j in range(N_JOINTS):
        p, c, k = JOINT_PARENT[j], JOINT_CHILD[j], 6 + 3 * j
        a = R[:, p] @ rot_y(q[:, k])
        b = a @ rot_x(q[:, k + 1])
        R[:, c] = b @ rot_z(q[:, k + 2])
        axes[:, k - 3] = R[:, p, :, 1]
        axes[:, k - 2] = a[:, :, 0]
        axes[:, k - 1] = b[:, :, 2]
    return R, axes


def _lever_arms(R, params):
    """Joint centre minus parent CoM ``d_p`` and joint centre minus child CoM ``d_c`` (n, 7, 3), global."""
    jp = np.asarray(params.joint_in_parent_m, dtype=float)
    jc = np.asarray(params.joint_in_child_m, dtype=float)
    d_parent = np.einsum("njab,jb->nja", R[:, list(JOINT_PARENT)], jp)
    d_child = np.einsum("njab,jb->nja", R[:, list(JOINT_CHILD)], jc)
    return d_parent, d_child


def _propagate(axes, d_parent, d_child, qd, qdd):
    """Recursive velocity/acceleration propagation, pelvis outwards (2.3–2.7).

    Returns ω, α, v, a (each (n, 8, 3), global). Each Cardan axis is fixed in the
    frame preceding its rotation, so ``α_after = α_before + u θ̈ + ω_before × u θ̇``;
    CoMs: ``v_c = v_p + ω_p × d_p − ω_c × d_c`` and its derivative.
    """
    n = qd.shape[0]
    w = np.empty((n, N_BODIES, 3))
    al = np.empty((n, N_BODIES, 3))
    v = np.empty((n, N_BODIES, 3))
    a = np.empty((n, N_BODIES, 3))

    def chain(w0, a0, k0):
        wk, ak = w0, a0
        for k in range(k0, k0 + 3):
            u = axes[:, k - 3]
            dw = u * qd[:, k, None]
            ak = ak + u * qdd[:, k, None] + _cross(wk, dw)
            wk = wk + dw
        return wk, ak

    zero = np.zeros((n, 3))
    w[:, 0], al[:, 0] = chain(zero, zero, 3)
    v[:, 0] = qd[:, :3]
    a[:, 0] = qdd[:, :3]
    for j in range(N_JOINTS):
        p, c = JOINT_PARENT[j], JOINT_CHILD[j]
        w[:, c], al[:, c] = chain(w[:, p], al[:, p], 6 + 3 * j)
        dp, dc = d_parent[:, j], d_child[:, j]
        v[:, c] = v[:, p] + _cross(w[:, p], dp) - _cross(w[:, c], dc)
        a[:, c] = (a[:, p] + _cross(al[:, p], dp) + _cross(w[:, p], _cross(w[:, p], dp))
                   - _cross(al[:, c], dc) - _cross(w[:, c], _cross(w[:, c], dc)))
    return w, al, v, a


def _jacobians(axes, d_parent, d_child):
    """Global Jacobians ``J_T`` and ``J_R`` (n, 8, 3, 27) (2.3, 2.4, 2.12).

    ``J_R`` of a child is its parent's plus the three joint axes; ``J_T`` of a child
    is ``J_T,p − d_p × J_R,p + d_c × J_R,c`` (column-wise cross products).
    """
    n = axes.shape[0]
    JR = np.zeros((n, N_BODIES, 3, N_COORDINATES))
    JT = np.zeros((n, N_BODIES, 3, N_COORDINATES))
    JT[:, 0, :, :3] = np.eye(3)
    JR[:, 0, :, 3:6] = np.swapaxes(axes[:, 0:3], 1, 2)
    for j in range(N_JOINTS):
        p, c, k = JOINT_PARENT[j], JOINT_CHILD[j], 6 + 3 * j
        JR[:, c] = JR[:, p]
        JR[:, c, :, k:k + 3] = np.swapaxes(axes[:, k - 3:k], 1, 2)
        JT[:, c] = JT[:, p] - _cross_columns(d_parent[:, j], JR[:, p]) + _cross_columns(d_child[:, j], JR[:, c])
    return JT, JR


def forward_kinematics(q, params: BodyParameters, qd=None, qdd=None, *, jacobians: bool = False) -> BodyStates:
    """Body poses (and velocities, accelerations, Jacobians) from coordinates ``q`` (2.2–2.7, 3.1).

    Parameters
    ----------
    q : array_like
        (n, 27) or one frame (27,): the coordinates of :data:`~gaitcli.kinematics.model.COORDINATES`,
        m and rad.
    params : BodyParameters
        The calibrated bodies.
    qd, qdd : array_like, optional
        (n, 27) first and second time derivatives of ``q`` (m/s, rad/s; m/s², rad/s²).
    jacobians : bool
        Also ``J_T``, ``J_R`` (n, 8, 3, 27) and, with ``qd``, the local accelerations at
        ``qdd = 0`` (2.6–2.7).

    Returns
    -------
    BodyStates
        Global axes, SI; the fields not asked for are None.
    """
    q = _as_frames(q, "q")
    R, axes = _rotations_and_axes(q)
    d_parent, d_child = _lever_arms(R, params)
    com = np.empty((q.shape[0], N_BODIES, 3))
    joint = np.empty((q.shape[0], N_JOINTS, 3))
    com[:, 0] = q[:, :3]
    for j in range(N_JOINTS):
        joint[:, j] = com[:, JOINT_PARENT[j]] + d_parent[:, j]
        com[:, JOINT_CHILD[j]] = joint[:, j] - d_child[:, j]
    states = BodyStates(rotation=R, com_m=com, joint_centre_m=joint)
    if qd is not None:
        qd = _as_frames(qd, "qd")
        if qd.shape != q.shape:
            raise InputError(None, "qd", f"got shape {qd.shape} (expected {q.shape} like q)")
        given_qdd = qdd is not None
        if given_qdd:
            qdd = _as_frames(qdd, "qdd")
            if qdd.shape != q.shape:
                raise InputError(None, "qdd", f"got shape {qdd.shape} (expected {q.shape} like q)")
        w, al, v, a = _propagate(axes, d_parent, d_child, qd, qdd if given_qdd else np.zeros_like(qd))
        states.angular_velocity_rad_s = w
        states.com_velocity_m_s = v
        if given_qdd:
            states.angular_acceleration_rad_s2 = al
            states.com_acceleration_m_s2 = a
        if jacobians:
            if given_qdd:
                _, al, _, a = _propagate(axes, d_parent, d_child, qd, np.zeros_like(qd))
            states.local_angular_acceleration_rad_s2 = al
            states.local_com_acceleration_m_s2 = a
    if jacobians:
        states.jacobian_translation, states.jacobian_rotation = _jacobians(axes, d_parent, d_child)
    return states


def pelvis_rotation_jacobian(q):
    """Pelvis angular-velocity Jacobian ``G`` (n, 3, 3): ``ω_pelvis = G · d/dt(pelvis angles)`` (2.4).

    Columns are the global Cardan axes ``e_x``, ``Rx e_y``, ``Rx Ry e_z``; ``G`` is the
    block of ``J_R,pelvis`` in the pelvis-angle columns.
    """
    q = _as_frames(q, "q")
    return np.swapaxes(_pelvis_rotation_and_axes(q)[1], 1, 2)


def marker_positions(q, params: BodyParameters, markers_in_body: dict) -> dict:
    """Global marker trajectories from body-fixed marker coordinates.

    ``markers_in_body`` maps body index → (k, 3) marker positions in that body's
    frame relative to its CoM (m); returns body index → (n, k, 3) global positions (m).
    """
    states = forward_kinematics(q, params)
    out = {}
    for body, local in markers_in_body.items():
        local = np.asarray(local, dtype=float).reshape(-1, 3)
        if not 0 <= int(body) < N_BODIES:
            raise InputError(None, "markers_in_body", f"got body index {body} (expected 0..{N_BODIES - 1})")
        out[body] = states.com_m[:, body, None, :] + np.einsum("nab,kb->nka", states.rotation[:, body], local)
    return out
