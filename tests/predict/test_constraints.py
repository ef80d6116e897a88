"""Inequality constraints of the predictive gait (gaitcli/predict/constraints.py): the corrected phase lists
(notes §1.9, §3 item 8), friction's two inequalities, and the smooth max of the gait-shape constraints."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from gaitcli.errors import InputError
from gaitcli.predict.constraints import (GAIT_SHAPE, clearance_phases, feet_in_contact, friction, in_contact,
                                         smooth_max)


def test_clearance_and_unilateral_lists_are_the_notes():
    # §1.9 groups 2 and 3 as printed (these two lists are right)
    assert {p: in_contact(p) for p in ("heel_r", "mtp_r", "heel_l", "mtp_l")} == {
        "heel_r": (1, 2, 3), "mtp_r": (2, 3, 4, 5, 6), "heel_l": (5, 6, 7), "mtp_l": (1, 2, 6, 7, 8)}
    assert {p: clearance_phases(p) for p in ("heel_r", "mtp_r", "heel_l", "mtp_l")} == {
        "heel_r": (4, 5, 6, 7, 8), "mtp_r": (1, 7, 8), "heel_l": (1, 2, 3, 4, 8), "mtp_l": (3, 4, 5)}


def test_friction_applies_where_the_foot_is_down_not_the_printed_phases():
    # printed (5.41–5.42): right 1–7, left 1, 2, 3, 5–8 — typos (§3 item 8):
    # the right foot is down in 1–6, the left in 5–8, 1, 2
    right = tuple(n for n in range(1, 9) if "r" in feet_in_contact(n))
    left = tuple(n for n in range(1, 9) if "l" in feet_in_contact(n))
    assert right == (1, 2, 3, 4, 5, 6) and left == (1, 2, 5, 6, 7, 8)


def test_the_gait_shape_phases_are_each_legs_swing_and_late_stance():
    for name, (_, phases, _) in GAIT_SHAPE.items():
        side = name[-1]
        if name.startswith("knee"):  # swing: no point of that foot in contact
            assert all(side not in feet_in_contact(n) for n in phases), name
        else:  # late stance: that foot still down
            assert all(side in feet_in_contact(n) for n in phases), name


def test_friction_inequalities():
    inside = np.array(friction(100.0, 200.0, 0.8))
    np.testing.assert_allclose(inside, [-60.0, -260.0])
    assert max(friction(200.0, 200.0, 0.8)) == pytest.approx(40.0)  # |f_x| > μ f_z: violated by 40 N
    assert max(friction(-200.0, 200.0, 0.8)) == pytest.approx(40.0)
    with pytest.raises(InputError, match="friction_coefficient"):
        friction(1.0, 1.0, 0.0)


def test_smooth_max_bounds_the_max_from_above_within_log_n_over_beta():
    x = np.random.default_rng(2).uniform(0.0, 1.2, 72)
    beta = 500.0
    value = smooth_max(x, beta)
    assert x.max() <= value <= x.max() + np.log(x.size) / beta
    symbol = ca.SX.sym("x", 72)
    f = ca.Function("f", [symbol], [smooth_max(symbol, beta), ca.gradient(smooth_max(symbol, beta), symbol)])
    got, gradient = f(x)
    assert float(got) == pytest.approx(value, rel=1e-12)
    weights = np.exp(beta * (x - x.max()))
    np.testing.assert_allclose(np.array(gradient).ravel(), weights / weights.sum(), atol=1e-12)  # softmax
