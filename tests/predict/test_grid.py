"""Control points uniform within each phase (5.2.5) and the unequal-step derivative (5.2.6)."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from gaitcli.core.numerics import finite_difference_matrix
from gaitcli.errors import InputError
from gaitcli.predict import grid, splines

DURATIONS = np.array([0.05, 0.11, 0.36, 0.06, 0.05, 0.11, 0.36, 0.06])  # s, a typical cycle (T = 1.16 s)


def test_default_grid_counts_points_and_instants():
    g = grid.control_grid()
    assert g.counts == (9, 10, 21, 20, 9, 10, 21, 20)
    assert (g.points, g.instants) == (120, 112)
    assert np.array_equal(np.bincount(g.phase), g.counts)
    assert sorted(set(g.instant)) == list(range(112))


def test_points_are_uniform_within_each_phase_and_transitions_appear_twice():
    g = grid.control_grid()
    t = grid.point_times(g, DURATIONS)
    ends = np.concatenate([[0], np.cumsum(DURATIONS)])
    for ph, n in enumerate(g.counts):
        np.testing.assert_allclose(t[g.phase == ph], np.linspace(ends[ph], ends[ph + 1], n), atol=1e-15)
    last = np.cumsum(g.counts) - 1  # the end point of each phase …
    np.testing.assert_allclose(t[last[:-1]], t[last[:-1] + 1])  # … is the next phase's start point,
    assert np.array_equal(g.instant[last[:-1]], g.instant[last[:-1] + 1])  # the same instant
    assert t[-1] == pytest.approx(DURATIONS.sum()) and g.instant[-1] == 0  # t = T is instant 0 of the next cycle
    instants = grid.instant_times(g, DURATIONS)
    assert len(instants) == 112 and instants[0] == 0 and np.all(np.diff(instants) > 0)
    assert instants[-1] < DURATIONS.sum() == pytest.approx(grid.cycle_period(DURATIONS))


@pytest.mark.parametrize("counts, problem", [((5, 10, 21, 4), "expected 8"), ((5, 10, 21, 1, 5, 10, 21, 4), "≥ 2")])
def test_bad_counts_are_one_line_errors(counts, problem):
    with pytest.raises(InputError, match=problem) as info:
        grid.control_grid(counts)
    assert str(info.value).startswith("control_points: got ")


def test_unequal_step_derivative_is_exact_on_quadratics():
    rng = np.random.default_rng(1)
    for _ in range(5):
        t0, h1, h2 = rng.uniform(-1, 1), rng.uniform(0.001, 0.3), rng.uniform(0.001, 0.3)
        times = np.array([t0 - h1, t0, t0 + h2])
        c = rng.normal(size=3)
        x = c[0] + c[1] * times + c[2] * times ** 2
        a, b, w = (weights[1] for weights in grid.unequal_step_weights(times, period=10.0))  # middle point: no wrap
        assert a * x[0] + b * x[1] + w * x[2] == pytest.approx(c[1] + 2 * c[2] * t0, rel=1e-9, abs=1e-9)


def test_equal_steps_give_the_central_difference():
    n, period = 24, 1.2
    times = np.arange(n) * period / n
    x = np.random.default_rng(2).normal(size=(n, 3))
    expected = finite_difference_matrix(n, period / n, "periodic") @ x
    np.testing.assert_allclose(grid.periodic_derivative(x, times, period), expected, rtol=1e-12)


def test_an_infinite_value_leaves_the_rates_away_from_it_untouched_and_warns_of_nothing(recwarn):
    """Two infs side by side (activations no muscle state allows) on unequal steps: the rates there and beside
    them are not finite (inf − inf at the pair: NaN), every other instant's is the finite series' own."""
    n, period = 12, 1.2
    times = np.arange(n) * period / (n + 1)
    times[6:] += 0.5 * period / (n + 1)  # the step after instant 5 the longer: a < 0 < b there
    finite = np.sin(2 * np.pi * times / period)
    x = finite.copy()
    x[4:6] = np.inf
    xdot = grid.periodic_derivative(x, times, period)
    assert not np.isfinite(xdot[3:7]).any() and np.isnan(xdot[5])
    others = np.setdiff1d(np.arange(n), [3, 4, 5, 6])
    np.testing.assert_allclose(xdot[others], grid.periodic_derivative(finite, times, period)[others], rtol=1e-12)
    assert not [w for w in recwarn if issubclass(w.category, RuntimeWarning)]


def test_periodic_wrap_does_not_depend_on_where_the_cycle_starts():
    g = grid.control_grid()
    period = DURATIONS.sum()
    t = grid.instant_times(g, DURATIONS)
    x = np.sin(2 * np.pi * t / period) + 0.3 * np.cos(6 * np.pi * t / period)
    xdot = grid.periodic_derivative(x, t, period)
    shift = 17  # start the cycle at instant 17 instead
    rotated = grid.periodic_derivative(np.roll(x, -shift), np.concatenate([t[shift:], t[:shift] + period]), period)
    np.testing.assert_allclose(rotated, np.roll(xdot, -shift), rtol=1e-12, atol=1e-12)
    # and it is a derivative: second order on the 112 instants of a 1.16 s cycle
    exact = 2 * np.pi / period * (np.cos(2 * np.pi * t / period) - 0.9 * np.sin(6 * np.pi * t / period))
    assert np.max(np.abs(xdot - exact)) < 0.02 * np.max(np.abs(exact))


def test_casadi_times_and_derivatives_equal_numpy():
    g = grid.control_grid()
    durations = ca.SX.sym("T_ph", 8)
    x = ca.SX.sym("x", 112, 2)
    values = np.random.default_rng(3).normal(size=(112, 2))
    xdot = grid.periodic_derivative(x, grid.instant_times(g, durations), grid.cycle_period(durations))
    f = ca.Function("f", [durations, x], [grid.point_times(g, durations), xdot])
    times, derivative = f(DURATIONS, values)
    np.testing.assert_allclose(times.full().ravel(), grid.point_times(g, DURATIONS), atol=1e-15)
    t = grid.instant_times(g, DURATIONS)
    np.testing.assert_allclose(derivative.full(), grid.periodic_derivative(values, t, DURATIONS.sum()), rtol=1e-12,
                               atol=1e-9)  # values up to ~1e3 (1/h with h ≈ 6 ms)


def test_spline_at_symbolic_control_points_and_its_jacobian():
    """A design vector (nodal values, T_ph) through the control-point times into the spline and ÿ, vs. differences."""
    g = grid.control_grid()
    spline = splines.quartic(18)
    y, durations = ca.SX.sym("y", 17), ca.SX.sym("T_ph", 8)
    period = grid.cycle_period(durations)
    outputs = [splines.evaluate(spline, y, period, grid.point_times(g, durations), r) for r in (0, 1, 2)]
    chi = ca.vertcat(y, durations)
    f = ca.Function("f", [chi], [ca.vertcat(*outputs), ca.jacobian(ca.vertcat(*outputs), chi)])

    def numeric(c):
        t = grid.point_times(g, c[17:])
        return np.concatenate([splines.evaluate(spline, c[:17], c[17:].sum(), t, r) for r in (0, 1, 2)])

    # stretch phase 3 so that its middle point lies 1e-8 s before node k: the differences cross the node
    j = np.flatnonzero((g.phase == 2) & (g.position == 0.5))[0]
    t, period = grid.point_times(g, DURATIONS)[j], DURATIONS.sum()
    k = round(17 * t / period)
    stretch = (k * period / 17 - t - 1e-8) / (0.5 - k / 17)  # t_j + δ/2 = k (T + δ)/17 − 1e-8
    near_a_node = DURATIONS + stretch * np.eye(8)[2]
    gap = k * near_a_node.sum() / 17 - grid.point_times(g, near_a_node)[j]
    assert gap == pytest.approx(1e-8, rel=1e-3)
    for d in (DURATIONS, near_a_node):
        c = np.concatenate([np.random.default_rng(4).normal(size=17), d])
        value, jac = f(c)
        np.testing.assert_allclose(value.full().ravel(), numeric(c), rtol=1e-11, atol=1e-11)
        step = 1e-7  # across the node ÿ's gradient has a kink (y'''' jumps): the differences are O(step) there
        fd = np.column_stack([(numeric(c + e) - numeric(c - e)) / (2 * step) for e in np.eye(25) * step])
        np.testing.assert_allclose(jac.full(), fd, rtol=1e-6, atol=1e-6 * np.max(np.abs(fd)))
