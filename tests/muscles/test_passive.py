"""Passive joint moments (Riener & Edrich 1999) and damping (Stein 1996, decision 7)."""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.muscles import JointModel, JointParameters


@pytest.mark.parametrize("angles, moments", [
    # check values of docs/model_constants.md §10: (φ_H, φ_K, φ_A) deg → (M_H, M_K, M_A) N·m
    ((0, 0, 0), (8.58, 10.42, 6.39)),
    ((30, 0, 0), (-1.01, 15.97, 6.39)),
    ((0, 60, 0), (10.62, -4.45, 1.05)),
    ((0, 0, -20), (8.58, 19.55, 42.36)),
    ((20, 60, 10), (7.05, -4.39, -0.57)),
])
def test_riener_edrich_published_values(angles, moments):
    out = JointModel().evaluate("riener_edrich", np.array(angles, float))
    np.testing.assert_allclose(out, moments, atol=0.01)


def test_generalized_signs():
    """Limb coordinates: thigh angle = hip flexion, knee flexion, dorsiflexion = −plantarflexion."""
    joints = JointModel()
    q = np.deg2rad([20.0, 60.0, -10.0])
    m_h, m_k, m_a = joints.evaluate("riener_edrich", np.array([20.0, 60.0, 10.0]))
    np.testing.assert_allclose(joints.evaluate("passive", q), [m_h, m_k, -m_a], rtol=1e-12)
    # strong dorsiflexion is resisted by a plantarflexing (negative) passive moment
    assert joints.evaluate("passive", np.deg2rad([0.0, 0.0, 25.0]))[2] < -20


def test_damping_and_switches():
    joints = JointModel(JointParameters(hip_damping_Nms_per_rad=0.5, knee_damping_Nms_per_rad=0.2,
                                        passive_moments=False))
    qd = np.array([2.0, -3.0, 5.0])
    np.testing.assert_allclose(joints.evaluate("damping", qd), [-1.0, 0.6, 0.0])
    np.testing.assert_allclose(joints.evaluate("passive", np.array([0.3, 0.2, 0.1])), 0.0)
    np.testing.assert_allclose(joints.evaluate("total", np.array([0.3, 0.2, 0.1]), qd), [-1.0, 0.6, 0.0])


def test_sign_conversions_work_on_numpy_and_casadi():
    """The two conventions' sign flips (kinematics/conventions) are pure arithmetic: numpy and SX alike."""
    import casadi as ca

    from gaitcli.kinematics.conventions import muscle_path_angles, riener_edrich_angles, riener_edrich_moments

    psi = np.array([0.3, 0.5, -0.2])  # hip flexion, knee flexion, ankle dorsiflexion (rad)
    np.testing.assert_allclose(muscle_path_angles(*psi), [-0.3, 0.5, 0.2])  # extension, flexion, plantarflexion
    np.testing.assert_allclose(riener_edrich_angles(*psi), np.rad2deg([0.3, 0.5, 0.2]))
    np.testing.assert_allclose(riener_edrich_moments(1.0, 2.0, 3.0), [1.0, 2.0, -3.0])
    x = ca.SX.sym("x", 3)
    f = ca.Function("f", [x], [ca.vertcat(*muscle_path_angles(*ca.vertsplit(x)),
                                          *riener_edrich_angles(*ca.vertsplit(x)))])
    np.testing.assert_allclose(np.array(f(psi)).ravel(),
                               np.r_[muscle_path_angles(*psi), riener_edrich_angles(*psi)], rtol=1e-15)

