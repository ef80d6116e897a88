"""The walking model's 16 muscles and passive structures (gaitcli/predict/muscles.py): anatomical signs of the
moment arms, the moment-arm matrix two ways (−∂l/∂y vs. B·A, 5.1), and the passive generalized forces."""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.predict.contact import joint_moment_map
from gaitcli.predict.muscles import WalkerMuscles

RNG = np.random.default_rng(5)
#: the model's senses (y4 thigh extension, y5 knee flexion, y6 plantarflexion): which way each muscle pulls
ACTIONS = {"iliopsoas": {3: -1}, "rectus_femoris": {3: -1, 4: -1}, "glutei": {3: +1}, "hamstrings": {3: +1, 4: +1},
           "vasti": {4: -1}, "gastrocnemius": {4: +1, 5: +1}, "tibialis_anterior": {5: -1}, "soleus": {5: +1}}
#: dissertation-sense joint moment = this sign × the muscle model's (flexion, flexion, dorsiflexion) moment
PSI_TO_MODEL = np.array([-1.0, 1.0, -1.0])


@pytest.fixture(scope="module")
def muscles() -> WalkerMuscles:
    return WalkerMuscles()


@pytest.mark.parametrize("name", list(ACTIONS))
def test_each_muscle_pulls_the_way_anatomy_says_on_both_legs(muscles, name):
    y = np.zeros(9)
    R = np.array(muscles.moment_arms(y))
    for side, offset in (("r", 0), ("l", 3)):
        column = R[:, muscles.names.index(f"{name}_{side}")]
        for coordinate in range(3, 6):
            expected = ACTIONS[name].get(coordinate, 0)
            arm = column[coordinate + offset]
            assert (arm > 0.005 if expected > 0 else arm < -0.005 if expected < 0 else abs(arm) < 1e-12), \
                (name, side, coordinate, arm)
        # hip muscles pull on the HAT as hard as on the thigh, the other way
        assert column[2] == pytest.approx(-column[3 + offset], abs=1e-12)


def test_moment_arms_two_ways(muscles):
    # R = −∂l_m/∂yᵀ (what the class computes) equals B·A (5.1): joint-moment map times the muscle model's own
    # moment arms at the leg's joint angles, turned into the model's senses
    B = joint_moment_map()
    for _ in range(5):
        y = np.concatenate([[0.0, 1.0], RNG.uniform(-0.6, 0.6, 7)])
        psi = [np.array(p).ravel() for p in muscles.joint_angles(y)]
        A = np.zeros((6, 16))
        for k, angles in enumerate(psi):
            A[3 * k:3 * k + 3, 8 * k:8 * k + 8] = PSI_TO_MODEL[:, None] * np.array(muscles.muscle.moment_arms(angles))
        np.testing.assert_allclose(np.array(muscles.moment_arms(y)), B @ A, atol=1e-12)


def test_lengthening_velocity_is_minus_the_moment_arms_times_the_rates(muscles):
    y = np.concatenate([[0.0, 1.0], RNG.uniform(-0.6, 0.6, 7)])
    yd = RNG.normal(size=9)
    v = np.array(muscles.velocities(y, yd)).ravel()
    np.testing.assert_allclose(v, -np.array(muscles.moment_arms(y)).T @ yd, atol=1e-12)
    h = 1e-6
    fd = (np.array(muscles.lengths(y + h * yd)).ravel() - np.array(muscles.lengths(y - h * yd)).ravel()) / (2 * h)
    np.testing.assert_allclose(v, fd, atol=1e-8)


def test_passive_forces_are_the_joint_models_moments_through_the_joint_map(muscles):
    B = joint_moment_map()
    y = np.concatenate([[0.0, 1.0], RNG.uniform(-0.6, 0.6, 7)])
    yd = RNG.normal(size=9)
    psi = [np.array(p).ravel() for p in muscles.joint_angles(y)]
    psi_rate = [np.array(p).ravel() for p in muscles.joint_angles(yd)]  # ψ is linear in y: rates alike
    tau = np.concatenate([PSI_TO_MODEL * np.array(muscles.joints.total(p, r)).ravel() for p, r in zip(psi, psi_rate)])
    np.testing.assert_allclose(np.array(muscles.passive(y, yd)).ravel(), B @ tau, atol=1e-10)


def test_hip_angle_is_relative_to_the_hat(muscles):
    # leaning the HAT forward with the thigh fixed in space flexes the hip: the muscle lengths follow the hip angle,
    # not the thigh's absolute angle (no upright-trunk assumption)
    upright = np.zeros(9)
    leaning = upright.copy()
    leaning[2] = 0.2
    thigh_forward = upright.copy()
    thigh_forward[3] = -0.2
    np.testing.assert_allclose(np.array(muscles.lengths(leaning)).ravel()[:8],
                               np.array(muscles.lengths(thigh_forward)).ravel()[:8], atol=1e-12)


def test_a_prosthetic_ankle_removes_soleus_tibialis_and_the_ankle_structures():
    # 5.3.3 (docs/prediction.md, "The prosthesis"): Sol and TA gone, Gas at the knee only with its length at a
    # neutral ankle, no Riener–Edrich ankle moment and their knee moment at a neutral ankle; the device's
    # moment (5.59) on y6 and y9
    from gaitcli.muscles.parameters import JointParameters
    from gaitcli.muscles.passive import JointModel
    from gaitcli.predict.prosthesis import COMMERCIAL_FEET

    foot = COMMERCIAL_FEET["seattle"]
    intact, prosthetic = WalkerMuscles(), WalkerMuscles(prosthesis=foot)
    removed = [n for n, keep in zip(prosthetic.names, prosthetic.present) if not keep]
    assert removed == ["tibialis_anterior_r", "soleus_r", "tibialis_anterior_l", "soleus_l"]
    y = RNG.uniform(-0.3, 0.3, 9)
    y[4], y[7] = 0.6, 0.3  # knees flexed
    yd = RNG.uniform(-2, 2, 9)
    R, R0 = np.array(prosthetic.moment_arms(y)), np.array(intact.moment_arms(y))
    gas = prosthetic.names.index("gastrocnemius_r")
    assert R[5, gas] == 0 and R[4, gas] == pytest.approx(R0[4, gas], abs=1e-12)  # r_k is constant (A.9)
    neutral = y.copy()
    neutral[5] = neutral[8] = 0.0
    np.testing.assert_allclose(np.array(prosthetic.lengths(y)), np.array(intact.lengths(neutral)), atol=1e-12)
    # passive: the intact tissue evaluated with the ankle at neutral, minus its ankle moment, plus the device
    tissue = np.array(prosthetic.tissue(y, yd)).ravel()
    joints = JointModel(JointParameters(prosthetic_ankle=True))
    expected = np.zeros(9)
    for ankle in (5, 8):
        psi = np.array(prosthetic.joint_angles(y)[0 if ankle == 5 else 1]).ravel()
        assert np.array(joints.passive(psi)).ravel()[2] == 0.0  # M_A removed
        knee_neutral = np.array(JointModel().passive(np.array([psi[0], psi[1], 0.0]))).ravel()[1]
        assert np.array(joints.passive(psi)).ravel()[1] == pytest.approx(knee_neutral, abs=1e-12)
    assert tissue[5] == 0.0 and tissue[8] == 0.0  # nothing else spans the ankle
    device = np.array(prosthetic.passive(y, yd)).ravel() - tissue
    expected[5], expected[8] = (foot.moment_Nm(y[k], yd[k], foot.branch_blend_rad()) for k in (5, 8))
    np.testing.assert_allclose(device, expected, atol=1e-10)


def test_strength_scale_scales_every_fmax_and_with_it_the_muscle_mass():
    # 5.3.3's F_max +50 %; muscle mass ∝ F_max (A.13): docs/prediction.md, "Stronger muscles"
    base, strong = WalkerMuscles(), WalkerMuscles(strength_scale=1.5)
    np.testing.assert_allclose(strong.muscle.params.max_isometric_force_N,
                               1.5 * base.muscle.params.max_isometric_force_N)
    np.testing.assert_allclose(strong.muscle.params.muscle_mass_kg, 1.5 * base.muscle.params.muscle_mass_kg)
