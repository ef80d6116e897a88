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
