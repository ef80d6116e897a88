"""Least-squares rigid pose of a marker cluster by SVD (3.3.1, Söderkvist & Wedin 1993).

For each frame the reference cluster ``a_j`` (body frame) is fitted to the measured
markers ``b_j`` (global): minimise (1/n) Σ |R a_j + d − b_j|² (3.5). With centroids
ā, b̄ (3.6) and the correlation matrix D = Σ (b_j − b̄)(a_j − ā)ᵀ (3.10–3.11),
D = U W Vᵀ (3.12) gives R = U diag(1, 1, det(U Vᵀ)) Vᵀ — (3.15) with the reflection
guard of docs/model_constants.md §4 — and d = b̄ − R ā (3.7).

Markers that are NaN in a frame get weight 0 in that frame (3.1.4: "the marker is
simply ignored in the pose reconstruction"); a frame with fewer than 3 usable
markers gets a NaN pose.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

MIN_MARKERS = 3


class RigidPoseFit(NamedTuple):
    """Per-frame result of :func:`fit_rigid_pose`.

    ``R`` (n, 3, 3) maps the reference (body) frame to global; ``d_m`` (n, 3) is where
    the reference frame's origin lies; ``rms_m`` (n,) the root-mean-square residual
    ‖r_Rj‖ (3.4) over the markers used; ``markers_used`` (n,) how many markers entered
    each frame's fit. All NaN where ``markers_used < 3``.
    """

    R: np.ndarray
    d_m: np.ndarray
    rms_m: np.ndarray
    markers_used: np.ndarray

    @property
    def invalid_frames(self) -> np.ndarray:
        """Indices of frames with fewer than 3 usable markers (NaN pose)."""
        return np.flatnonzero(self.markers_used < MIN_MARKERS)


def fit_rigid_pose(reference, current) -> RigidPoseFit:
    """Fit ``reference`` to ``current`` frame by frame (3.5–3.15), vectorised.

    Parameters
    ----------
    reference : array_like
        (k, 3) the cluster in the body frame, m; a NaN row is left out of every fit.
    current : array_like
        (n, k, 3) or (k, 3) the same markers in global axes, m; NaN markers are left out of
        that frame's fit.

    Returns
    -------
    RigidPoseFit
        ``R``, ``d_m``, ``rms_m`` and ``markers_used`` per frame.
    """
    a = np.asarray(reference, dtype=float)
    b = np.asarray(current, dtype=float)
    if b.ndim == 2:
        b = b[None]
    if a.ndim != 2 or a.shape[1] != 3 or b.shape[1:] != a.shape:
        raise ValueError(f"reference (k, 3) and current (n, k, 3) do not match: {a.shape} vs {b.shape}")
    w = (np.all(np.isfinite(b), axis=-1) & np.all(np.isfinite(a), axis=-1)).astype(float)  # (n, k)
    used = w.sum(axis=1)
    safe = np.maximum(used, 1.0)[:, None]
    a0 = np.where(np.isfinite(a), a, 0.0)
    b0 = np.where(w[..., None] > 0, b, 0.0)
    a_bar = (w @ a0) / safe  # (n, 3): reference centroid of the markers seen in each frame (3.6)
    b_bar = np.einsum("nk,nki->ni", w, b0) / safe
    a_tilde = (a0[None] - a_bar[:, None]) * w[..., None]  # (3.11), zero for unused markers
    b_tilde = (b0 - b_bar[:, None]) * w[..., None]
    D = np.einsum("nki,nkj->nij", b_tilde, a_tilde) / safe[..., None]  # (3.10)
    valid = used >= MIN_MARKERS
    D[~valid] = np.eye(3)
    U, _, Vt = np.linalg.svd(D)  # (3.12)
    sign = np.sign(np.linalg.det(U @ Vt))
    sign[sign == 0] = 1.0
    U = U.copy()
    U[..., :, 2] *= sign[:, None]  # U diag(1, 1, det(U Vᵀ)): no reflection (docs/model_constants.md §4)
    R = U @ Vt  # (3.15)
    d = b_bar - np.einsum("nij,nj->ni", R, a_bar)  # (3.7)
    resid = np.einsum("nij,kj->nki", R, a0) + d[:, None] - b0
    rms = np.sqrt(np.sum(w * np.sum(resid ** 2, axis=-1), axis=1) / safe[:, 0])
    R[~valid] = np.nan
    d[~valid] = np.nan
    rms[~valid] = np.nan
    return RigidPoseFit(R, d, rms, used.astype(int))
