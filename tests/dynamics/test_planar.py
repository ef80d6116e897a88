"""Planar open chains (dynamics/planar.py): known answers for a double pendulum and a free rigid body,
finite-difference Jacobians, energy conservation and a branched floating-base tree."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from gaitcli.dynamics.planar import Joint, PlanarChain, Segment
from gaitcli.errors import InputError
from gaitcli.muscles.evaluation import evaluate

G = 9.81
# two rods: mass, length, CoM from the proximal joint, inertia about the CoM
M1, L1, C1, I1 = 2.0, 0.9, 0.4, 0.15
M2, L2, C2, I2 = 1.3, 0.7, 0.35, 0.05


@pytest.fixture(scope="module")
def pendulum():
    """Double pendulum hanging from the base point; q1 absolute from the downward vertical, q2 relative."""
    segments = [Segment("upper", M1, I1, L1, C1, points={"elbow": (L1, 0.0)}),
                Segment("lower", M2, I2, L2, C2, points={"tip": (L2, 0.0), "side": (0.2, 0.05)})]
    joints = [Joint("q1", None, "upper", absolute=True), Joint("q2", "upper", "lower")]
    return PlanarChain(segments, joints, base="prescribed", gravity_m_s2=G)


def textbook(q, qd):
    """M, k (Coriolis/centrifugal) and gravity forces of the double pendulum (e.g. Spong et al., Robot
    Modeling and Control, 7.3: two-link planar arm; here hanging, angles from the downward vertical)."""
    q1, q2 = q
    d1, d2 = qd
    c2, s2 = np.cos(q2), np.sin(q2)
    m11 = M1 * C1 ** 2 + M2 * (L1 ** 2 + C2 ** 2 + 2 * L1 * C2 * c2) + I1 + I2
    m12 = M2 * (C2 ** 2 + L1 * C2 * c2) + I2
    m22 = M2 * C2 ** 2 + I2
    h = M2 * L1 * C2 * s2
    k = np.array([-h * (2 * d1 * d2 + d2 ** 2), h * d1 ** 2])
    g = -G * np.array([(M1 * C1 + M2 * L1) * np.sin(q1) + M2 * C2 * np.sin(q1 + q2), M2 * C2 * np.sin(q1 + q2)])
    return np.array([[m11, m12], [m12, m22]]), k, g


def test_double_pendulum_matches_textbook(pendulum):
    rng = np.random.default_rng(1)
    for _ in range(50):
        q, qd, qdd = rng.uniform(-np.pi, np.pi, 2), rng.normal(0, 5, 2), rng.normal(0, 20, 2)
        base_acc = rng.normal(0, 3, 2)
        mass, bias, gravity = textbook(q, qd)
        np.testing.assert_allclose(evaluate(pendulum.mass_matrix, q), mass, rtol=0, atol=1e-12)
        np.testing.assert_allclose(evaluate(pendulum.bias, q, qd, np.zeros(2)), bias, rtol=0, atol=1e-12)
        np.testing.assert_allclose(evaluate(pendulum.gravity, q), gravity, rtol=0, atol=1e-12)
        # the Newton–Euler sum is M·q̈ + k − g plus the inertial force of the base acceleration
        tau = evaluate(pendulum.inverse_dynamics, q, qd, qdd, base_acc)
        np.testing.assert_allclose(tau, mass @ qdd + bias - gravity + _base_term(q, base_acc), atol=1e-10)


def _base_term(q, base_acc):
    """Generalized inertial force of a base acceleration: Σ m_i J_iᵀ·A (J_i the CoM Jacobians)."""
    q1, q2 = q
    j1 = C1 * np.array([[np.cos(q1), 0.0], [np.sin(q1), 0.0]])
    j2 = (L1 * np.array([[np.cos(q1), 0.0], [np.sin(q1), 0.0]])
          + C2 * np.array([[np.cos(q1 + q2)] * 2, [np.sin(q1 + q2)] * 2]))
    return (M1 * j1.T + M2 * j2.T) @ base_acc


def test_point_positions_and_jacobians(pendulum):
    """Jacobians against central differences of the positions (1e-7: h² truncation ≈ 1e-12·|x'''|)."""
    rng = np.random.default_rng(2)
    base = np.array([0.3, 1.2])
    q = rng.uniform(-2, 2, 2)
    elbow, tip, side = evaluate(pendulum.points, q, base)
    np.testing.assert_allclose(elbow, base + L1 * np.array([np.sin(q[0]), -np.cos(q[0])]), atol=1e-15)
    np.testing.assert_allclose(tip, elbow + L2 * np.array([np.sin(q.sum()), -np.cos(q.sum())]), atol=1e-15)
    h = 1e-6
    jacobians = evaluate(pendulum.point_jacobians, q)
    for k, jac in enumerate(jacobians):
        fd = np.column_stack([(evaluate(pendulum.points, q + h * e, base)[k]
                               - evaluate(pendulum.points, q - h * e, base)[k]) / (2 * h) for e in np.eye(2)])
        np.testing.assert_allclose(jac, fd, atol=1e-7)


def test_applied_force_is_virtual_work(pendulum):
    """A force at a point of a segment does the work of J_pointᵀ·f; a free moment that of (∂φ/∂q)ᵀ·M."""
    rng = np.random.default_rng(3)
    base = np.array([0.0, 1.0])
    q, f = rng.uniform(-2, 2, 2), rng.normal(0, 50, 2)
    _, _, side = evaluate(pendulum.points, q, base)
    side_jac = evaluate(pendulum.point_jacobians, q)[2]
    np.testing.assert_allclose(evaluate(pendulum.applied_force["lower"], q, base, side, f, 0.0), side_jac.T @ f,
                               atol=1e-12)
    np.testing.assert_allclose(evaluate(pendulum.applied_force["lower"], q, base, side, np.zeros(2), 7.0),
                               [7.0, 7.0], atol=1e-12)  # φ_lower = q1 + q2
    np.testing.assert_allclose(evaluate(pendulum.applied_force["upper"], q, base, side, np.zeros(2), 7.0),
                               [7.0, 0.0], atol=1e-12)


def test_free_double_pendulum_conserves_energy(pendulum):
    """No joint moments, fixed base: ½q̇ᵀMq̇ + m·g·z_com stays constant (M, k and g are consistent)."""
    base = np.array([0.0, 0.0])
    total_mass = M1 + M2

    def rhs(t, x):
        q, qd = x[:2], x[2:]
        qdd = np.linalg.solve(evaluate(pendulum.mass_matrix, q),
                              evaluate(pendulum.gravity, q) - evaluate(pendulum.bias, q, qd, np.zeros(2)))
        return np.concatenate([qd, qdd])

    def energy(x):
        q, qd = x[:2], x[2:]
        z_com = evaluate(pendulum.centre_of_mass, q, base)[1]
        return 0.5 * qd @ evaluate(pendulum.mass_matrix, q) @ qd + total_mass * G * z_com

    x0 = np.array([1.2, -0.5, 0.0, 2.0])
    sol = solve_ivp(rhs, (0.0, 2.0), x0, method="DOP853", rtol=1e-11, atol=1e-12, t_eval=np.linspace(0, 2, 9))
    assert np.ptp(sol.y[1]) > 0.5  # the lower link swings
    e = np.array([energy(x) for x in sol.y.T])
    np.testing.assert_allclose(e, e[0], rtol=0, atol=1e-8 * total_mass * G * (L1 + L2))


def test_floating_rigid_body_matches_hand_derivation():
    """One body, q = (x, z, φ), CoM at (a, c) in its frame: r = (x, z) + a·e_along + c·e_across, so
    M = [[m, 0, m·r'_x], [0, m, m·r'_z], [·, ·, I + m(a² + c²)]] with r' = ∂r/∂φ, and k = −m·r''·φ̇² stacked likewise."""
    m, inertia, a, c = 3.0, 0.2, 0.25, -0.08
    body = PlanarChain([Segment("body", m, inertia, 0.5, a, c)], [], base="floating", root="body")
    rng = np.random.default_rng(4)
    for _ in range(20):
        q, qd = rng.normal(0, 1, 3), rng.normal(0, 3, 3)
        phi = q[2]
        dr = a * np.array([np.cos(phi), np.sin(phi)]) + c * np.array([-np.sin(phi), np.cos(phi)])
        ddr = a * np.array([-np.sin(phi), np.cos(phi)]) + c * np.array([-np.cos(phi), -np.sin(phi)])
        expected = np.array([[m, 0, m * dr[0]], [0, m, m * dr[1]],
                             [m * dr[0], m * dr[1], inertia + m * (a * a + c * c)]])
        np.testing.assert_allclose(evaluate(body.mass_matrix, q), expected, atol=1e-12)
        bias = m * ddr * qd[2] ** 2
        np.testing.assert_allclose(evaluate(body.bias, q, qd), [bias[0], bias[1], dr @ bias], atol=1e-12)
        np.testing.assert_allclose(evaluate(body.gravity, q), -m * G * np.array([0, 1, dr[1]]), atol=1e-12)


def _walker():
    """The predict model's layout: hip x, hip z, HAT angle, then thigh (absolute), knee, ankle per leg."""
    segments = [Segment("hat", 50.0, 3.0, 0.8, -0.3, points={"head": (-0.8, 0.0)})]
    joints = []
    for side in ("r", "l"):
        segments += [Segment(f"thigh_{side}", 7.5, 0.12, 0.44, 0.19, points={f"knee_{side}": (0.44, 0.0)}),
                     Segment(f"shank_{side}", 3.2, 0.05, 0.43, 0.19, points={f"ankle_{side}": (0.43, 0.0)}),
                     Segment(f"foot_{side}", 1.0, 0.004, 0.25, 0.04, 0.05,
                             points={f"heel_{side}": (0.06, -0.06), f"mtp_{side}": (0.06, 0.13)})]
        joints += [Joint(f"thigh_{side}", "hat", f"thigh_{side}", at=(0.0, 0.0), absolute=True),
                   Joint(f"knee_{side}", f"thigh_{side}", f"shank_{side}", sign=-1.0),
                   Joint(f"ankle_{side}", f"shank_{side}", f"foot_{side}")]
    return PlanarChain(segments, joints, base="floating", root="hat",
                       base_coordinates=("hip_x", "hip_z", "hat_angle"))


def test_branched_floating_tree():
    """9 coordinates; M symmetric positive definite, its translation block the total mass; a pure
    translation of the base causes no bias forces; the legs hang from the hip whatever the HAT does."""
    walker = _walker()
    assert walker.n == 9 and walker.coordinates[:4] == ("hip_x", "hip_z", "hat_angle", "thigh_r")
    rng = np.random.default_rng(5)
    total = walker.total_mass_kg
    for _ in range(20):
        q, qd = rng.normal(0, 0.8, 9), rng.normal(0, 3, 9)
        mass = evaluate(walker.mass_matrix, q)
        np.testing.assert_allclose(mass, mass.T, atol=1e-13)
        assert np.linalg.eigvalsh(mass).min() > 1e-4
        np.testing.assert_allclose(mass[:2, :2], total * np.eye(2), atol=1e-12)
        translating = np.r_[qd[:2], np.zeros(7)]
        np.testing.assert_allclose(evaluate(walker.bias, q, translating), 0.0, atol=1e-12)
        np.testing.assert_allclose(evaluate(walker.gravity, q)[:2], [0.0, -total * G], atol=1e-10)
        points = dict(zip(walker.point_names, evaluate(walker.points, q)))
        tilted = q.copy()
        tilted[2] += 0.3  # the thighs' angles are absolute: turning the HAT leaves the legs in place
        moved = dict(zip(walker.point_names, evaluate(walker.points, tilted)))
        for name in ("knee_r", "ankle_l", "mtp_r"):
            np.testing.assert_allclose(moved[name], points[name], atol=1e-14)
        assert not np.allclose(moved["head"], points["head"])
    np.testing.assert_allclose(evaluate(walker.points, np.zeros(9))[0], [0.0, 0.8], atol=1e-15)  # head above hip


def test_bad_chains():
    seg = Segment("a", 1.0, 0.1, 1.0, 0.5)
    with pytest.raises(InputError, match="base: got 'flaoting'.*did you mean 'floating'"):
        PlanarChain([seg], [], base="flaoting", root="a")
    with pytest.raises(InputError, match="parent 'b' must come before"):
        PlanarChain([seg, Segment("b", 1.0, 0.1, 1.0, 0.5)], [Joint("qa", "b", "a"), Joint("qb", None, "b")],
                    base="prescribed")
    with pytest.raises(InputError, match="have no joint"):
        PlanarChain([seg, Segment("b", 1.0, 0.1, 1.0, 0.5)], [], base="floating", root="a")
