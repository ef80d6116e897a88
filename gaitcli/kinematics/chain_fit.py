"""Pose of the whole chain by least squares (``pose: chain_lsq``): the 27 coordinates that put every tracking
marker closest to where it was measured, frame by frame.

The dissertation fits each segment on its own (3.3.1, :mod:`gaitcli.kinematics.pose`) and keeps only the
rotations: the distal segments then hang from the pelvis by the joint constraints (3.3.2), so an error of the
hip centre or of the thigh cluster is handed down to the knee and the ankle. Here the coordinates ``q`` of the
model (3.1) minimise Σ_j |p_j(q) − m_j|² over all tracking markers of all bodies (unit weights; a marker not
seen in a frame has weight 0), by Gauss–Newton vectorised over frames, started from the segment fit. A marker
j of body b sits at p_j = c_b(q) + S_b(q) a_j; its Jacobian is J_T,b − [S_b a_j]× J_R,b with the chain's
translational and rotational Jacobians (2.3, 2.4). The coordinates of a body locked to its parent stay 0.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gaitcli.core.recording import Markers
from gaitcli.kinematics.calibration import StaticCalibration
from gaitcli.kinematics.forward import forward_kinematics
from gaitcli.kinematics.model import BODIES, JOINT_CHILD

#: Gauss–Newton stops when no coordinate moves by more than this (m or rad), or after ``MAX_ITERATIONS``
STEP_TOLERANCE = 1e-9
MAX_ITERATIONS = 20
#: Levenberg damping of the normal equations (relative to their diagonal), for frames near a Cardan singularity
DAMPING = 1e-9


@dataclass
class ChainFit:
    """``q`` (n, 27) the fitted coordinates (NaN where the start was); ``segment_rms_m`` (n, 8) each body's RMS
    marker residual (NaN for bodies without tracking markers); ``iterations`` of Gauss–Newton."""

    q: np.ndarray
    segment_rms_m: np.ndarray
    iterations: int


def _marker_sets(markers: Markers, calibration: StaticCalibration):
    """Per tracked body: its index, the reference cluster (k, 3) and the measured markers (n, k, 3)."""
    out = []
    n = markers.n_frames
    for b, body in enumerate(BODIES):
        labels = calibration.tracking_landmarks[body]
        if not labels:
            continue
        measured = np.stack([markers.get(lab) if lab in markers else np.full((n, 3), np.nan) for lab in labels],
                            axis=1)
        out.append((b, calibration.cluster(body), measured))
    return out


def _residuals(states, sets):
    """Residuals (n, M, 3) and Jacobians (n, M, 3, 27) of every tracking marker, weights (n, M)."""
    r, J, w = [], [], []
    for b, cluster, measured in sets:
        arm = np.einsum("nij,kj->nki", states.rotation[:, b], cluster)  # S_b a_j
        p = states.com_m[:, b, None, :] + arm
        seen = np.all(np.isfinite(measured), axis=-1)
        r.append(np.where(seen[..., None], p - np.nan_to_num(measured), 0.0))
        JT, JR = states.jacobian_translation[:, b], states.jacobian_rotation[:, b]  # (n, 3, 27)
        # ω × (S a) = −(S a) × ω: J = J_T − [S a]× J_R, column by column
        cross = np.cross(arm[:, :, None, :], np.swapaxes(JR, 1, 2)[:, None])  # (n, k, 27, 3)
        J.append(JT[:, None] - np.swapaxes(cross, 2, 3))
        w.append(seen.astype(float))
    return np.concatenate(r, axis=1), np.concatenate(J, axis=1), np.concatenate(w, axis=1)


def fit_chain(q0: np.ndarray, markers: Markers, calibration: StaticCalibration) -> ChainFit:
    """The chain's least-squares coordinates from the start ``q0`` (n, 27) (see the module docstring)."""
    q = np.array(q0, dtype=float)
    ok = np.all(np.isfinite(q), axis=1)
    free = np.ones(q.shape[1], bool)
    for body in calibration.locked:  # a locked body's joint angles stay 0
        j = JOINT_CHILD.index(BODIES.index(body))
        free[6 + 3 * j: 9 + 3 * j] = False
    sets = _marker_sets(markers, calibration)
    params = calibration.body
    iterations = 0
    if ok.any():
        qk = q[ok]
        subset = [(b, cluster, measured[ok]) for b, cluster, measured in sets]
        for _ in range(MAX_ITERATIONS):
            states = forward_kinematics(qk, params, jacobians=True)
            r, J, w = _residuals(states, subset)
            J = J[..., free].reshape(qk.shape[0], -1, int(free.sum()))
            wr = (w[..., None] * r).reshape(qk.shape[0], -1)
            W = np.repeat(w, 3, axis=1)
            H = np.einsum("nmi,nm,nmj->nij", J, W, J)
            H += DAMPING * np.einsum("nii->ni", H).max(axis=1)[:, None, None] * np.eye(H.shape[1])
            step = -np.linalg.solve(H, np.einsum("nmi,nm->ni", J, wr)[..., None])[..., 0]
            qk[:, free] += step
            if np.abs(step).max() < STEP_TOLERANCE:
                break
        q[ok] = qk
    rms = np.full((q.shape[0], len(BODIES)), np.nan)
    if ok.any():
        states = forward_kinematics(q[ok], params)
        for b, cluster, measured in sets:
            p = states.com_m[:, b, None, :] + np.einsum("nij,kj->nki", states.rotation[:, b], cluster)
            d2 = np.sum((p - measured[ok]) ** 2, axis=-1)
            seen = np.isfinite(d2)
            with np.errstate(invalid="ignore", divide="ignore"):
                rms[ok, b] = np.sqrt(np.where(seen, d2, 0.0).sum(axis=1) / seen.sum(axis=1))
    return ChainFit(q=q, segment_rms_m=rms, iterations=iterations)
