"""Lab → model axis inference on synthetic walkers in known lab orientations."""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.core.recording import ForcePlate, Markers, Recording
from gaitcli.io.axes import apply_rotation, infer_lab_to_model, snap_to_axis, vertical_from_markers

# 6 markers of a standing body in model axes (x forward, y left, z up): head, shoulders, pelvis, feet.
BODY_M = np.array([
    [0.00, 0.00, 1.70], [0.00, 0.20, 1.45], [0.00, -0.20, 1.45],
    [0.00, 0.12, 0.95], [0.05, 0.10, 0.05], [-0.05, -0.10, 0.05],
])


def _walker(n_frames=60, speed_m_s=1.3, rate_hz=100.0, heading_rad=0.0, rng=None):
    """Markers (frames, 6, 3) in model-like axes walking along heading (rad from +x), with 2 mm noise."""
    t = np.arange(n_frames) / rate_hz
    direction = np.array([np.cos(heading_rad), np.sin(heading_rad), 0.0])
    c, s = np.cos(heading_rad), np.sin(heading_rad)
    Rz = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    p = (BODY_M @ Rz.T)[None] + speed_m_s * t[:, None, None] * direction
    if rng is not None:
        p = p + rng.normal(0, 0.002, p.shape)
    return p


def _proper(R):
    return np.allclose(R @ R.T, np.eye(3), atol=1e-12) and np.isclose(np.linalg.det(R), 1.0)


# Lab orientations as model_to_lab rotations: z-up rotated about z, y-up (OpenSim-like), x-up, z-down.
LABS = {
    "z_up_identity": np.eye(3),
    "z_up_walk_minus_y": np.array([[0, 1, 0], [-1, 0, 0], [0, 0, 1]], float),
    "y_up": np.array([[1, 0, 0], [0, 0, 1], [0, -1, 0]], float),
    "x_up_walk_z": np.array([[0, 0, 1], [0, -1, 0], [1, 0, 0]], float),
    "z_down": np.array([[1, 0, 0], [0, -1, 0], [0, 0, -1]], float),
}


@pytest.mark.parametrize("name", list(LABS))
def test_markers_only_recover_the_lab_rotation(name):
    """Markers walking along model +x in a lab rotated by a signed permutation: R = model_to_lab^T exactly."""
    model_to_lab = LABS[name]
    assert _proper(model_to_lab)
    rng = np.random.default_rng(1)
    lab = _walker(rng=rng) @ model_to_lab.T  # floor at 0; in the z-down lab the markers sit at z < 0
    R = infer_lab_to_model(lab, [])
    assert _proper(R)
    np.testing.assert_allclose(R, model_to_lab.T, atol=1e-12)


def _plate(force_up_N, up_lab, n=50):
    f = np.zeros((n, 3))
    f[10:40] = force_up_N * up_lab
    return ForcePlate("plate1", f, np.zeros((n, 3)), np.zeros(3), np.zeros((4, 3)), 1000.0)


def test_loaded_plate_decides_vertical_even_when_markers_are_ambiguous():
    """A loaded plate pushing along lab +y makes y up, whatever the marker extents say."""
    rng = np.random.default_rng(2)
    lab = rng.normal(0, 0.3, (1, 6, 3)) + np.array([0.0, 1.0, 0.0])  # a rigid cloud, no body shape
    lab = lab + np.linspace(0, 1.0, 40)[:, None, None] * np.array([0.0, 0.0, -1.0])  # walks along lab -z
    R = infer_lab_to_model(lab, [_plate(700.0, np.array([0.0, 0.999, 0.04]))])
    np.testing.assert_allclose(R[2], [0, 1, 0], atol=1e-12)  # snapped vertical
    np.testing.assert_allclose(R[0], [0, 0, -1], atol=1e-12)  # forward = walking direction
    np.testing.assert_allclose(R[1], np.cross(R[2], R[0]))


def test_forward_snaps_within_10_degrees_and_is_exact_beyond():
    for heading_deg, snapped in ((7.0, True), (25.0, False)):
        lab = _walker(heading_rad=np.radians(heading_deg))
        R = infer_lab_to_model(lab, [])
        expected = [1, 0, 0] if snapped else [np.cos(np.radians(heading_deg)), np.sin(np.radians(heading_deg)), 0]
        np.testing.assert_allclose(R[0], expected, atol=1e-9)
        np.testing.assert_allclose(R[2], [0, 0, 1])
        assert _proper(R)


def test_static_and_two_frame_trials_fall_back_to_lab_axes_with_vertical_fixed():
    y_up = LABS["y_up"]
    for frames in (2, 200):
        lab = _walker(n_frames=frames, speed_m_s=0.0, rng=np.random.default_rng(3)) @ y_up.T
        R = infer_lab_to_model(lab, [])
        # forward falls back to lab x, up is lab y, y_model = z x x = -lab z
        np.testing.assert_allclose(R, [[1, 0, 0], [0, 0, -1], [0, 1, 0]], atol=1e-12)
    empty = np.full((5, 3, 3), np.nan)
    np.testing.assert_allclose(infer_lab_to_model(empty, []), np.eye(3))


def test_gaps_do_not_bias_the_walking_direction():
    """Markers appearing and vanishing (centroid jumps sideways) still give the true direction."""
    lab = _walker(n_frames=100, heading_rad=np.radians(40.0))
    lab[:50, :3] = np.nan  # upper markers seen only in the second half
    lab[60:, 4] = np.nan
    R = infer_lab_to_model(lab, [])
    np.testing.assert_allclose(R[0], [np.cos(np.radians(40)), np.sin(np.radians(40)), 0], atol=1e-9)


def test_vertical_from_markers_and_snap():
    np.testing.assert_allclose(snap_to_axis([0.1, -0.9, 0.2]), [0, -1, 0])
    lab = _walker() @ LABS["y_up"].T
    np.testing.assert_allclose(vertical_from_markers(lab), [0, 1, 0])


def test_apply_rotation_rotates_everything_and_composes():
    rng = np.random.default_rng(4)
    markers = Markers(("A", "B"), rng.normal(size=(5, 2, 3)), 100.0)
    corners = rng.normal(size=(4, 3))
    plate = ForcePlate("p", rng.normal(size=(10, 3)), rng.normal(size=(10, 3)), corners.mean(0), corners, 1000.0)
    rec = Recording(markers, [plate])
    R1 = LABS["y_up"].T
    R2 = LABS["z_up_walk_minus_y"]
    out = apply_rotation(apply_rotation(rec, R1), R2)
    R = R2 @ R1
    np.testing.assert_allclose(out.lab_to_model, R)
    np.testing.assert_allclose(out.markers.positions_m, markers.positions_m @ R.T)
    np.testing.assert_allclose(out.plates[0].moment_Nm, plate.moment_Nm @ R.T)
    np.testing.assert_allclose(out.plates[0].corners_m, corners @ R.T)
    np.testing.assert_allclose(out.plates[0].centre_m, R @ plate.centre_m)
    np.testing.assert_allclose(rec.markers.positions_m, markers.positions_m)  # input untouched
