"""Equations of motion M ÿ + k = q (2.10–2.13) checked against energy and virtual power, independently
of how they are assembled: kinetic energy from body velocities, dT/dt, the potential of gravity and the
power of an external wrench."""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.dynamics import equations
from gaitcli.dynamics.equations import ExternalWrench, equations_of_motion, generalized_forces
from gaitcli.errors import InputError
from gaitcli.kinematics.forward import forward_kinematics
from tests.dynamics.synthetic_model import random_parameters, random_wrenches, sine_motion


@pytest.fixture(scope="module")
def model():
    rng = np.random.default_rng(21)
    return random_parameters(rng)


def _kinetic_energy(q, qd, params):
    """T = Σ ½ m v² + ½ ωᵀ I ω from the body velocities of forward kinematics."""
    st = forward_kinematics(q, params, qd)
    inertia = np.einsum("nbij,bjk,nblk->nbil", st.rotation, params.inertia_kgm2, st.rotation)
    w = st.angular_velocity_rad_s
    return 0.5 * (np.einsum("b,nbi,nbi->n", params.mass_kg, st.com_velocity_m_s, st.com_velocity_m_s)
                  + np.einsum("nbi,nbij,nbj->n", w, inertia, w))


def test_mass_matrix_is_symmetric_positive_definite_and_gives_kinetic_energy(model):
    q, qd, _ = sine_motion(np.random.default_rng(1), np.linspace(0, 1, 11))
    M, _, _ = equations_of_motion(q, qd, model)
    np.testing.assert_allclose(M, np.swapaxes(M, 1, 2), atol=1e-12)
    assert np.linalg.eigvalsh(M).min() > 0
    np.testing.assert_allclose(0.5 * np.einsum("ni,nij,nj->n", qd, M, qd), _kinetic_energy(q, qd, model), rtol=1e-12)


def test_power_balance_checks_the_coriolis_vector(model):
    # dT/dt = q̇ᵀ (M q̈ + k) for any motion; dT/dt by central differences (h = 1e-5 s: error ~1e-8 J/s)
    h = 1e-5
    t = np.linspace(0, 1.5, 16)
    (qm, qdm, _), (q, qd, qdd), (qp, qdp, _) = [sine_motion(np.random.default_rng(2), tt) for tt in (t - h, t, t + h)]
    M, k, _ = equations_of_motion(q, qd, model)
    power = np.einsum("ni,ni->n", qd, np.einsum("nij,nj->ni", M, qdd) + k)
    dT_dt = (_kinetic_energy(qp, qdp, model) - _kinetic_energy(qm, qdm, model)) / (2 * h)
    np.testing.assert_allclose(power, dT_dt, atol=1e-5)
    assert np.abs(power).max() > 50  # the check is not trivially zero


def test_gravity_forces_are_minus_the_potential_gradient(model):
    q, qd, _ = sine_motion(np.random.default_rng(3), np.linspace(0, 1, 5))
    _, _, q_grav = equations_of_motion(q, qd, model, gravity_m_s2=9.81)

    def potential(qq):
        return 9.81 * forward_kinematics(qq, model).com_m[:, :, 2] @ model.mass_kg

    h = 1e-6
    grad = np.stack([(potential(q + h * e) - potential(q - h * e)) / (2 * h) for e in np.eye(27)], -1)
    np.testing.assert_allclose(q_grav, -grad, atol=1e-6)


def test_external_wrench_power(model):
    # virtual power: q_extᵀ q̇ = F · (v + ω × (p − r)) + L · ω for a force F at p and free moment L
    t = np.linspace(0, 1, 9)
    q, qd, _ = sine_motion(np.random.default_rng(4), t)
    wrenches = random_wrenches(np.random.default_rng(5), t)
    _, _, q0 = equations_of_motion(q, qd, model)
    st = forward_kinematics(q, model, qd)
    for w in wrenches:
        _, _, q1 = equations_of_motion(q, qd, model, [w])
        b = w.body
        v_point = st.com_velocity_m_s[:, b] + np.cross(st.angular_velocity_rad_s[:, b], w.point_m - st.com_m[:, b])
        power = np.sum(w.force_N * v_point + w.moment_Nm * st.angular_velocity_rad_s[:, b], axis=1)
        np.testing.assert_allclose(np.einsum("ni,ni->n", q1 - q0, qd), power, atol=1e-9)


def test_generalized_forces_equal_m_qdd_plus_k_minus_q_across_blocks(model, monkeypatch):
    monkeypatch.setattr(equations, "CHUNK_FRAMES", 7)  # blocks that do not divide the frame count
    t = np.linspace(0, 1, 30)
    q, qd, qdd = sine_motion(np.random.default_rng(6), t)
    wrenches = random_wrenches(np.random.default_rng(7), t)
    M, k, qa = equations_of_motion(q, qd, model, wrenches)
    Q = generalized_forces(q, qd, qdd, model, wrenches)
    np.testing.assert_allclose(Q, np.einsum("nij,nj->ni", M, qdd) + k - qa, atol=1e-9)


def test_unloaded_wrench_with_undefined_point_contributes_only_its_free_moment(model):
    t = np.linspace(0, 1, 4)
    q, qd, _ = sine_motion(np.random.default_rng(8), t)
    free = np.tile([0.0, 0.0, 2.0], (4, 1))
    nan_point = ExternalWrench(4, np.zeros((4, 3)), np.full((4, 3), np.nan), free)
    origin = ExternalWrench(4, np.zeros((4, 3)), np.zeros((4, 3)), free)
    a = equations_of_motion(q, qd, model, [nan_point])[2]
    np.testing.assert_array_equal(a, equations_of_motion(q, qd, model, [origin])[2])
    assert np.all(np.isfinite(a))


def test_bad_external_wrenches_are_input_errors(model):
    q = np.zeros((3, 27))
    with pytest.raises(InputError, match="force_N"):
        ExternalWrench(4, np.zeros((3, 2)), np.zeros((3, 3)))
    with pytest.raises(InputError, match="body"):
        ExternalWrench(8, np.zeros((3, 3)), np.zeros((3, 3)))
    with pytest.raises(InputError, match="frames"):
        equations_of_motion(q, q, model, [ExternalWrench(4, np.zeros((2, 3)), np.zeros((2, 3)))])
    with pytest.raises(InputError, match="ExternalWrench"):
        equations_of_motion(q, q, model, [(4, np.zeros((3, 3)))])
