"""Equations of motion of the 27-DoF model by Newton–Euler with the global Jacobian (2.10–2.13).

Per body ``i`` Newton's and Euler's equations (2.8–2.9) in global axes are

    m_i a_i = f^e_i + f^r_i,    I_i α_i + ω_i × I_i ω_i = l^e_i + l^r_i,

with ``I_i = S_i I_i,body S_iᵀ`` the inertia tensor about the CoM in global axes.
Writing ``a_i = J_T,i ÿ + ā_i`` and ``α_i = J_R,i ÿ + ᾱ_i`` (2.6–2.7) and
premultiplying the stacked system (2.10) by the transposed global Jacobian
``J̄ᵀ`` (2.12) eliminates the reaction wrenches and gives (2.13)

    M(y) ÿ + k(y, ẏ) = q(y, ẏ),
    M = Σ_i J_T,iᵀ m_i J_T,i + J_R,iᵀ I_i J_R,i,
    k = Σ_i J_T,iᵀ m_i ā_i + J_R,iᵀ (I_i ᾱ_i + ω_i × I_i ω_i),
    q = Σ_i J_T,iᵀ f^e_i + J_R,iᵀ l^e_i.

Applied wrenches are gravity (``−g e_z`` on every CoM) and the external wrenches
given as :class:`ExternalWrench` (a force at a global point plus a free moment on
one body, e.g. a ground reaction at the centre of pressure). Joint moments are
not part of ``q`` here: in inverse dynamics they are what the 21 reduced rows of
``M ÿ + k − q`` equal (3.21).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gaitcli.core.physics import GRAVITY_M_S2
from gaitcli.errors import InputError
from gaitcli.kinematics.forward import N_BODIES, N_COORDINATES, BodyStates, forward_kinematics
from gaitcli.kinematics.model import JOINT_CHILD, JOINT_PARENT, BodyParameters

#: frames per block in :func:`generalized_forces`; bounds memory at about 2 MB per 100 frames
CHUNK_FRAMES = 2048


@dataclass
class ExternalWrench:
    """An external wrench on body ``body``: force ``force_N`` (n, 3) applied at the global point
    ``point_m`` (n, 3) plus a free moment ``moment_Nm`` (n, 3), all in global axes.

    ``point_m`` may be NaN in frames where ``force_N`` is exactly zero (no contact,
    undefined centre of pressure); those frames then contribute only ``moment_Nm``.
    ``moment_Nm=None`` means no free moment.
    """

    body: int
    force_N: np.ndarray
    point_m: np.ndarray
    moment_Nm: np.ndarray | None = None

    def __post_init__(self):
        self.force_N = np.atleast_2d(np.asarray(self.force_N, dtype=float))
        self.point_m = np.atleast_2d(np.asarray(self.point_m, dtype=float))
        if self.moment_Nm is None:
            self.moment_Nm = np.zeros_like(self.force_N)
        self.moment_Nm = np.atleast_2d(np.asarray(self.moment_Nm, dtype=float))
        if not 0 <= int(self.body) < N_BODIES:
            raise InputError(None, "ExternalWrench.body", f"got {self.body} (expected a body index 0..{N_BODIES - 1})")
        self.body = int(self.body)
        for name in ("force_N", "point_m", "moment_Nm"):
            arr = getattr(self, name)
            if arr.ndim != 2 or arr.shape[1] != 3 or arr.shape != self.force_N.shape:
                raise InputError(None, f"ExternalWrench.{name}",
                                 f"got shape {arr.shape} (expected (frames, 3) like force_N)")

    def frames(self, sl: slice) -> ExternalWrench:
        """The same wrench restricted to the frames ``sl``."""
        return ExternalWrench(self.body, self.force_N[sl], self.point_m[sl], self.moment_Nm[sl])


def check_external_wrenches(external, n_frames):
    """Validate a sequence of :class:`ExternalWrench` against the frame count; returns a tuple."""
    external = tuple(external or ())
    for w in external:
        if not isinstance(w, ExternalWrench):
            raise InputError(None, "external", f"got {type(w).__name__} (expected ExternalWrench)")
        if w.force_N.shape[0] != n_frames:
            raise InputError(None, "external",
                             f"wrench on body {w.body} has {w.force_N.shape[0]} frames (expected {n_frames})")
    return external


def check_motion(q, qd, qdd):
    """``q``, ``qd``, ``qdd`` as float arrays of equal shape (frames, 27); a single frame becomes (1, 27)."""
    q = np.atleast_2d(np.asarray(q, dtype=float))
    if q.ndim != 2 or q.shape[1] != N_COORDINATES:
        raise InputError(None, "q", f"got shape {q.shape} (expected (frames, {N_COORDINATES}))")
    out = [q]
    for name, x in (("qd", qd), ("qdd", qdd)):
        x = np.atleast_2d(np.asarray(x, dtype=float))
        if x.shape != q.shape:
            raise InputError(None, name, f"got shape {x.shape} (expected {q.shape} like q)")
        out.append(x)
    return out


def _global_inertia(states: BodyStates, params: BodyParameters):
    """``I_i = S_i I_i,body S_iᵀ`` (n, 8, 3, 3), kg·m², about each CoM in global axes."""
    S = states.rotation
    return np.einsum("nbij,bjk,nblk->nbil", S, np.asarray(params.inertia_kgm2, dtype=float), S)


def applied_body_wrenches(states: BodyStates, params: BodyParameters, external=(), *,
                          gravity_m_s2: float = GRAVITY_M_S2):
    """Stacked applied forces ``f^e`` (n, 8, 3) in N and moments ``l^e`` about each CoM (n, 8, 3) in N·m.

    This is the ``q̄e`` of (2.10): gravity plus the external wrenches.
    """
    n = states.com_m.shape[0]
    mass = np.asarray(params.mass_kg, dtype=float)
    force = np.zeros((n, N_BODIES, 3))
    moment = np.zeros((n, N_BODIES, 3))
    force[:, :, 2] = -gravity_m_s2 * mass
    for w in check_external_wrenches(external, n):
        lever = w.point_m - states.com_m[:, w.body]
        lever = np.where(np.all(w.force_N == 0.0, axis=1)[:, None], 0.0, lever)
        force[:, w.body] += w.force_N
        moment[:, w.body] += w.moment_Nm + np.cross(lever, w.force_N)
    return force, moment


def _gyroscopic(inertia, omega):
    """``ω × I ω`` (n, 8, 3)."""
    return np.cross(omega, np.einsum("nbij,nbj->nbi", inertia, omega))


def dalembert_body_wrenches(states: BodyStates, qdd, params: BodyParameters, external=(), *,
                            gravity_m_s2: float = GRAVITY_M_S2):
    """Per body ``M̄ J̄ ÿ + q̄c − q̄e`` of (2.10): force (n, 8, 3) in N, moment about the CoM (n, 8, 3) in N·m.

    ``states`` must come from ``forward_kinematics(q, params, qd, jacobians=True)``; the
    accelerations are formed here as ``J ÿ`` plus the local terms (2.6–2.7).
    """
    mass = np.asarray(params.mass_kg, dtype=float)
    acc = np.einsum("nbik,nk->nbi", states.jacobian_translation, qdd) + states.local_com_acceleration_m_s2
    alpha = np.einsum("nbik,nk->nbi", states.jacobian_rotation, qdd) + states.local_angular_acceleration_rad_s2
    inertia = _global_inertia(states, params)
    f_e, l_e = applied_body_wrenches(states, params, external, gravity_m_s2=gravity_m_s2)
    force = mass[None, :, None] * acc - f_e
    moment = np.einsum("nbij,nbj->nbi", inertia, alpha) + _gyroscopic(inertia, states.angular_velocity_rad_s) - l_e
    return force, moment


def distal_bodies():
    """For each joint, the indices of the bodies distal to it (its child body and all descendants)."""
    children = {b: [] for b in range(N_BODIES)}
    for p, c in zip(JOINT_PARENT, JOINT_CHILD):
        children[p].append(c)

    def below(b):
        out = [b]
        for c in children[b]:
            out += below(c)
        return out

    return [below(c) for c in JOINT_CHILD]


def project(states: BodyStates, force, moment):
    """``J̄ᵀ`` times stacked body forces/moments (n, 8, 3) → generalized forces (n, 27) (2.13).

    Uses the structure of ``J̄``: the columns of joint ``j`` are zero for bodies not
    distal to ``j``, so those bodies are left out of the sum. Besides saving work this
    keeps a NaN body (segment not tracked) from spreading into the rows of joints it
    does not affect.
    """
    JT, JR = states.jacobian_translation, states.jacobian_rotation
    out = np.empty(force.shape[:1] + (JT.shape[-1],))
    out[:, :6] = np.einsum("nbik,nbi->nk", JT[..., :6], force) + np.einsum("nbik,nbi->nk", JR[..., :6], moment)
    for j, bodies in enumerate(distal_bodies()):
        cols = slice(6 + 3 * j, 9 + 3 * j)
        out[:, cols] = (np.einsum("nbik,nbi->nk", JT[:, bodies][..., cols], force[:, bodies])
                        + np.einsum("nbik,nbi->nk", JR[:, bodies][..., cols], moment[:, bodies]))
    return out


def equations_of_motion(q, qd, params: BodyParameters, external=(), *, gravity_m_s2: float = GRAVITY_M_S2):
    """Mass matrix ``M`` (n, 27, 27), Coriolis/gyroscopic vector ``k`` (n, 27), applied forces ``q`` (n, 27) (2.13).

    Units: rows of translational coordinates in N (``M`` in kg), rows of angles in
    N·m per rad (``M`` in kg·m²); ``external`` is a sequence of :class:`ExternalWrench`.
    """
    states = forward_kinematics(q, params, qd, jacobians=True)
    JT, JR = states.jacobian_translation, states.jacobian_rotation
    mass = np.asarray(params.mass_kg, dtype=float)
    inertia = _global_inertia(states, params)
    M = np.einsum("nbik,b,nbil->nkl", JT, mass, JT) + np.einsum("nbik,nbij,nbjl->nkl", JR, inertia, JR)
    coriolis_force = mass[None, :, None] * states.local_com_acceleration_m_s2
    coriolis_moment = (np.einsum("nbij,nbj->nbi", inertia, states.local_angular_acceleration_rad_s2)
                       + _gyroscopic(inertia, states.angular_velocity_rad_s))
    k = project(states, coriolis_force, coriolis_moment)
    q_applied = project(states, *applied_body_wrenches(states, params, external, gravity_m_s2=gravity_m_s2))
    return M, k, q_applied


def generalized_forces(q, qd, qdd, params: BodyParameters, external=(), *, gravity_m_s2: float = GRAVITY_M_S2):
    """``M ÿ + k − q`` (n, 27) as ``J̄ᵀ (M̄ J̄ ÿ + q̄c − q̄e)``, without forming ``M`` (2.10–2.13, 3.19).

    Processed in blocks of :data:`CHUNK_FRAMES` frames. Rows 0–5 are the pelvis
    residuals ``r`` (3.22), rows 6–26 the generalized joint forces of (3.21).
    """
    q, qd, qdd = check_motion(q, qd, qdd)
    external = check_external_wrenches(external, q.shape[0])
    out = np.empty(q.shape)
    for start in range(0, q.shape[0], CHUNK_FRAMES):
        sl = slice(start, start + CHUNK_FRAMES)
        states = forward_kinematics(q[sl], params, qd[sl], jacobians=True)
        ext = [w.frames(sl) for w in external]
        out[sl] = project(states, *dalembert_body_wrenches(states, qdd[sl], params, ext,
                                                           gravity_m_s2=gravity_m_s2))
    return out
