"""Periodic quartic/cubic splines (5.10–5.23): interpolation, continuity, accuracy, CasADi."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from numpy.polynomial import Polynomial

from gaitcli.errors import InputError
from gaitcli.predict import splines
from gaitcli.predict.splines import (
    continuity_matrix,
    cubic,
    evaluate_fractions,
    evaluate_window,
    quartic,
    segment_of,
    window_values,
)

T = 1.13  # s
SPLINES = {"quartic": splines.quartic, "cubic": splines.cubic}


def phase_sine(t, derivative=0, period=T, phase=0.3):
    """d^r/dt^r sin(2πt/T + φ), written out independently of the splines."""
    w = 2 * np.pi / period
    return w ** derivative * np.sin(w * np.asarray(t) + phase + derivative * np.pi / 2)


@pytest.mark.parametrize("kind", SPLINES)
def test_interpolates_the_nodal_values_and_wraps(kind):
    spline = SPLINES[kind](18)
    y = np.random.default_rng(1).normal(size=(17, 3))
    nodes = np.arange(18) * T / 17  # t_1 … t_nn; t_nn carries y_1
    got = splines.evaluate(spline, y, T, nodes)
    np.testing.assert_allclose(got, np.vstack([y, y[:1]]), rtol=0, atol=1e-12)
    t = np.array([0.1, 0.5, 1.0])
    np.testing.assert_allclose(splines.evaluate(spline, y, T, t - 2 * T), splines.evaluate(spline, y, T, t + 3 * T),
                               atol=1e-12)


@pytest.mark.parametrize("kind", SPLINES)
def test_derivatives_continuous_at_every_node_and_at_the_wrap(kind):
    spline = SPLINES[kind](18)
    y = np.random.default_rng(2).normal(size=17)
    pieces = [Polynomial(c) for c in (spline.matrix @ y).reshape(17, spline.degree + 1)]
    for k in range(17):  # k = 16 is the wrap: the last segment's end against the first's start
        left, right = pieces[k], pieces[(k + 1) % 17]
        for r in range(spline.degree):  # C0–C3 (quartic), C0–C2 (cubic)
            a, b = left.deriv(r)(1.0), right.deriv(r)(0.0)
            assert abs(a - b) <= 1e-9 * max(1.0, abs(a)), (k, r)
    # the next derivative is not continuous in general: the spline is exactly C^(d−1)
    jumps = [abs(pieces[k].deriv(spline.degree)(1.0) - pieces[(k + 1) % 17].deriv(spline.degree)(0.0))
             for k in range(17)]
    assert max(jumps) > 1e-3


@pytest.mark.parametrize("kind", SPLINES)
def test_constants_are_reproduced_exactly(kind):
    spline = SPLINES[kind](14)
    t = np.random.default_rng(3).uniform(-T, 2 * T, 50)
    np.testing.assert_allclose(splines.evaluate(spline, np.full(13, 3.7), T, t), 3.7, rtol=1e-13)
    for r in range(1, spline.degree):
        np.testing.assert_allclose(splines.evaluate(spline, np.full(13, 3.7), T, t, r), 0.0, atol=1e-9)


def test_quartic_error_on_a_sine_falls_like_dt_to_the_fifth():
    t = np.linspace(0, T, 2001)
    intervals = np.array([9, 17, 33])
    errors = []
    for n in intervals.tolist():
        y = phase_sine(np.arange(n) * T / n)
        errors.append(np.max(np.abs(splines.evaluate(splines.quartic(n + 1), y, T, t) - phase_sine(t))))
    orders = np.log(np.array(errors[:-1]) / errors[1:]) / np.log(intervals[1:] / intervals[:-1])
    assert np.all(orders >= 4.5), orders
    assert errors[1] < 2e-6  # N = 17 (nn = 18), the dissertation's grid


def test_derivatives_are_time_derivatives():
    spline = splines.quartic(34)
    y = phase_sine(np.arange(33) * T / 33)
    t = np.linspace(0, T, 301)
    for r, tol in ((1, 1e-5), (2, 1e-3), (3, 0.1)):
        scale = (2 * np.pi / T) ** r
        np.testing.assert_allclose(splines.evaluate(spline, y, T, t, r), phase_sine(t, r), atol=tol * scale)


@pytest.mark.parametrize("nodes", [17, 19, 5])
def test_odd_node_count_is_one_line_input_error(nodes):
    with pytest.raises(InputError) as info:
        splines.quartic(nodes)
    message = str(info.value)
    assert message.startswith(f"nodes: got {nodes} (expected an even number of nodes")
    assert "singular" in message and "\n" not in message and info.value.exit_code == 2


def test_cubic_accepts_every_node_count_and_derivative_is_checked():
    for nodes in (3, 4, 17, 18):
        assert splines.cubic(nodes).matrix.shape == (4 * (nodes - 1), nodes - 1)
    with pytest.raises(InputError, match="derivative"):
        splines.evaluate(splines.cubic(18), np.zeros(17), T, [0.1], derivative=3)


def test_hip_x_advances_by_the_stride_per_cycle():
    spline = splines.quartic(18)
    y = np.random.default_rng(4).normal(scale=0.02, size=17)
    stride = 1.31  # m
    t = np.random.default_rng(5).uniform(0, T, 20)
    for cycles in (1, 2, -1):
        np.testing.assert_allclose(splines.hip_x(spline, y, T, stride, t + cycles * T)
                                   - splines.hip_x(spline, y, T, stride, t), cycles * stride, atol=1e-12)
    # the mean velocity over a cycle is ΔS/T
    grid = np.linspace(0, T, 4001)
    velocity = splines.hip_x(spline, y, T, stride, grid, 1)
    assert np.trapezoid(velocity, grid) / T == pytest.approx(stride / T, rel=1e-9)


def symbolic_and_numeric(spline, times, derivative, symbol=ca.SX):
    """The CasADi expression of the spline (nodal values and T symbolic) as a function, and numpy evaluation."""
    y, period = symbol.sym("y", spline.intervals), symbol.sym("T")
    expr = splines.evaluate(spline, y, period, times, derivative)
    return ca.Function("f", [y, period], [expr, ca.jacobian(expr, ca.vertcat(y, period))])


@pytest.mark.parametrize("kind", SPLINES)
@pytest.mark.parametrize("symbol", [ca.SX, ca.MX])
def test_casadi_evaluation_equals_numpy(kind, symbol):
    spline = SPLINES[kind](18)
    y = np.random.default_rng(6).normal(size=17)
    t = np.random.default_rng(7).uniform(-0.2, 2 * T, 25)
    for r in range(spline.degree):
        f = symbolic_and_numeric(spline, t, r, symbol)
        expected = splines.evaluate(spline, y, T, t, r)
        np.testing.assert_allclose(f(y, T)[0].full().ravel(), expected, rtol=1e-12, atol=1e-12)
        fractions = ca.SX.sym("s", 25)  # symbolic fractions, numeric nodal values and period
        g = ca.Function("g", [fractions], [splines.evaluate_fractions(spline, y, T, fractions, r)])
        np.testing.assert_allclose(g(t / T).full().ravel(), expected, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("kind", SPLINES)
def test_casadi_jacobian_equals_central_differences(kind):
    spline = SPLINES[kind](18)
    y = np.random.default_rng(8).normal(size=17)
    # one time 1e-7 s after node 5, so that changing T moves it across the node (segment switch)
    t = np.array([0.05, 5 * T / 17 + 1e-7, 0.7, 1.6])
    x0, step = np.append(y, T), 1e-6
    for r in range(spline.degree - 1):  # the derivatives whose gradient is continuous across a node
        f = symbolic_and_numeric(spline, t, r)
        jac = f(y, T)[1].full()
        fd = np.column_stack([(splines.evaluate(spline, (x0 + e)[:-1], (x0 + e)[-1], t, r)
                               - splines.evaluate(spline, (x0 - e)[:-1], (x0 - e)[-1], t, r)) / (2 * step)
                              for e in np.eye(18) * step])
        np.testing.assert_allclose(jac, fd, rtol=1e-6, atol=1e-6 * np.max(np.abs(fd)))


def test_hip_x_casadi_equals_numpy():
    spline = splines.quartic(18)
    y = np.random.default_rng(9).normal(size=17)
    ys, period, stride = ca.SX.sym("y", 17), ca.SX.sym("T"), ca.SX.sym("dS")
    t = np.array([0.1, 0.9, 1.5])
    for r in (0, 1, 2):
        f = ca.Function("f", [ys, period, stride], [splines.hip_x(spline, ys, period, stride, t, r)])
        np.testing.assert_allclose(f(y, T, 1.3).full().ravel(), splines.hip_x(spline, y, T, 1.3, t, r), atol=1e-12)


def test_design_vector_size():
    assert splines.design_vector_size(18) == 435
    assert [splines.design_vector_size(n) for n in (14, 16, 20)] == [335, 385, 485]
    assert splines.design_vector_size(18, muscles=12) == 367
    assert splines.design_vector_size(18, muscles=12, extra=6) == 373


@pytest.mark.parametrize("make", [quartic, cubic])
def test_continuity_matrix_holds_exactly_for_the_periodic_splines(make):
    # K·p = 0 on every column of the nodal-value → coefficient map, and its null space has exactly N
    # dimensions (the nodal values p_{k,0} then fix the spline, 5.13)
    spline = make(18)
    K = continuity_matrix(spline)
    assert np.abs(K @ spline.matrix).max() < 1e-12
    assert K.shape[1] - np.linalg.matrix_rank(K) == spline.intervals


@pytest.mark.parametrize("make", [quartic, cubic])
def test_windowed_evaluation_equals_the_spline_inside_its_window(make):
    spline = make(18)
    rng = np.random.default_rng(5)
    y = rng.normal(size=(17, 3))
    coefficients = ca.DM(spline.matrix @ y)
    period = 1.17
    for fraction in (0.0, 0.013, 0.4237, 0.5, 0.9999):
        k = int(segment_of(spline, fraction))
        for window in ((k - 1, k + 1), (k, k), (k - 1, k)):
            for r in range(spline.degree - 1):
                value = np.array(evaluate_window(spline, coefficients, period, fraction, window, r)).ravel()
                np.testing.assert_allclose(value, evaluate_fractions(spline, y, period, [fraction], r).ravel(),
                                           rtol=1e-12, atol=1e-9)
            rates = window_values(spline, coefficients, period, fraction, window, range(spline.degree - 1))
            for r, rate in enumerate(rates):  # every derivative from one selection of the segment
                np.testing.assert_allclose(np.array(rate).ravel(),
                                           evaluate_fractions(spline, y, period, [fraction], r).ravel(),
                                           rtol=1e-12, atol=1e-9)
    # outside its window the nearest window segment's polynomial is extrapolated: a different, smooth value
    outside = np.array(evaluate_window(spline, coefficients, period, 0.5, (0, 1), 0)).ravel()
    assert not np.allclose(outside, evaluate_fractions(spline, y, period, [0.5]).ravel())


@pytest.mark.parametrize("make", [quartic, cubic])
def test_bspline_coefficients_give_the_nodal_value_splines_curve(make):
    # the same curve from B-spline coefficients c (bspline_matrix) as from the nodal values y it interpolates
    # (5.13–5.23), to 1e-12 at random fractions, value and every continuous derivative; y → c → y round-trips
    spline = make(18)
    rng = np.random.default_rng(7)
    y = rng.normal(size=(17, 3))
    c = spline.bspline_of(y)
    np.testing.assert_allclose(spline.nodal_from_bspline @ c, y, atol=1e-12)
    np.testing.assert_allclose(spline.bspline_of(spline.nodal_from_bspline @ c), c, atol=1e-12)
    fractions = rng.uniform(0, 1, 200)
    for r in range(spline.degree):
        e = splines.evaluation_matrix(spline, fractions, r)
        k, tau = splines._segments(spline, fractions)
        from_c = sum(rate * tau[:, None] ** (p - r) * (spline.basis @ c).reshape(17, spline.degree + 1, 3)[
            k.astype(int), p] for p, rate in splines._terms(spline, r))
        np.testing.assert_allclose(from_c, e @ y, rtol=0, atol=1e-12 * np.abs(e @ y).max())


@pytest.mark.parametrize("degree", [3, 4])
@pytest.mark.parametrize("intervals", [5, 8, 17])
def test_bspline_matrix_is_scipys_periodic_bspline_and_local(degree, intervals):
    # against scipy's de Boor evaluation of the periodic B-spline on the integer knots (another code path than
    # the cardinal pieces bspline_matrix reads off); C^(d−1) at every node incl. the wrap (K·basis = 0), even
    # where nodal interpolation is singular (quartic, even N); segment k reads d + 1 coefficients
    from scipy.interpolate import BSpline

    basis = splines.bspline_matrix(degree, intervals)
    c = np.random.default_rng(intervals).normal(size=intervals)
    shift = (degree + 1) // 2
    knots = np.arange(-degree, intervals + degree + 1, dtype=float) - shift
    coefficients = c[(np.arange(intervals + degree) - degree) % intervals]  # scipy's basis i is our c_{i−d}
    reference = BSpline(knots, coefficients, degree, extrapolate="periodic")
    x = np.linspace(0, intervals, 301, endpoint=False)
    k = np.floor(x).astype(int)
    p = (basis @ c).reshape(intervals, degree + 1)[k]
    ours = sum(p[:, j] * (x - k) ** j for j in range(degree + 1))
    np.testing.assert_allclose(ours, reference(x), atol=1e-12)
    spline = splines.PeriodicSpline(degree, intervals, np.zeros((1, 1)))
    assert np.abs(continuity_matrix(spline) @ basis).max() < 1e-12
    per_segment = np.abs(basis.reshape(intervals, degree + 1, intervals)).sum(axis=1) > 0
    assert per_segment.sum(axis=1).max() == min(degree + 1, intervals)
