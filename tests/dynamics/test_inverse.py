"""Inverse dynamics (3.19–3.22): static known answers, the residual mapping, the required
whole-body wrench, frame conversions and NaN handling."""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.dynamics.equations import ExternalWrench
from gaitcli.dynamics.inverse import express_in, inverse_dynamics, required_external_wrench
from gaitcli.errors import InputError
from gaitcli.kinematics.forward import forward_kinematics
from gaitcli.kinematics.model import JOINT_CHILD, JOINT_PARENT
from tests.dynamics.synthetic_model import random_parameters, random_wrenches, sine_motion

G = 9.81
G_VEC = np.array([0.0, 0.0, -G])
RIGHT_LEG, LEFT_LEG = [2, 3, 4], [5, 6, 7]


@pytest.fixture(scope="module")
def static_case():
    """A still, non-trivial posture (5 frames of different postures), q̇ = q̈ = 0."""
    rng = np.random.default_rng(31)
    params = random_parameters(rng)
    q, _, _ = sine_motion(rng, np.array([0.0, 0.3, 0.7, 1.1, 1.6]))
    zero = np.zeros_like(q)
    return params, q, zero, forward_kinematics(q, params)


def _static_moment(st, params, bodies, about):
    """Moment about ``about`` (n, 3) that holds the weights of ``bodies`` still: −Σ (r_b − c) × m_b g."""
    return -sum(np.cross(st.com_m[:, b] - about, params.mass_kg[b] * G_VEC) for b in bodies)


def test_standing_without_ground_reaction_leaves_the_weight_as_residual(static_case):
    params, q, zero, st = static_case
    res = inverse_dynamics(q, zero, zero, params, gravity_m_s2=G)
    expected_force = np.tile([0.0, 0.0, params.total_mass_kg * G], (q.shape[0], 1))  # −(total weight)
    np.testing.assert_allclose(res.residual_force_N, expected_force, atol=1e-10)
    np.testing.assert_allclose(res.residual_moment_Nm, _static_moment(st, params, range(8), st.com_m[:, 0]), atol=1e-10)
    hip = st.joint_centre_m[:, 1]
    np.testing.assert_allclose(res.joint_moments_global_Nm[:, 1], _static_moment(st, params, RIGHT_LEG, hip),
                               atol=1e-10)
    leg_weight = np.broadcast_to(params.mass_kg[RIGHT_LEG].sum() * G_VEC, (5, 3))
    np.testing.assert_allclose(res.joint_forces_N[:, 1], -leg_weight, atol=1e-10)


def test_weight_through_the_centre_of_mass_gives_zero_residual(static_case):
    params, q, zero, st = static_case
    n, weight = q.shape[0], params.total_mass_kg * G
    com = np.einsum("b,nbi->ni", params.mass_kg, st.com_m) / params.total_mass_kg
    cop = com * [1.0, 1.0, 0.0]  # on the floor below the whole-body CoM
    grf = ExternalWrench(4, np.tile([0.0, 0.0, weight], (n, 1)), cop)
    res = inverse_dynamics(q, zero, zero, params, [grf], gravity_m_s2=G)
    np.testing.assert_allclose(res.residual_force_N, 0, atol=1e-10)
    np.testing.assert_allclose(res.residual_moment_Nm, 0, atol=1e-10)
    # right hip: hold the right leg's weight and the whole body's weight standing on the right foot
    hip_r, hip_l = st.joint_centre_m[:, 1], st.joint_centre_m[:, 4]
    expected = _static_moment(st, params, RIGHT_LEG, hip_r) - np.cross(cop - hip_r, grf.force_N)
    np.testing.assert_allclose(res.joint_moments_global_Nm[:, 1], expected, atol=1e-9)
    np.testing.assert_allclose(res.joint_moments_global_Nm[:, 4], _static_moment(st, params, LEFT_LEG, hip_l),
                               atol=1e-10)


def test_residual_is_minus_an_extra_wrench_on_the_pelvis():
    # the required wrench on the right foot makes the data consistent; an additional known wrench
    # (force F at a point p, free moment L) on the pelvis must come back as residual −F, −(L + (p − r) × F)
    rng = np.random.default_rng(32)
    params = random_parameters(rng)
    t = np.linspace(0, 1, 40)
    q, qd, qdd = sine_motion(rng, t)
    st = forward_kinematics(q, params)
    force, moment = required_external_wrench(q, qd, qdd, params)
    ground = ExternalWrench(4, force, np.zeros_like(force), moment)
    extra_f, extra_l = rng.normal(0, 50, (40, 3)), rng.normal(0, 10, (40, 3))
    extra_p = st.com_m[:, 0] + rng.normal(0, 0.2, (40, 3))
    res = inverse_dynamics(q, qd, qdd, params, [ground, ExternalWrench(0, extra_f, extra_p, extra_l)])
    np.testing.assert_allclose(res.residual_force_N, -extra_f, atol=1e-9)
    expected_moment = -(extra_l + np.cross(extra_p - st.com_m[:, 0], extra_f))
    np.testing.assert_allclose(res.residual_moment_Nm, expected_moment, atol=1e-9)


def test_required_external_wrench_gives_zero_residual_about_any_point():
    rng = np.random.default_rng(33)
    params = random_parameters(rng)
    t = np.linspace(0, 2, 80)
    q, qd, qdd = sine_motion(rng, t)
    point = np.c_[q[:, 0], np.zeros((80, 2))]  # on the floor below the pelvis
    force, moment = required_external_wrench(q, qd, qdd, params, point_m=point)
    res = inverse_dynamics(q, qd, qdd, params, [ExternalWrench(7, force, point, moment)])
    np.testing.assert_allclose(res.residual_force_N, 0, atol=1e-9)
    np.testing.assert_allclose(res.residual_moment_Nm, 0, atol=1e-9)
    assert np.abs(moment).max() > 10 and np.abs(force[:, 2] - params.total_mass_kg * G).max() > 10


def test_moment_vectors_reproduce_the_generalized_forces_and_frames():
    rng = np.random.default_rng(34)
    params = random_parameters(rng)
    t = np.linspace(0, 1, 20)
    q, qd, qdd = sine_motion(rng, t)
    res = inverse_dynamics(q, qd, qdd, params, random_wrenches(rng, t))
    st = forward_kinematics(q, params, jacobians=True)
    for j, (p, c) in enumerate(zip(JOINT_PARENT, JOINT_CHILD)):
        axes = st.jacobian_rotation[:, c, :, 6 + 3 * j:9 + 3 * j]  # flexion, adduction, rotation axes
        np.testing.assert_allclose(np.einsum("nik,ni->nk", axes, res.joint_moments_global_Nm[:, j]),
                                   res.generalized_forces[:, 6 + 3 * j:9 + 3 * j], atol=1e-9)
        np.testing.assert_allclose(st.rotation[:, c] @ res.joint_moments_distal_Nm[:, j, :, None],
                                   res.joint_moments_global_Nm[:, j, :, None], atol=1e-9)
        np.testing.assert_allclose(st.rotation[:, p] @ res.joint_moments_proximal_Nm[:, j, :, None],
                                   res.joint_moments_global_Nm[:, j, :, None], atol=1e-9)
    # rotation about z by 90°: global x is the frame's −y
    np.testing.assert_allclose(express_in(np.array([1.0, 0, 0]), np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]])),
                               [0.0, -1.0, 0.0], atol=1e-15)


def test_nan_frames_stay_local():
    rng = np.random.default_rng(35)
    params = random_parameters(rng)
    t = np.linspace(0, 1, 12)
    q, qd, qdd = sine_motion(rng, t)
    q[4:6, 18:21] = np.nan  # hip_l not tracked in two frames
    res = inverse_dynamics(q, qd, qdd, params)
    bad_moment = np.isnan(res.joint_moments_global_Nm).any(axis=2)
    expected = np.zeros((12, 7), dtype=bool)
    expected[4:6, 4:] = True  # left hip, knee, ankle in frames 4-5; lumbar and right leg unaffected
    np.testing.assert_array_equal(bad_moment, expected)
    np.testing.assert_array_equal(np.flatnonzero(np.isnan(res.residual_force_N).any(axis=1)), [4, 5])


def test_shape_mismatch_is_an_input_error(static_case):
    params, q, zero, _ = static_case
    with pytest.raises(InputError, match="qdd"):
        inverse_dynamics(q, zero, zero[:-1], params)


def test_moments_about_another_point_balance_the_same_loads():
    """A weightless foot held still by the shank against a ground force F at a point C: about any point P the
    joint moment balances the ground's, M_P + (C − P) × F = 0; so moments_about(M_J, −F, J, P) from the moment
    about J equals the statics about P directly."""
    from gaitcli.dynamics.inverse import moments_about

    rng = np.random.default_rng(4)
    ground, cop = np.array([12.0, -30.0, 700.0]), np.array([0.10, 0.02, 0.0])
    J, P = rng.normal(size=3) * 0.05 + [0, 0, 0.08], rng.normal(size=3) * 0.05 + [0, 0, 0.08]
    force_on_foot = -ground  # the shank holds the foot against the ground force (statics, no weight)
    M_J, M_P = -np.cross(cop - J, ground), -np.cross(cop - P, ground)
    got = moments_about(M_J[None, None], force_on_foot[None, None], J[None, None], P[None, None])
    np.testing.assert_allclose(got[0, 0], M_P, atol=1e-12)
    assert np.linalg.norm(M_P - M_J) > 1.0  # the points differ enough for the shift to matter
