"""Forward kinematics of the 27-DoF model: poses against the rotation module, velocities and
accelerations against finite differences (2.5), Jacobians against finite differences of r and S."""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.errors import InputError
from gaitcli.kinematics.forward import forward_kinematics, marker_positions, pelvis_rotation_jacobian
from gaitcli.kinematics.model import JOINT_CHILD, JOINT_PARENT
from gaitcli.kinematics.rotations import cardan_xyz_to_matrix, joint_angles_to_matrix, matrix_to_joint_angles
from tests.dynamics.synthetic_model import random_parameters, sine_motion


@pytest.fixture(scope="module")
def setup():
    rng = np.random.default_rng(11)
    params = random_parameters(rng)
    t = np.linspace(0.0, 1.5, 31)
    return params, rng, t


def _vee(W):
    """Vector of a (near) skew-symmetric matrix (n, 3, 3), averaging both halves."""
    return 0.5 * np.stack([W[:, 2, 1] - W[:, 1, 2], W[:, 0, 2] - W[:, 2, 0], W[:, 1, 0] - W[:, 0, 1]], -1)


def test_poses_follow_the_cardan_conventions(setup):
    params, rng, t = setup
    q, _, _ = sine_motion(rng, t)
    st = forward_kinematics(q, params)
    np.testing.assert_allclose(st.rotation[:, 0], cardan_xyz_to_matrix(q[:, 3:6]), atol=1e-14)
    np.testing.assert_allclose(st.com_m[:, 0], q[:, :3], atol=1e-14)
    for j, (p, c) in enumerate(zip(JOINT_PARENT, JOINT_CHILD)):
        angles = q[:, 6 + 3 * j:9 + 3 * j]
        np.testing.assert_allclose(st.rotation[:, c], st.rotation[:, p] @ joint_angles_to_matrix(angles), atol=1e-13)
        rel = np.swapaxes(st.rotation[:, p], 1, 2) @ st.rotation[:, c]
        np.testing.assert_allclose(matrix_to_joint_angles(rel), angles, atol=1e-12)
        # the joint centre seen from the parent and from the child is the same point
        from_parent = st.com_m[:, p] + st.rotation[:, p] @ params.joint_in_parent_m[j]
        from_child = st.com_m[:, c] + st.rotation[:, c] @ params.joint_in_child_m[j]
        np.testing.assert_allclose(from_parent, st.joint_centre_m[:, j], atol=1e-14)
        np.testing.assert_allclose(from_child, st.joint_centre_m[:, j], atol=1e-14)


def test_velocities_and_accelerations_match_finite_differences(setup):
    params, rng, t = setup
    h = 1e-5  # central differences: truncation ~h²·|x'''| ≈ 1e-9, round-off ~1e-16/h ≈ 1e-11
    motion = [sine_motion(np.random.default_rng(5), tt) for tt in (t - h, t, t + h)]  # same motion, shifted times
    (qm, qdm, _), (q, qd, qdd), (qp, qdp, _) = motion
    st = forward_kinematics(q, params, qd, qdd)
    sm, sp = forward_kinematics(qm, params, qdm), forward_kinematics(qp, params, qdp)
    for b in range(8):
        S_dot = (sp.rotation[:, b] - sm.rotation[:, b]) / (2 * h)
        omega_fd = _vee(S_dot @ np.swapaxes(st.rotation[:, b], 1, 2))  # (2.5): ω̃ = Ṡ Sᵀ
        np.testing.assert_allclose(st.angular_velocity_rad_s[:, b], omega_fd, atol=1e-7)
        alpha_fd = (sp.angular_velocity_rad_s[:, b] - sm.angular_velocity_rad_s[:, b]) / (2 * h)
        np.testing.assert_allclose(st.angular_acceleration_rad_s2[:, b], alpha_fd, atol=1e-6)
        v_fd = (sp.com_m[:, b] - sm.com_m[:, b]) / (2 * h)
        np.testing.assert_allclose(st.com_velocity_m_s[:, b], v_fd, atol=1e-7)
        a_fd = (sp.com_velocity_m_s[:, b] - sm.com_velocity_m_s[:, b]) / (2 * h)
        np.testing.assert_allclose(st.com_acceleration_m_s2[:, b], a_fd, atol=1e-6)


def test_jacobians_match_partial_derivatives_and_the_recursion(setup):
    params, rng, t = setup
    q, qd, qdd = sine_motion(rng, t[:5])
    st = forward_kinematics(q, params, qd, qdd, jacobians=True)
    JT, JR = st.jacobian_translation, st.jacobian_rotation
    h = 1e-6
    for k in range(27):
        dq = np.zeros(27)
        dq[k] = h
        sp, sm = forward_kinematics(q + dq, params), forward_kinematics(q - dq, params)
        np.testing.assert_allclose(JT[:, :, :, k], (sp.com_m - sm.com_m) / (2 * h), atol=1e-8)  # (2.3)
        for b in range(8):
            dS = (sp.rotation[:, b] - sm.rotation[:, b]) / (2 * h)
            np.testing.assert_allclose(JR[:, b, :, k], _vee(dS @ np.swapaxes(st.rotation[:, b], 1, 2)), atol=1e-8)
    # (2.3)-(2.7): velocities and accelerations from the Jacobians equal the recursive ones
    np.testing.assert_allclose(np.einsum("nbik,nk->nbi", JR, qd), st.angular_velocity_rad_s, atol=1e-12)
    np.testing.assert_allclose(np.einsum("nbik,nk->nbi", JT, qd), st.com_velocity_m_s, atol=1e-12)
    np.testing.assert_allclose(np.einsum("nbik,nk->nbi", JR, qdd) + st.local_angular_acceleration_rad_s2,
                               st.angular_acceleration_rad_s2, atol=1e-11)
    np.testing.assert_allclose(np.einsum("nbik,nk->nbi", JT, qdd) + st.local_com_acceleration_m_s2,
                               st.com_acceleration_m_s2, atol=1e-11)
    np.testing.assert_allclose(pelvis_rotation_jacobian(q), JR[:, 0, :, 3:6], atol=0)


def test_local_terms_vanish_without_velocity(setup):
    params, rng, t = setup
    q, _, _ = sine_motion(rng, t[:3])
    st = forward_kinematics(q, params, np.zeros_like(q), jacobians=True)
    assert np.all(st.local_com_acceleration_m_s2 == 0) and np.all(st.local_angular_acceleration_rad_s2 == 0)


def test_marker_positions_at_joint_centres(setup):
    params, rng, t = setup
    q, _, _ = sine_motion(rng, t)
    st = forward_kinematics(q, params)
    markers = {3: np.stack([params.joint_in_child_m[3 - 1], params.joint_in_parent_m[3], np.zeros(3)])}
    out = marker_positions(q, params, markers)
    np.testing.assert_allclose(out[3][:, 0], st.joint_centre_m[:, 2], atol=1e-14)  # knee_r
    np.testing.assert_allclose(out[3][:, 1], st.joint_centre_m[:, 3], atol=1e-14)  # ankle_r
    np.testing.assert_allclose(out[3][:, 2], st.com_m[:, 3], atol=0)


def test_single_frame_and_bad_shapes(setup):
    params, rng, t = setup
    q, qd, _ = sine_motion(rng, t[:1])
    assert forward_kinematics(q[0], params).rotation.shape == (1, 8, 3, 3)
    with pytest.raises(InputError, match="q"):
        forward_kinematics(np.zeros((4, 26)), params)
    with pytest.raises(InputError, match="qd"):
        forward_kinematics(q, params, np.zeros((2, 27)))
