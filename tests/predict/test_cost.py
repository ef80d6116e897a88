"""Inversion and cost of a predicted gait (gaitcli/predict/cost.py): known answers (Jdev 0 at the mean and
n_d·T one SD away, Et of constant activation the maintenance heat), the inversion's consistency with activation
dynamics (2.17), and numpy = CasADi."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from gaitcli.errors import InputError
from gaitcli.muscles.hill import MuscleModel
from gaitcli.predict.cost import (
    check_weights,
    cost_of_transport,
    deviation,
    invert_muscles,
    objective,
    trapezoid_periodic,
)
from gaitcli.predict.grid import control_grid, cycle_period, instant_times

DURATIONS = np.array([0.05, 0.09, 0.28, 0.16, 0.05, 0.09, 0.28, 0.16])  # s, phases 1–8 (a 1.16 s cycle)


@pytest.fixture(scope="module")
def grid_times():
    grid = control_grid()
    return instant_times(grid, DURATIONS), cycle_period(DURATIONS)


@pytest.fixture(scope="module")
def muscle() -> MuscleModel:
    return MuscleModel()


def test_jdev_is_zero_on_the_reference_and_n_d_times_t_one_sd_away(grid_times):
    t, T = grid_times
    rng = np.random.default_rng(0)
    mean = rng.normal(size=(t.size, 10))
    sd = rng.uniform(0.5, 2.0, size=(t.size, 10))
    assert deviation(mean, mean, sd, t, T) == 0.0
    assert deviation(mean + sd, mean, sd, t, T) == pytest.approx(10 * T, rel=1e-12)  # n_d · T


def test_trapezoid_integrates_a_periodic_linear_piece_exactly(grid_times):
    # a periodic triangle wave with its corners on instants: the trapezoid rule is exact
    t, T = grid_times
    values = np.interp(t, [0.0, T / 2, T], [0.0, 1.0, 0.0])
    assert trapezoid_periodic(values, t, T) == pytest.approx(T / 2, rel=1e-12)


def test_et_of_isometric_constant_activation_is_the_maintenance_heat(muscle, grid_times):
    # constant force and muscle length: v_se = v_ce = 0, ȧ = 0 so u = a; the metabolic rate is the maintenance
    # heat of A.15 alone, by hand: m·S·h_AM·a^0.6, h_AM = 1.28·FT + 25 W/kg (A.18), with l_ce ≤ l_opt
    t, T = grid_times
    p = muscle.params
    m = muscle.m
    a_target = 0.3
    # a length where every fibre is at 0.95 l_opt under the force that activation gives there (fixed point)
    l_ce = 0.95 * np.asarray(p.optimal_fibre_length_m)
    f_iso = np.asarray(muscle.evaluate("force_length", l_ce[None, :])).ravel()
    force = a_target * np.asarray(p.max_isometric_force_N) * f_iso * np.cos(p.pennation_rad)
    l_se = np.asarray(muscle.evaluate("tendon_length", force[None, :])).ravel()
    l_m = l_se + l_ce * np.cos(p.pennation_rad)
    n = t.size
    state = invert_muscles(muscle, np.tile(force, (n, 1)), np.tile(l_m, (n, 1)), np.zeros((n, m)), t, T)
    np.testing.assert_allclose(state["a"], a_target, rtol=1e-9)
    np.testing.assert_allclose(state["u"], a_target, rtol=1e-9)
    rate = muscle.evaluate("metabolic_rate", state["u"], state["a"], state["l_ce"], state["v_ce"], state["f_ce"])
    maintenance = (np.asarray(p.muscle_mass_kg) * p.heat_scale * (1.28 * np.asarray(p.fast_twitch_pct) + 25.0)
                   * a_target ** 0.6)
    stride = 1.3
    assert cost_of_transport(rate, t, T, stride) == pytest.approx(maintenance.sum() * T / stride, rel=1e-9)


def test_inversion_satisfies_activation_dynamics(muscle, grid_times):
    # smooth periodic forces: the excitations found make (2.17) give back the differenced activation rate
    t, T = grid_times
    p = muscle.params
    phase = 2 * np.pi * t[:, None] / T
    force = np.asarray(p.max_isometric_force_N) * (0.25 + 0.15 * np.sin(phase + np.arange(muscle.m)))
    l_opt = np.asarray(p.optimal_fibre_length_m)
    l_slack = np.asarray(p.tendon_slack_length_m)
    l_m = l_slack + l_opt * (1.0 + 0.05 * np.cos(phase))
    v_m = -l_opt * 0.05 * np.sin(phase) * 2 * np.pi / T
    state = invert_muscles(muscle, force, l_m, v_m, t, T)
    adot = muscle.evaluate("activation_rate", state["u"], state["a"])
    np.testing.assert_allclose(adot, state["adot"], rtol=1e-9, atol=1e-9)
    assert np.all(np.isfinite(state["u"]))


def test_casadi_evaluation_equals_numpy(muscle, grid_times):
    t, T = grid_times
    rng = np.random.default_rng(1)
    p = muscle.params
    force = np.asarray(p.max_isometric_force_N) * rng.uniform(0.1, 0.4, size=(t.size, muscle.m))
    l_m = np.asarray(p.tendon_slack_length_m) + np.asarray(p.optimal_fibre_length_m) * rng.uniform(0.9, 1.1,
                                                                                                  (t.size, muscle.m))
    v_m = rng.normal(scale=0.05, size=(t.size, muscle.m))
    numeric = invert_muscles(muscle, force, l_m, v_m, t, T)
    symbols = ca.MX.sym("F", *force.shape)
    durations = ca.MX.sym("T_ph", 8)
    grid = control_grid()
    symbolic = invert_muscles(muscle, symbols, ca.DM(l_m), ca.DM(v_m), instant_times(grid, durations),
                              cycle_period(durations))
    f = ca.Function("f", [symbols, durations], [symbolic["u"], symbolic["a"]])
    u, a = f(force, DURATIONS)
    np.testing.assert_allclose(np.array(u), numeric["u"], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(np.array(a), numeric["a"], rtol=1e-9, atol=1e-12)


def test_objective_and_its_weights():
    assert objective(350.0, 12.0) == pytest.approx(4 / 3 * 3.5 + 2 / 3 * 12.0)
    assert check_weights((1, 1)) == (1.0, 1.0)
    # fractions are exact: "4/3,2/3" is DEFAULT_WEIGHTS to the bit (the decimals 0.6666666666666667 are not)
    assert check_weights(("4/3", "2/3")) == (4 / 3, 2 / 3) and check_weights((" 1.5", "0.5 ")) == (1.5, 0.5)
    assert check_weights(("4/3", "0.6666666666666667"))[1] != 2 / 3
    for bad in ((1, 2), (2.5, -0.5), ("a", 1), (1,), ("1/0", "2"), ("nan", "2")):
        with pytest.raises(InputError, match="--weights"):
            check_weights(bad)
