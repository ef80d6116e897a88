"""Markers -> segment poses -> 27 coordinates, against a known q(t) placed on the bodies by a test-local chain."""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.core.numerics import frame_ranges
from gaitcli.core.recording import Markers
from gaitcli.errors import GaitWarning, InputError
from gaitcli.kinematics.calibration import calibrate
from gaitcli.kinematics.coordinates import (
    convert_frames,
    missing_frame_messages,
    poses_to_coordinates,
    track_segments,
    unwrap_angles,
)
from gaitcli.kinematics.markerset import landmarks_to_markers, standing_template
from gaitcli.kinematics.model import BODIES, COORDINATES, JOINT_CHILD, JOINT_PARENT
from gaitcli.kinematics.rotations import cardan_xyz_to_matrix, joint_angles_to_matrix, matrix_to_joint_angles

RATE_HZ = 100.0


@pytest.fixture(scope="module")
def cal():
    return calibrate(landmarks_to_markers(standing_template(1.75)), mass_kg=70.0, stature_m=1.75)


def known_q(n=300):
    """A smooth walking-like q(t); the pelvis turns through more than a full circle to exercise unwrapping."""
    t = np.arange(n) / RATE_HZ
    w = 2 * np.pi / 1.1
    q = np.zeros((n, 27))
    q[:, 0] = 1.2 * t
    q[:, 1] = 0.02 * np.sin(w * t)
    q[:, 2] = 0.95 + 0.02 * np.cos(2 * w * t)
    q[:, 3] = 0.05 * np.sin(w * t)
    q[:, 4] = 0.1 + 0.04 * np.sin(2 * w * t)
    q[:, 5] = np.linspace(-0.5, 2 * np.pi + 1.0, n)
    amplitude = np.array([0.5, 0.12, 0.25])
    for j in range(7):
        phase = 0.7 * j
        q[:, 6 + 3 * j: 9 + 3 * j] = amplitude * np.sin(w * t[:, None] + phase + np.array([0.0, 0.4, 1.1]))
    q[:, 9] += 2.6  # hip_r flexion sweeps through +-pi: the unwrapped column keeps going
    return q


def place_bodies(q, body):
    """Test-local forward chain (reference frames): rotations (n, 8, 3, 3) and CoMs (n, 8, 3)."""
    n = q.shape[0]
    R = np.zeros((n, 8, 3, 3))
    com = np.zeros((n, 8, 3))
    R[:, 0] = cardan_xyz_to_matrix(q[:, 3:6])
    com[:, 0] = q[:, 0:3]
    for j, (p, c) in enumerate(zip(JOINT_PARENT, JOINT_CHILD)):
        R[:, c] = R[:, p] @ joint_angles_to_matrix(q[:, 6 + 3 * j: 9 + 3 * j])
        com[:, c] = (com[:, p] + np.einsum("nij,j->ni", R[:, p], body.joint_in_parent_m[j])
                     - np.einsum("nij,j->ni", R[:, c], body.joint_in_child_m[j]))
    return R, com


def markers_from_q(q, cal, noise_m=0.0, rng=None):
    R, com = place_bodies(q, cal.body)
    labels, tracks = [], []
    for b, name in enumerate(BODIES):
        for lab, local in cal.landmarks_in_body_m[name].items():
            if lab not in labels:
                labels.append(lab)
                tracks.append(com[:, b] + np.einsum("nij,j->ni", R[:, b], local))
    pos = np.stack(tracks, axis=1)
    if noise_m:
        pos = pos + rng.normal(scale=noise_m, size=pos.shape)
    return Markers(tuple(labels), pos, RATE_HZ)


def test_known_motion_is_recovered_exactly(cal):
    q = known_q()
    poses = track_segments(markers_from_q(q, cal), cal)
    out = poses_to_coordinates(poses)
    assert out.shape == (q.shape[0], len(COORDINATES))
    np.testing.assert_allclose(out, q, atol=1e-9)
    R, com = place_bodies(q, cal.body)
    np.testing.assert_allclose(poses.rotation, R, atol=1e-12)
    np.testing.assert_allclose(poses.com_m, com, atol=1e-12)
    assert np.nanmax(poses.joint_gap_m) < 1e-12 and np.nanmax(poses.rms_m) < 1e-12
    assert all(v.size == 0 for v in poses.missing_frames.values())
    assert missing_frame_messages(poses) == []


def test_static_posture_gives_zero_reference_coordinates(cal):
    static = landmarks_to_markers({k: v for k, v in cal.static_landmarks_m.items()})
    q = poses_to_coordinates(track_segments(static, cal))
    np.testing.assert_allclose(q[0, :3], cal.com_m[0], atol=1e-12)
    np.testing.assert_allclose(q[0, 3:], 0.0, atol=1e-12)


def test_noisy_markers_give_small_errors(cal):
    rng = np.random.default_rng(7)
    q = known_q()
    poses = track_segments(markers_from_q(q, cal, noise_m=0.002, rng=rng), cal)
    err = poses_to_coordinates(poses) - q
    rms_position_mm = 1000 * np.sqrt(np.mean(err[:, :3] ** 2))
    rms_angle_deg = np.degrees(np.sqrt(np.mean(err[:, 3:] ** 2, axis=0)))
    # 2 mm noise on clusters of 3-4 markers 0.1-0.3 m across: about a degree, worst for the 3-marker shank/foot
    assert rms_position_mm < 2.0, rms_position_mm
    assert rms_angle_deg.max() < 3.0, dict(zip(COORDINATES[3:], rms_angle_deg.round(2)))
    assert np.nanmedian(poses.rms_m) == pytest.approx(0.002 * np.sqrt(3) * 0.6, rel=0.5)


def test_missing_markers_give_nan_and_messages(cal):
    """A body is untracked wherever a marker of its cluster is missing, also when 3 or more remain (issue 34: a
    smaller cluster's pose jumps at the gap's ends); elsewhere the poses are exact."""
    q = known_q(60)
    markers = markers_from_q(q, cal)
    pos = markers.positions_m.copy()
    pos[10:21, markers.index("GTr")] = np.nan  # thigh_r keeps 3 markers
    pos[30:41, markers.index("TTl")] = np.nan  # shank_l drops to 2 markers
    poses = track_segments(Markers(markers.labels, pos, RATE_HZ, first_frame=1), cal)
    out = poses_to_coordinates(poses)
    np.testing.assert_array_equal(poses.missing_frames["thigh_r"], np.arange(10, 21))
    np.testing.assert_array_equal(poses.missing_frames["shank_l"], np.arange(30, 41))
    assert np.all(np.isnan(out[10:21, COORDINATES.index("hip_r_flexion")]))
    assert np.all(np.isnan(out[30:41, COORDINATES.index("knee_l_flexion")]))
    assert np.all(np.isnan(out[30:41, COORDINATES.index("ankle_l_rotation")]))
    tracked = np.ones(60, bool)
    tracked[10:21] = tracked[30:41] = False
    np.testing.assert_allclose(out[tracked], q[tracked], atol=1e-9)  # unwrapping skips the NaN gaps
    assert missing_frame_messages(poses) == ["segment thigh_r misses a tracking marker in frames 11–21",
                                             "segment shank_l misses a tracking marker in frames 31–41"]


def test_a_marker_the_trial_never_shows_leaves_the_cluster_smaller_throughout(cal):
    """Only a marker the trial shows somewhere makes its absence untrack the body: without GTr at all the thigh
    is fitted to its other three markers in every frame."""
    q = known_q(30)
    markers = markers_from_q(q, cal)
    pos = markers.positions_m.copy()
    pos[:, markers.index("GTr")] = np.nan
    out = poses_to_coordinates(track_segments(Markers(markers.labels, pos, RATE_HZ), cal))
    np.testing.assert_allclose(out, q, atol=1e-9)


def test_locked_hat_follows_the_pelvis():
    t = standing_template(1.75)
    for name in ("C7", "ST", "ACr", "ACl"):
        t.pop(name)
    with pytest.warns(GaitWarning):
        cal = calibrate(landmarks_to_markers(t), mass_kg=70.0, stature_m=1.75)
    q = known_q(50)
    q[:, 6:9] = 0.0
    poses = track_segments(markers_from_q(q, cal), cal)
    np.testing.assert_allclose(poses_to_coordinates(poses), q, atol=1e-9)
    assert "hat" not in poses.missing_frames and poses.locked == ("hat",)


def test_anatomical_frames_convert_both_ways(cal):
    q = known_q(40)
    poses = track_segments(markers_from_q(q, cal), cal)
    anat = convert_frames(poses, cal, "anatomical")
    C = cal.reference_to_anatomical
    np.testing.assert_allclose(anat.rotation, poses.rotation @ C, atol=1e-15)
    back = convert_frames(anat, cal, "reference")
    np.testing.assert_allclose(back.rotation, poses.rotation, atol=1e-14)
    with pytest.raises(InputError, match=r"frames: got 'anatomic' .*did you mean 'anatomical'\?"):
        convert_frames(poses, cal, "anatomic")
    # relative rotation in anatomical frames = C_p^T S_rel C_d (3.17 with both frames)
    qa = poses_to_coordinates(anat, unwrap=False)
    knee = C[2].T @ joint_angles_to_matrix(q[:, 12:15]) @ C[3]
    np.testing.assert_allclose(qa[:, 12:15], matrix_to_joint_angles(knee), atol=1e-12)


def test_helpers():
    assert frame_ranges([3, 4, 5, 9, 11, 12]) == [(3, 5), (9, 9), (11, 12)]
    assert frame_ranges([]) == []
    a = np.array([3.0, -3.0, np.nan, 3.1, -3.0])
    np.testing.assert_allclose(unwrap_angles(a), [3.0, 2 * np.pi - 3.0, np.nan, 3.1, 2 * np.pi - 3.0])
