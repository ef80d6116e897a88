"""Limb model (4.5.1): input table, de Leva parameters, inverse and forward dynamics."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from gaitcli.dynamics.sagittal import SagittalMotion
from gaitcli.errors import InputError
from gaitcli.muscles import LimbModel, LimbParameters, MotionInterpolant
from gaitcli.muscles.evaluation import evaluate

G = 9.81


def _reference_unit(phi):
    """Unit vector of a segment at absolute angle φ from the downward vertical, (x, z)."""
    return ca.vertcat(ca.sin(phi), -ca.cos(phi))


class ReferenceLimbModel:
    """The limb model as written before the planar builder (commit 9e9ac57), kept as the reference;
    the same Functions and signatures as :class:`LimbModel`."""

    def __init__(self, params: LimbParameters):
        self.params = p = params
        sym = ca.SX.sym
        q, qd, qdd, tau = sym("q", 3), sym("qd", 3), sym("qdd", 3), sym("tau", 3)
        hip, hip_acc, grf, cop = sym("hip", 2), sym("hip_acc", 2), sym("grf", 2), sym("cop_x")
        th, sh, ft = q[0], q[0] - q[1], q[0] - q[1] + q[2]
        knee = hip + p.thigh_length_m * _reference_unit(th)
        ankle = knee + p.shank_length_m * _reference_unit(sh)
        foot_fwd = ca.vertcat(ca.cos(ft), ca.sin(ft))
        foot_up = ca.vertcat(-ca.sin(ft), ca.cos(ft))
        coms = [hip + p.thigh_com_m * _reference_unit(th), knee + p.shank_com_m * _reference_unit(sh),
                ankle + p.foot_com_forward_m * foot_fwd - p.foot_com_down_m * foot_up]
        masses = [p.thigh_mass_kg, p.shank_mass_kg, p.foot_mass_kg]
        inertias = [p.thigh_inertia_kgm2, p.shank_inertia_kgm2, p.foot_inertia_kgm2]
        rates = [ca.DM([[1, 0, 0]]), ca.DM([[1, -1, 0]]), ca.DM([[1, -1, 1]])]  # ω_b = c_b·q̇
        gravity = ca.vertcat(0, p.gravity_m_s2)
        mass_matrix = ca.SX.zeros(3, 3)
        tau_id = ca.SX.zeros(3)
        for com, mass, inertia, c in zip(coms, masses, inertias, rates):
            jac = ca.jacobian(com, q)
            acc = jac @ qdd + ca.jacobian(jac @ qd, q) @ qd + hip_acc  # CoM acceleration
            mass_matrix += mass * jac.T @ jac + inertia * c.T @ c
            tau_id += jac.T @ (mass * (acc + gravity)) + c.T * (inertia * (c @ qdd))
        # ground reaction at (cop_x, 0) on the foot: force at the ankle plus its moment
        r = ca.vertcat(cop, 0) - ankle
        q_gr = ca.jacobian(ankle, q).T @ grf + rates[2].T * (r[0] * grf[1] - r[1] * grf[0])
        tau_id -= q_gr
        bias = ca.substitute(tau_id, qdd, ca.SX.zeros(3))
        self.points = ca.Function("points", [q, hip], [knee, ankle], ["q", "hip"], ["knee", "ankle"])
        self.mass_matrix = ca.Function("mass_matrix", [q], [mass_matrix], ["q"], ["M"])
        self.inverse_dynamics = ca.Function(
            "inverse_dynamics", [q, qd, qdd, hip, hip_acc, grf, cop], [tau_id],
            ["q", "qd", "qdd", "hip", "hip_acc", "grf", "cop_x"], ["tau"])
        self.forward_dynamics = ca.Function(
            "forward_dynamics", [q, qd, tau, hip, hip_acc, grf, cop], [ca.solve(mass_matrix, tau - bias)],
            ["q", "qd", "tau", "hip", "hip_acc", "grf", "cop_x"], ["qdd"])


def test_rebuilt_limb_matches_reference(model, limb):
    """The limb built with dynamics/planar.py gives the equations of the hand-written model to 1e-10."""
    ref = ReferenceLimbModel(limb)
    rng = np.random.default_rng(11)
    n = 200
    q, qd, qdd = rng.normal(0, 1.0, (n, 3)), rng.normal(0, 5, (n, 3)), rng.normal(0, 30, (n, 3))
    hip, hip_acc = rng.normal(0, 1.0, (n, 2)), rng.normal(0, 5, (n, 2))
    grf, cop = rng.normal(0, 500, (n, 2)), rng.normal(0, 0.5, (n, 1))
    cases = {"points": (q, hip), "mass_matrix": (q,),
             "inverse_dynamics": (q, qd, qdd, hip, hip_acc, grf, cop),
             "forward_dynamics": (q, qd, qdd * 10, hip, hip_acc, grf, cop)}
    for name, args in cases.items():
        rebuilt, reference = getattr(model, name), getattr(ref, name)
        assert (rebuilt.name_in(), rebuilt.name_out()) == (reference.name_in(), reference.name_out())
        new, old = evaluate(rebuilt, *args), evaluate(reference, *args)
        for a, b in zip(new if isinstance(new, tuple) else (new,), old if isinstance(old, tuple) else (old,)):
            np.testing.assert_allclose(a, b, rtol=1e-10, atol=1e-10, err_msg=name)
    # the muscle and joint models take the joint angles; with the trunk upright hip flexion = thigh angle
    np.testing.assert_array_equal(model.evaluate("joint_angles", q), q)


@pytest.fixture(scope="module")
def limb():
    return LimbParameters.from_anthropometry(73.0, 1.792, "male")


@pytest.fixture(scope="module")
def model(limb):
    return LimbModel(limb)


def test_de_leva_parameters(limb):
    """Diss. Table A.5, subject 1 (73.0 kg, 1.792 m): masses 10.34 / 3.16 / 1.00 kg (docs/model_constants.md §1)."""
    assert limb.thigh_mass_kg == pytest.approx(10.34, abs=0.01)
    assert limb.shank_mass_kg == pytest.approx(3.16, abs=0.01)
    assert limb.foot_mass_kg == pytest.approx(1.00, abs=0.01)
    assert limb.foot_inertia_kgm2 == pytest.approx(0.0047, abs=0.0001)  # r_sag as in Table A.5
    measured = LimbParameters.from_anthropometry(73.0, 1.792, "male", thigh_length_m=0.475, shank_length_m=0.429)
    assert measured.thigh_com_m == pytest.approx(0.4095 * 0.475)
    assert measured.shank_com_m == pytest.approx(0.4395 * 0.429)
    assert measured.thigh_inertia_kgm2 == pytest.approx(10.3375 * (0.329 * 0.475) ** 2, rel=1e-3)
    female = LimbParameters.from_anthropometry(61.9, 1.735, "female")
    assert female.thigh_length_m == pytest.approx(0.3685)
    with pytest.raises(InputError, match="sex"):
        LimbParameters.from_anthropometry(70, 1.7, "x")


def test_de_leva_parameters_unchanged_by_the_shared_table():
    """from_anthropometry reads kinematics.anthropometry.DE_LEVA; the numbers are those of the limb's own
    former copy of the table (recorded at commit 9e9ac57), male 73.0 kg / 1.792 m and female 61.9 kg / 1.735 m."""
    former = {
        ("male", 73.0, 1.792): dict(
            thigh_length_m=0.4345677197013211, shank_length_m=0.4531979322228605, foot_length_m=0.2656606547960942,
            thigh_mass_kg=10.3368, shank_mass_kg=3.1609, foot_mass_kg=1.0001, thigh_com_m=0.177955481217691,
            shank_com_m=0.19918049121194717, foot_com_forward_m=0.05755584575914226, foot_com_down_m=0.043,
            thigh_inertia_kgm2=0.21129675905263215, shank_inertia_kgm2=0.03928771855799649,
            foot_inertia_kgm2=0.00466191285970484),
        ("female", 61.9, 1.735): dict(
            thigh_length_m=0.3685, shank_length_m=0.4386, foot_length_m=0.2283, thigh_mass_kg=9.14882,
            shank_mass_kg=2.97739, foot_mass_kg=0.79851, thigh_com_m=0.1331022, shank_com_m=0.19087872,
            foot_com_forward_m=0.03380628666666666, foot_com_down_m=0.041632254464285715,
            thigh_inertia_kgm2=0.1646049286200519, shank_inertia_kgm2=0.039617263775893155,
            foot_inertia_kgm2=0.003720784856578533),
    }
    for (sex, mass, stature), values in former.items():
        params = LimbParameters.from_anthropometry(mass, stature, sex)
        for name, value in values.items():
            assert getattr(params, name) == pytest.approx(value, rel=1e-14), (sex, name)


def test_static_leg_hanging_vertical(model, limb):
    """q = 0, at rest, no ground reaction: each joint holds the weight moment of the foot CoM offset.

    The foot's weight, ahead of the joints, pulls the hip into extension, the knee into flexion
    and the ankle into plantarflexion, so the moments are hip flexion, knee extension, dorsiflexion.
    """
    tau = model.evaluate("inverse_dynamics", np.zeros(3), np.zeros(3), np.zeros(3), np.array([0, 0.9]),
                         np.zeros(2), np.zeros(2), np.zeros(1))
    expected = limb.foot_mass_kg * G * limb.foot_com_forward_m  # gravity on the foot pulls it into extension
    np.testing.assert_allclose(tau, [expected, -expected, expected], atol=1e-12)


def test_static_stance_ankle_moment(model, limb):
    """Leg vertical, body weight at the COP 0.1 m ahead of the ankle: plantarflexor moment (−)."""
    hip = np.array([0.0, 0.9])
    fz = 700.0
    knee, ankle = model.evaluate("points", np.zeros(3), hip)
    tau = model.evaluate("inverse_dynamics", np.zeros(3), np.zeros(3), np.zeros(3), hip, np.zeros(2),
                         np.array([0.0, fz]), np.array([ankle[0] + 0.1]))
    weight = limb.foot_mass_kg * G * limb.foot_com_forward_m
    np.testing.assert_allclose(tau[2], weight - 0.1 * fz, atol=1e-9)
    np.testing.assert_allclose(tau[1], -weight + 0.1 * fz, atol=1e-9)  # GRF 0.1 m ahead of the knee: flexor
    # a horizontal force at the floor acts with the lever arm of the ankle height
    tau_x = model.evaluate("inverse_dynamics", np.zeros(3), np.zeros(3), np.zeros(3), hip, np.zeros(2),
                           np.array([100.0, 0.0]), np.array([ankle[0]]))
    np.testing.assert_allclose(tau_x[2] - weight, -100.0 * ankle[1], atol=1e-9)  # tips the foot up: PF moment


def test_hip_acceleration_equals_gravity(model):
    """An upward hip acceleration A acts like gravity g + A (prescribed hip, 4.5.1)."""
    rng = np.random.default_rng(5)
    q, qd = rng.normal(0, 0.4, 3), rng.normal(0, 2, 3)
    hip = np.array([0.3, 0.9])
    a = 4.0
    with_acc = model.evaluate("inverse_dynamics", q, qd, np.zeros(3), hip, np.array([0, a]), np.zeros(2),
                              np.zeros(1))
    quasi = model.evaluate("inverse_dynamics", q, np.zeros(3), np.zeros(3), hip, np.zeros(2), np.zeros(2),
                           np.zeros(1))
    moving = model.evaluate("inverse_dynamics", q, qd, np.zeros(3), hip, np.zeros(2), np.zeros(2), np.zeros(1))
    np.testing.assert_allclose(with_acc - moving, quasi * a / G, rtol=1e-10, atol=1e-12)


def test_forward_inverse_consistency(model):
    rng = np.random.default_rng(6)
    q, qd, qdd = rng.normal(0, 0.5, (10, 3)), rng.normal(0, 2, (10, 3)), rng.normal(0, 10, (10, 3))
    hip, hip_acc = rng.normal(0, 0.5, (10, 2)), rng.normal(0, 3, (10, 2))
    grf, cop = rng.normal(0, 300, (10, 2)), rng.normal(0, 0.3, (10, 1))
    tau = model.evaluate("inverse_dynamics", q, qd, qdd, hip, hip_acc, grf, cop)
    np.testing.assert_allclose(model.evaluate("forward_dynamics", q, qd, tau, hip, hip_acc, grf, cop), qdd,
                               rtol=1e-9, atol=1e-9)


def test_energy_conserved_in_free_swing(model, limb):
    """Fixed hip, no moments: kinetic + potential energy stays constant (an independent check of M and k)."""
    hip = np.array([0.0, 1.0])

    def energy(x):
        q, qd = x[:3], x[3:]
        mass = model.evaluate("mass_matrix", q)
        th, sh, ft = q[0], q[0] - q[1], q[0] - q[1] + q[2]
        knee_z = hip[1] - limb.thigh_length_m * np.cos(th)
        ankle_z = knee_z - limb.shank_length_m * np.cos(sh)
        z = [hip[1] - limb.thigh_com_m * np.cos(th), knee_z - limb.shank_com_m * np.cos(sh),
             ankle_z + limb.foot_com_forward_m * np.sin(ft) - limb.foot_com_down_m * np.cos(ft)]
        pot = G * (limb.thigh_mass_kg * z[0] + limb.shank_mass_kg * z[1] + limb.foot_mass_kg * z[2])
        return 0.5 * qd @ mass @ qd + pot

    def rhs(t, x):
        qdd = model.evaluate("forward_dynamics", x[:3], x[3:], np.zeros(3), hip, np.zeros(2), np.zeros(2),
                             np.zeros(1))
        return np.concatenate([x[3:], qdd])

    x0 = np.array([0.6, 0.9, -0.2, 0.0, 0.0, 0.0])
    sol = solve_ivp(rhs, (0, 1.0), x0, rtol=1e-10, atol=1e-12, t_eval=[0.0, 0.5, 1.0])
    e = [energy(x) for x in sol.y.T]
    assert np.ptp(sol.y[0]) > 0.1  # it does swing
    np.testing.assert_allclose(e, e[0], rtol=1e-7)


# ---------------------------------------------------------------------------------- input table
def test_from_table_units_and_events(gait_table):
    table, events = gait_table
    motion = SagittalMotion.from_table(table, "r", path="sagittal.csv", **events)
    np.testing.assert_allclose(np.rad2deg(motion.knee_flexion_rad), table["knee_flexion_r_deg"])
    assert motion.heel_strike_s == (0.0, 1.1)
    assert motion.side == "r"


def test_from_table_missing_column(gait_table):
    table = dict(gait_table[0])
    del table["grf_z_r_N"]
    with pytest.raises(InputError, match="grf_z_r_N: missing column"):
        SagittalMotion.from_table(table, "r", path="sagittal.csv")


def test_from_table_bad_time(gait_table):
    table = dict(gait_table[0])
    table["time_s"] = table["time_s"][::-1].copy()
    with pytest.raises(InputError, match="time_s"):
        SagittalMotion.from_table(table, "r", path="sagittal.csv")


def test_nan_in_analysed_interval(gait_table):
    table, events = gait_table
    table = {k: np.array(v, dtype=float) for k, v in table.items()}
    t = table["time_s"]
    table["knee_flexion_r_deg"][(t > 0.40) & (t < 0.45)] = np.nan
    motion = SagittalMotion.from_table(table, "r", path="trial/sagittal.csv", **events)
    with pytest.raises(InputError) as err:
        MotionInterpolant(motion, 0.0, 1.1)
    msg = str(err.value)
    assert msg.startswith("trial/sagittal.csv: knee_flexion_r_deg: NaN in frames 71–74")
    assert "0.410–0.440 s" in msg
    MotionInterpolant(motion, 0.5, 1.0)  # NaN outside the interval is fine


def test_nan_cop_allowed_only_without_load(gait_table):
    table, events = gait_table
    table = {k: np.array(v, dtype=float) for k, v in table.items()}
    motion = SagittalMotion.from_table(table, "r", **events)
    MotionInterpolant(motion, 0.0, 1.1)  # swing COP is NaN in the fixture
    t = table["time_s"]
    table["cop_x_r_m"][(t > 0.2) & (t < 0.23)] = np.nan
    with pytest.raises(InputError, match="cop_x_r_m"):
        MotionInterpolant(SagittalMotion.from_table(table, "r", **events), 0.0, 1.1)


def test_interpolant_derivatives(gait):
    motion, _ = gait
    interp = MotionInterpolant(motion, 0.0, 1.1)
    t = np.linspace(0.1, 1.0, 7)
    s = interp(t)
    h = 1e-5
    np.testing.assert_allclose(s.qd, (interp(t + h).q - interp(t - h).q) / (2 * h), atol=1e-5)
    np.testing.assert_allclose(s.hip_vel[:, 0], 1.25 + 0.01 * 4 * np.pi / 1.1 * np.cos(4 * np.pi * (t / 1.1 - 0.3)),
                               atol=2e-3)


def test_from_table_dataframe_left_side(gait_table):
    pd = pytest.importorskip("pandas")
    table, events = gait_table
    frame = pd.DataFrame({k.replace("_r_", "_l_"): v for k, v in table.items()})
    motion = SagittalMotion.from_table(frame, "l", **events)
    assert motion.side == "l"
    np.testing.assert_allclose(motion.hip_x_m, table["hip_x_r_m"])
    with pytest.raises(InputError, match="hip_x_r_m"):
        SagittalMotion.from_table(frame, "r")
