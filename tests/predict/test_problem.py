"""The NLP's transcription (gaitcli/predict/problem.py): numeric and symbolic evaluation agree, CasADi's exact
derivatives match finite differences (durations included), and the spline kinematics keep their periodicity."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from gaitcli.predict.problem import Transcriber
from gaitcli.predict.splines import evaluate, hip_x, quartic_midpoints

DURATIONS = [0.05, 0.09, 0.28, 0.16] * 2


@pytest.fixture(scope="module")
def transcriber() -> Transcriber:
    return Transcriber(18)


def design(transcriber, seed=0):
    rng = np.random.default_rng(seed)
    n, n_t = transcriber.layout.nodes - 1, transcriber.layout.blocks["trunk"][1]
    trunk = np.column_stack([rng.normal(scale=0.01, size=n_t), 0.9 + 0.01 * rng.normal(size=n_t),
                             0.1 * rng.normal(size=n_t)])
    legs = [np.column_stack([0.1 * rng.normal(size=n) for _ in range(3)]) for _ in range(2)]
    stretch = [0.3 + 0.2 * rng.random((n, 8)) for _ in range(2)]
    return transcriber.layout.pack({"trunk": trunk, "right_leg": legs[0], "left_leg": legs[1],
                                    "right_stretch": stretch[0], "left_stretch": stretch[1],
                                    "durations": DURATIONS, "steps": [0.65, 0.62]})


def test_numeric_and_symbolic_transcriptions_agree(transcriber):
    x = design(transcriber)
    numeric = transcriber(x)
    X = ca.MX.sym("x", transcriber.layout.size)
    symbolic = transcriber(X)
    f = ca.Function("f", [X], [symbolic.y, symbolic.ydd, ca.vertcat(*symbolic.moment_error_Nm),
                               ca.vertcat(*symbolic.contact_error_m), symbolic.metabolic_rate_W])
    y, ydd, moment, contact, rate = f(x)
    np.testing.assert_allclose(np.array(y), numeric.y, atol=1e-12)
    np.testing.assert_allclose(np.array(ydd), numeric.ydd, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(np.array(moment).ravel(), np.concatenate(numeric.moment_error_Nm), rtol=1e-8,
                               atol=1e-8)
    np.testing.assert_allclose(np.array(contact).ravel(), np.concatenate(numeric.contact_error_m), atol=1e-12)
    np.testing.assert_allclose(np.array(rate), numeric.metabolic_rate_W, rtol=1e-8, atol=1e-6)
    assert numeric.y.shape == (120, 9) and numeric.metabolic_rate_W.shape == (112, 16)


def test_hip_progresses_by_the_two_steps_per_cycle(transcriber):
    x = design(transcriber)
    t = transcriber(x)
    # the last control point closes the cycle at t = T: hip x has advanced L_r + L_l, the rest is periodic
    assert t.y[-1, 0] - t.y[0, 0] == pytest.approx(0.65 + 0.62, abs=1e-12)
    np.testing.assert_allclose(t.y[-1, 1:], t.y[0, 1:], atol=1e-12)
    assert t.period_s == pytest.approx(sum(DURATIONS))


def test_points_take_the_splines_at_their_own_times(transcriber):
    # every point, the two at each phase transition and the one closing the cycle at t = T included, carries
    # the splines evaluated at its own time (hip x with its drift; the left leg's on nodes half a cycle later)
    x = design(transcriber)
    t = transcriber(x)
    blocks = transcriber.layout.unpack(x)
    times, period, stride = t.point_times_s, t.period_s, t.stride_m
    trunk, leg = quartic_midpoints(blocks["trunk"].shape[0]), transcriber.quartic
    for r, values in enumerate((t.y, t.yd, t.ydd)):
        hip = hip_x(trunk, blocks["trunk"][:, 0], period, stride, times, r)
        rest = [evaluate(trunk, blocks["trunk"][:, 1:], period, times, r),
                evaluate(leg, blocks["right_leg"], period, times, r),
                evaluate(leg, blocks["left_leg"], period, times - period / 2, r)]
        np.testing.assert_allclose(values, np.column_stack([hip, *rest]), rtol=1e-12, atol=1e-9)
    stretch = [evaluate(transcriber.cubic, blocks["right_stretch"], period, times),
               evaluate(transcriber.cubic, blocks["left_stretch"], period, times - period / 2)]
    np.testing.assert_allclose(t.stretch, np.column_stack(stretch), atol=1e-12)


def test_a_gait_given_by_its_instant_values_transcribes_as_its_design_vector(transcriber):
    # what the symmetric model uses: durations, steps and the splines' values at the instants
    x = design(transcriber)
    direct = transcriber(x)
    durations, steps_r, steps_l, _, _ = transcriber.design(x)
    given = transcriber.at(durations, steps_r, steps_l, transcriber.instant_values(x))
    np.testing.assert_allclose(np.concatenate(given.moment_error_Nm), np.concatenate(direct.moment_error_Nm),
                               rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(given.metabolic_rate_W, direct.metabolic_rate_W, rtol=1e-12)


def test_exact_derivatives_match_finite_differences(transcriber):
    # the moment and contact errors at every control point w.r.t. the whole design vector, durations included
    x = design(transcriber, seed=1)
    X = ca.MX.sym("x", transcriber.layout.size)
    t = transcriber(X)
    out = ca.vertcat(ca.vertcat(*t.moment_error_Nm), ca.vertcat(*t.contact_error_m))
    value = ca.Function("v", [X], [out])
    jacobian = ca.Function("J", [X], [ca.jacobian(out, X)])
    J = np.array(jacobian(x))
    rng = np.random.default_rng(2)
    for _ in range(3):
        direction = rng.normal(size=x.size)
        h = 1e-6
        fd = (np.array(value(x + h * direction)) - np.array(value(x - h * direction))).ravel() / (2 * h)
        np.testing.assert_allclose(J @ direction, fd, rtol=1e-4, atol=1e-4 * np.abs(fd).max())
    durations = transcriber.layout.blocks["durations"][0]
    direction = np.zeros(x.size)
    direction[durations + 2] = 1.0  # stretch phase 3 alone
    h = 1e-7
    fd = (np.array(value(x + h * direction)) - np.array(value(x - h * direction))).ravel() / (2 * h)
    np.testing.assert_allclose(J @ direction, fd, rtol=1e-3, atol=1e-3 * np.abs(fd).max())
