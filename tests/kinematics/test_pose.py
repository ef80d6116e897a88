"""SVD least-squares pose (3.5–3.15) with the reflection guard (decision 2)."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from gaitcli.kinematics.pose import fit_rigid_pose

RNG = np.random.default_rng(2024)


def _random_rotations(n):
    return Rotation.random(n, random_state=RNG).as_matrix()


def test_exact_rigid_clusters_are_recovered():
    for k in (3, 4, 6):
        reference = RNG.normal(scale=0.1, size=(k, 3))
        R = _random_rotations(200)
        d = RNG.normal(size=(200, 3))
        current = np.einsum("nij,kj->nki", R, reference) + d[:, None]
        fit = fit_rigid_pose(reference, current)
        np.testing.assert_allclose(fit.R, R, atol=1e-12)
        np.testing.assert_allclose(fit.d_m, d, atol=1e-12)
        assert np.all(fit.rms_m < 1e-12) and np.all(fit.markers_used == k)
        assert fit.invalid_frames.size == 0


def test_near_coplanar_noisy_cluster_never_reflects():
    # four markers within 0.1 mm of a plane, 2 mm noise: U V^T alone is often a reflection here
    reference = np.array([[0.1, 0.0, 0.0], [-0.1, 0.0, 0.0], [0.0, 0.08, 0.0], [0.0, -0.08, 1e-4]])
    n = 2000
    R = _random_rotations(n)
    current = np.einsum("nij,kj->nki", R, reference) + RNG.normal(scale=0.002, size=(n, 4, 3))
    fit = fit_rigid_pose(reference, current)
    np.testing.assert_allclose(np.linalg.det(fit.R), 1.0, atol=1e-12)
    # the test exercises the guard: without it some frames would be reflections
    a = reference - reference.mean(0)
    b = current - current.mean(1, keepdims=True)
    U, _, Vt = np.linalg.svd(np.einsum("nki,kj->nij", b, a))
    assert np.sum(np.linalg.det(U @ Vt) < 0) > 0
    # and the guarded answer is the least-squares rotation (same as scipy's Kabsch on a few frames)
    for i in range(5):
        ref_rot, _ = Rotation.align_vectors(b[i], a)
        np.testing.assert_allclose(fit.R[i], ref_rot.as_matrix(), atol=1e-9)


def test_nan_markers_are_ignored_per_frame():
    k, n = 5, 300
    reference = RNG.normal(scale=0.1, size=(k, 3))
    R = _random_rotations(n)
    d = RNG.normal(size=(n, 3))
    current = np.einsum("nij,kj->nki", R, reference) + d[:, None] + RNG.normal(scale=0.003, size=(n, k, 3))
    mask = RNG.random((n, k)) < 0.35
    current[mask] = np.nan
    fit = fit_rigid_pose(reference, current)
    seen = (~mask).sum(1)
    np.testing.assert_array_equal(fit.markers_used, seen)
    np.testing.assert_array_equal(fit.invalid_frames, np.flatnonzero(seen < 3))
    assert np.all(np.isnan(fit.R[seen < 3])) and np.all(np.isnan(fit.rms_m[seen < 3]))
    for i in np.flatnonzero(seen >= 3)[:40]:  # independent per-frame fit on the visible subset
        ok = ~mask[i]
        a = reference[ok] - reference[ok].mean(0)
        b = current[i, ok] - current[i, ok].mean(0)
        rot, _ = Rotation.align_vectors(b, a)
        np.testing.assert_allclose(fit.R[i], rot.as_matrix(), atol=1e-9)
        np.testing.assert_allclose(fit.d_m[i], current[i, ok].mean(0) - rot.as_matrix() @ reference[ok].mean(0),
                                   atol=1e-9)
        resid = reference[ok] @ fit.R[i].T + fit.d_m[i] - current[i, ok]
        np.testing.assert_allclose(fit.rms_m[i], np.sqrt(np.mean(np.sum(resid ** 2, 1))), rtol=1e-12)
