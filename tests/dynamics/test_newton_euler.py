"""Recursive Newton–Euler against the global-Jacobian inverse dynamics (two independent
implementations), and against a knee pendulum with an analytic moment."""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.dynamics import inverse
from gaitcli.dynamics.inverse import inverse_dynamics
from gaitcli.dynamics.newton_euler import recursive_newton_euler
from gaitcli.kinematics.model import BodyParameters
from tests.dynamics.synthetic_model import random_parameters, random_wrenches, sine_motion


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_two_implementations_agree_on_exact_synthetic_data(seed, monkeypatch):
    # all 27 coordinates moving, full inertia tensors, wrenches on both feet, HAT and a thigh.
    # Measured agreement (seeds 0-2, 250 frames): moments ≤ 7e-13 N·m of up to 2400 N·m,
    # residual forces ≤ 7e-13 N, residual moments ≤ 1.4e-12 N·m, joint forces ≤ 5e-13 N: round-off.
    monkeypatch.setattr(inverse, "CHUNK_FRAMES", 64)
    rng = np.random.default_rng(seed)
    params = random_parameters(rng)
    t = np.linspace(0.0, 2.5, 250)
    q, qd, qdd = sine_motion(rng, t)
    wrenches = random_wrenches(rng, t)
    gid = inverse_dynamics(q, qd, qdd, params, wrenches)
    ne = recursive_newton_euler(q, qd, qdd, params, wrenches)
    assert np.abs(gid.joint_moments_global_Nm).max() > 100  # loads are not trivially small
    np.testing.assert_allclose(gid.joint_moments_global_Nm, ne.joint_moments_Nm, rtol=0, atol=1e-6)
    np.testing.assert_allclose(gid.joint_forces_N, ne.joint_forces_N, rtol=0, atol=1e-6)
    np.testing.assert_allclose(gid.residual_force_N, ne.residual_force_N, rtol=0, atol=1e-6)
    np.testing.assert_allclose(gid.residual_moment_Nm, ne.residual_moment_Nm, rtol=0, atol=1e-6)


def test_knee_pendulum_has_the_analytic_moment():
    # pelvis, hip and ankle fixed at zero angles; the shank+foot swing about the knee's y axis.
    # With diagonal inertias and CoM offsets in the x-z plane of the shank, the moment on the
    # shank is along y only: τ_y = J θ̈ − g Σ m_b r_bx(θ), J = Σ I_yy + m_b (s_bx² + s_bz²),
    # r_b = Ry(θ) s_b with s_b the CoM of body b relative to the knee in the shank frame.
    rng = np.random.default_rng(3)
    base = random_parameters(rng)
    inertia = np.array([np.diag(np.diag(i)) for i in base.inertia_kgm2])
    jp, jc = base.joint_in_parent_m.copy(), base.joint_in_child_m.copy()
    jc[2, 1] = jp[3, 1] = jc[3, 1] = 0.0  # knee_r in shank, ankle_r in shank and foot
    params = BodyParameters(base.mass_kg, inertia, jp, jc)
    t = np.linspace(0, 2, 101)
    A, w = 0.9, 2 * np.pi * 1.1
    q = np.zeros((t.size, 27))
    qd, qdd = np.zeros_like(q), np.zeros_like(q)
    q[:, 2] = 1.0
    k = 6 + 3 * 2  # knee_r flexion
    q[:, k], qd[:, k], qdd[:, k] = A * np.sin(w * t), A * w * np.cos(w * t), -A * w**2 * np.sin(w * t)
    s_shank = -jc[2]
    s_foot = -jc[2] + jp[3] - jc[3]
    m, g, th = params.mass_kg, 9.81, q[:, k]
    swinging = ((m[3], s_shank), (m[4], s_foot))
    J = inertia[3, 1, 1] + inertia[4, 1, 1] + sum(mb * (s[0] ** 2 + s[2] ** 2) for mb, s in swinging)
    rx = sum(mb * (np.cos(th) * s[0] + np.sin(th) * s[2]) for mb, s in swinging)
    expected = np.zeros((t.size, 3))
    expected[:, 1] = J * qdd[:, k] - g * rx
    for result in (inverse_dynamics(q, qd, qdd, params).joint_moments_global_Nm,
                   recursive_newton_euler(q, qd, qdd, params).joint_moments_Nm):
        np.testing.assert_allclose(result[:, 2], expected, rtol=0, atol=1e-10)
