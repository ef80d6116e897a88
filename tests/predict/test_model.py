"""The 7-body planar walking model (gaitcli/predict/model.py): parameters, signs, and equations checked
against quantities computed independently from its point positions."""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.predict.model import COORDINATES, WalkerParameters, WalkingModel

G = 9.81
RNG = np.random.default_rng(7)


@pytest.fixture(scope="module")
def model() -> WalkingModel:
    return WalkingModel()


def random_state(rng=RNG):
    y = np.concatenate([[0.3, 0.95], rng.uniform(-0.6, 0.6, 7)])
    return y, rng.normal(size=9)


def test_subject_1_parameters_are_the_dissertations():
    # Tables A.4–A.5: thigh 10.34 kg, CoM 0.195 m; shank 3.16 kg, CoM 0.188 m; foot 1.00 kg;
    # the 2-D HAT is the rest, 44.0 kg
    p = WalkerParameters.subject_1()
    assert p.limb.thigh_mass_kg == pytest.approx(10.34, abs=0.005)
    assert p.limb.thigh_com_m == pytest.approx(0.195, abs=0.001)
    assert p.limb.shank_mass_kg == pytest.approx(3.16, abs=0.005)
    assert p.limb.shank_com_m == pytest.approx(0.188, abs=0.001)
    assert p.limb.foot_mass_kg == pytest.approx(1.00, abs=0.005)
    assert p.hat_mass_kg == pytest.approx(44.0, abs=0.01)
    assert WalkingModel(p).total_mass_kg == pytest.approx(73.0, abs=1e-12)
    assert 0.25 < p.hat_com_above_hip_m < 0.45 and p.hat_inertia_kgm2 > 1.0  # trunk-sized, not a point


def test_upright_posture_geometry(model):
    # y = 0 with the hip at height h: everything below the hip on one vertical, feet flat, A and B on one level
    p = model.params
    h = 1.0
    y = np.zeros(9)
    y[1] = h
    sole = h - p.limb.thigh_length_m - p.limb.shank_length_m - p.contact_below_ankle_m
    for s in ("r", "l"):
        np.testing.assert_allclose(model.point(f"knee_{s}", y), [0.0, h - p.limb.thigh_length_m], atol=1e-12)
        np.testing.assert_allclose(model.point(f"heel_{s}", y), [-p.heel_behind_ankle_m, sole], atol=1e-12)
        np.testing.assert_allclose(model.point(f"mtp_{s}", y), [p.mtp_ahead_of_ankle_m, sole], atol=1e-12)
    np.testing.assert_allclose(model.point("hat_com", y), [0.0, h + p.hat_com_above_hip_m], atol=1e-12)


@pytest.mark.parametrize("index,point,moves", [
    (2, "hat_com", "forward"),  # y3 > 0: the HAT leans forward (clockwise seen from the right)
    (3, "knee_r", "back"),      # y4 > 0: thigh extension puts the knee behind the hip
    (6, "knee_l", "back"),
    (4, "ankle_r", "back"),     # y5 > 0: knee flexion swings the ankle back
    (5, "mtp_r", "down"),       # y6 > 0: plantarflexion lowers the toes
    (8, "mtp_l", "down"),
])
def test_the_dissertations_signs_clockwise_positive(model, index, point, moves):
    y = np.zeros(9)
    y[1] = 1.0
    before = model.point(point, y)
    y[index] = 0.2
    after = model.point(point, y)
    change = {"forward": after[0] - before[0], "back": before[0] - after[0], "down": before[1] - after[1]}[moves]
    assert change > 0.01


def test_mass_matrix_is_symmetric_positive_definite_and_gives_the_linear_momentum(model):
    # the rows of M ẏ for the free translation (x, z) are the body's linear momentum m·v_CoM, with v_CoM
    # taken by central differences of the model's own centre of mass
    y, yd = random_state()
    M = np.array(model.mass_matrix(y))
    np.testing.assert_allclose(M, M.T, atol=1e-12)
    assert np.linalg.eigvalsh(M).min() > 0
    h = 1e-6
    com_rate = (np.array(model.centre_of_mass(y + h * yd)).ravel()
                - np.array(model.centre_of_mass(y - h * yd)).ravel()) / (2 * h)
    np.testing.assert_allclose((M @ yd)[:2], model.total_mass_kg * com_rate, rtol=1e-6, atol=1e-6)


def test_gravity_is_minus_the_gradient_of_the_potential_energy(model):
    y, _ = random_state()
    g = np.array(model.gravity(y)).ravel()
    h = 1e-6
    potential = lambda yy: model.total_mass_kg * G * float(np.array(model.centre_of_mass(yy)).ravel()[1])  # noqa: E731
    gradient = np.array([(potential(y + h * e) - potential(y - h * e)) / (2 * h) for e in np.eye(9)])
    np.testing.assert_allclose(g, -gradient, rtol=1e-6, atol=1e-6)


def test_point_jacobians_are_the_derivatives_of_the_points(model):
    y, _ = random_state()
    h = 1e-6
    jacobians = model.point_jacobians(y)
    for name, J in zip(model.point_names, jacobians):
        fd = np.column_stack([(model.point(name, y + h * e) - model.point(name, y - h * e)) / (2 * h)
                              for e in np.eye(9)])
        np.testing.assert_allclose(np.array(J), fd, atol=1e-7, err_msg=name)


def test_energy_is_conserved_in_free_flight(model):
    # no joint moments, no contact: M ÿ + k = g; kinetic + potential energy constant (RK4, 0.2 s)
    def rates(state):
        y, yd = state[:9], state[9:]
        ydd = np.linalg.solve(np.array(model.mass_matrix(y)),
                              np.array(model.gravity(y)).ravel() - np.array(model.bias(y, yd)).ravel())
        return np.concatenate([yd, ydd])

    def energy(state):
        y, yd = state[:9], state[9:]
        return (0.5 * yd @ np.array(model.mass_matrix(y)) @ yd
                + model.total_mass_kg * G * float(np.array(model.centre_of_mass(y)).ravel()[1]))

    y, yd = random_state(np.random.default_rng(3))
    state = np.concatenate([y, 0.5 * yd])
    e0, dt = energy(state), 1e-3
    for _ in range(200):
        k1 = rates(state)
        k2 = rates(state + dt / 2 * k1)
        k3 = rates(state + dt / 2 * k2)
        k4 = rates(state + dt * k3)
        state = state + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    assert abs(energy(state) - e0) < 1e-6 * max(1.0, abs(e0))


def test_clinical_angles_follow_the_geometry(model):
    # hip flexion: the angle from the HAT's downward axis to the thigh, measured on the points; knee flexion
    # and ankle dorsiflexion likewise; the conversion in kinematics/conventions must agree
    from gaitcli.kinematics.conventions import walker_to_clinical

    y = np.array([0.0, 1.0, 0.15, -0.4, 0.7, -0.2, 0.3, 0.1, 0.25])

    def angle(u, v):  # counter-clockwise angle from u to v in the x–z plane, seen from the right
        return np.arctan2(u[0] * v[1] - u[1] * v[0], u @ v)

    hip, hat = model.point("hip", y), model.point("hat_com", y)
    got = walker_to_clinical(y)[0]
    for k, s in enumerate(("r", "l")):
        knee, ankle = model.point(f"knee_{s}", y), model.point(f"ankle_{s}", y)
        heel, mtp = model.point(f"heel_{s}", y), model.point(f"mtp_{s}", y)
        hip_flexion = angle(hip - hat, knee - hip)  # forward swing of the thigh from the trunk line: ccw
        knee_flexion = -angle(knee - hip, ankle - knee)
        dorsiflexion = angle(ankle - knee, mtp - heel) - np.pi / 2  # foot ⟂ shank at neutral
        np.testing.assert_allclose(got[3 * k:3 * k + 3], np.degrees([hip_flexion, knee_flexion, dorsiflexion]),
                                   atol=1e-9)
    assert got[0] > 0 and got[1] > 0 and got[2] > 0  # flexed hip and knee, dorsiflexed right ankle


def test_coordinates_are_named_in_order():
    assert COORDINATES == ("hip_x", "hip_z", "hat_angle", "thigh_r", "knee_r", "ankle_r", "thigh_l", "knee_l",
                           "ankle_l")


def test_added_foot_mass_at_the_foot_centre_of_mass():
    # 5.3.2's +2 kg per foot, at the foot's CoM (docs/prediction.md, "Added foot mass"): mass, CoM and inertia by hand
    p = WalkerParameters.subject_1()
    heavy = p.with_foot_mass(2.0)
    assert heavy.limb.foot_mass_kg == pytest.approx(p.limb.foot_mass_kg + 2.0)
    assert heavy.body_mass_kg == pytest.approx(p.body_mass_kg + 4.0)
    assert heavy.hat_mass_kg == p.hat_mass_kg
    assert (heavy.limb.foot_com_forward_m, heavy.limb.foot_com_down_m) == (p.limb.foot_com_forward_m,
                                                                         p.limb.foot_com_down_m)
    assert heavy.limb.foot_inertia_kgm2 == p.limb.foot_inertia_kgm2
    assert WalkingModel(heavy).total_mass_kg == pytest.approx(WalkingModel(p).total_mass_kg + 4.0)
    assert p.with_foot_mass(0.0) is p


def test_added_foot_mass_as_a_band_combines_by_parallel_axes():
    # a 1.719 kg band (Table A.2: I_Y = 0.0043 kg·m²) 0.1 m ahead of and 0.02 m below the ankle
    p = WalkerParameters.subject_1()
    m0, m = p.limb.foot_mass_kg, 1.719
    c0 = np.array([p.limb.foot_com_forward_m, p.limb.foot_com_down_m])
    band = np.array([0.1, 0.02])
    banded = p.with_foot_mass(m, (0.1, 0.02)).limb
    com = np.array([banded.foot_com_forward_m, banded.foot_com_down_m])
    np.testing.assert_allclose(com, (m0 * c0 + m * band) / (m0 + m), atol=1e-12)
    # about the new CoM: the two bodies' own inertias plus m·d² each
    d0, d1 = np.linalg.norm(c0 - com), np.linalg.norm(band - com)
    expected = p.limb.foot_inertia_kgm2 + m0 * d0 ** 2 + 0.0043 + m * d1 ** 2
    assert banded.foot_inertia_kgm2 == pytest.approx(expected, rel=1e-12)
    # the model's whole-body centre of mass in the upright posture moves by 2·m·(band − foot CoM)/M_total
    y = np.array([0.0, 1.0, 0, 0, 0, 0, 0, 0, 0])
    light, heavy = WalkingModel(p), WalkingModel(p.with_foot_mass(m, (0.1, 0.02)))
    moment_light = np.array(light.centre_of_mass(y)).ravel() * light.total_mass_kg
    moment_heavy = np.array(heavy.centre_of_mass(y)).ravel() * heavy.total_mass_kg
    ankle_z = y[1] - p.limb.thigh_length_m - p.limb.shank_length_m
    band_world = np.array([0.1, ankle_z - 0.02])
    np.testing.assert_allclose(moment_heavy - moment_light, 2 * m * band_world, atol=1e-9)
