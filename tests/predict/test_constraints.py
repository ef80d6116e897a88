"""Inequality constraints of the predictive gait (gaitcli/predict/constraints.py): the corrected phase lists
(5.33–5.42; docs/prediction.md, "Contact lists"), friction's two inequalities, and the smooth max of the gait-shape
constraints."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from gaitcli.errors import InputError
from gaitcli.predict.constraints import GAIT_SHAPE, clearance_phases, feet_in_contact, friction, in_contact, smooth_max


def test_clearance_and_unilateral_lists_are_the_dissertations():
    # (5.33–5.36) and (5.37–5.40) as printed (these two lists are right)
    assert {p: in_contact(p) for p in ("heel_r", "mtp_r", "heel_l", "mtp_l")} == {
        "heel_r": (1, 2, 3), "mtp_r": (2, 3, 4, 5, 6), "heel_l": (5, 6, 7), "mtp_l": (1, 2, 6, 7, 8)}
    assert {p: clearance_phases(p) for p in ("heel_r", "mtp_r", "heel_l", "mtp_l")} == {
        "heel_r": (4, 5, 6, 7, 8), "mtp_r": (1, 7, 8), "heel_l": (1, 2, 3, 4, 8), "mtp_l": (3, 4, 5)}


def test_friction_applies_where_the_foot_is_down_not_the_printed_phases():
    # printed (5.41–5.42): right 1–7, left 1, 2, 3, 5–8 — typos (docs/prediction.md):
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


@pytest.fixture(scope="module")
def tiny():
    """The walking model on the tiniest grid: 2 control points per phase (P = 16, I = 8), 6 nodes (N = 5, the
    symmetric model's trunk N_h = 3)."""
    from gaitcli.predict.grid import control_grid
    from gaitcli.predict.problem import Transcriber

    return Transcriber(6, grid=control_grid((2,) * 8))


def _group_sizes(transcriber, symmetric, settings):
    """Each constraint group function's row count, called one by one as build_nlp calls them."""
    from gaitcli.predict import constraints as c
    from gaitcli.predict.dynamics import contact_points
    from gaitcli.predict.layout import DesignLayout
    from gaitcli.predict.nlp import constraint_rows, point_functions
    from gaitcli.predict.reference import read_reference
    from gaitcli.predict.variables import Variables
    from gaitcli.resources import bundled_reference

    v = Variables(transcriber, DesignLayout.build(6, symmetric=symmetric))
    cycle = np.arange(v.n_i) * 5 // v.n_i
    segments = {"cycle": cycle, **({"half": np.arange(v.half) * 3 // v.half} if symmetric
                                   else {"left": (cycle + 2) % 5, "trunk": np.arange(v.n_i) * 6 // v.n_i})}
    points = contact_points(v, transcriber.contact)
    functions = point_functions(v, transcriber, read_reference(bundled_reference()), points)
    rows = constraint_rows(v, transcriber, settings, functions, points, segments, 1)
    for name, group in rows.items():  # the bounds come with the rows
        assert sum(len(low) for low in group.lows) == sum(len(high) for high in group.highs) == group.size, name
    assert set(rows) == set(c.GROUPS)
    return {name: group.size for name, group in rows.items()}


def test_each_constraint_group_has_its_rows_on_a_tiny_grid(tiny):
    # counted by hand from the phase table (contact.py): the stated points are the first half cycle's 8 (phases
    # 1, 1, 2, 2, 3, 3, 4, 4) in the symmetric model, all 16 in the full one. Per phase 1 … 4 (5 … 8 mirrored):
    # reactions 5, 5, 3, 3; contact rows 4, 5, 3, 2; f_z ≥ 0 rows 2, 3, 2, 1; an MTP moment in 1 and 4; feet down
    # 2, 2, 1, 1 (two friction rows each); points clear of the floor 2, 1, 2, 3; the shape bounds 4 and a heel
    # rocker's length per foot stated
    from gaitcli.predict.settings import PredictSettings

    bounded = PredictSettings(hip_moment_Nm_per_kg=0.9, swing_hip_moment_Nm_per_kg=0.3)
    symmetric = {"nodes": 3 * 3 + 5 * 3 + 5 * 8,  # a nodal value per interval and column (trunk N_h = 3)
                 "splines": 8 * (3 + 3 + 3 + 8) + 4 * (3 + 3 + 3),  # Q's y, ẏ, ÿ, ŝ at 8 instants; P's at 4
                 "dynamics": 9 * 4, "paths": 2 * 8 * 8, "activation": 8 * 8, "excitation": 2 * 8 * 8,
                 "reactions": 2 * (5 + 5 + 3 + 3), "moment": 6 * 8, "contact": 2 * (4 + 5 + 3 + 2),
                 "unilateral": 2 * (2 + 3 + 2 + 1), "mtp": 2 * 2, "friction": 2 * 2 * (2 + 2 + 1 + 1),
                 "clearance": 2 * (2 + 1 + 2 + 3), "speed": 1, "shape": 4 + 1, "hip_bound": 8, "windows": 8 + 4,
                 "monotone": 0}
    assert _group_sizes(tiny, True, bounded) == symmetric
    full = {"nodes": 6 * 3 + 5 * 6 + 5 * 16, "splines": 8 * (9 + 9 + 9 + 16), "dynamics": 9 * 8,
            "paths": 2 * 16 * 8, "activation": 16 * 8, "excitation": 2 * 16 * 8, "reactions": 2 * 2 * (5 + 5 + 3 + 3),
            "moment": 6 * 16, "contact": 2 * 2 * (4 + 5 + 3 + 2), "unilateral": 2 * 2 * (2 + 3 + 2 + 1),
            "mtp": 2 * 2 * 2, "friction": 2 * 2 * 2 * (2 + 2 + 1 + 1), "clearance": 2 * 2 * (2 + 1 + 2 + 3),
            "speed": 1, "shape": 4 + 2, "hip_bound": 0, "windows": 3 * 8, "monotone": 0}
    assert _group_sizes(tiny, False, PredictSettings()) == full


@pytest.mark.parametrize("symmetric", [True, False])
def test_each_heel_rocker_is_at_least_its_share_of_the_cycle(tiny, symmetric):
    # the shape group's last rows: T_1 − f·ΣT (and T_5 − f·ΣT), f = foot_flat_min_pct / 100, ≥ 0; none at 0
    from gaitcli.predict.constraints import shape_rows
    from gaitcli.predict.layout import DesignLayout
    from gaitcli.predict.variables import DURATION_SCALE_S, Variables

    v = Variables(tiny, DesignLayout.build(6, symmetric=symmetric))
    assert shape_rows(v, 0.0).size == 4
    rows = shape_rows(v, 7.0)
    stated = ca.vertcat(*rows.expressions[4:])
    durations = np.array([0.08, 0.12, 0.2, 0.15] + ([] if symmetric else [0.06, 0.1, 0.25, 0.15]))
    value = ca.Function("rows", [v.durations_z], [stated])(durations / DURATION_SCALE_S)
    full = np.tile(durations, 2) if symmetric else durations
    expected = [full[k] - 0.07 * full.sum() for k in ((0,) if symmetric else (0, 4))]
    np.testing.assert_allclose(value.full().ravel(), expected, rtol=1e-12)
    assert np.all(np.concatenate(rows.lows[4:]) == 0) and np.all(np.isinf(np.concatenate(rows.highs[4:])))


def test_a_prosthetic_models_groups_leave_out_the_removed_muscles_and_add_the_monotonicity_rows():
    # soleus and tibialis anterior gone (6 of 8 muscles per leg): their splines, paths, activation and
    # excitation rows; the device's τ_s slope at each of the 71 sampled angles
    from gaitcli.predict.grid import control_grid
    from gaitcli.predict.muscles import WalkerMuscles
    from gaitcli.predict.problem import Transcriber
    from gaitcli.predict.prosthesis import COMMERCIAL_FEET
    from gaitcli.predict.settings import PredictSettings

    sach = Transcriber(6, grid=control_grid((2,) * 8), muscles=WalkerMuscles(prosthesis=COMMERCIAL_FEET["sach"]))
    sizes = _group_sizes(sach, True, PredictSettings())
    assert sizes["nodes"] == 3 * 3 + 5 * 3 + 5 * 6 and sizes["splines"] == 8 * 15 + 4 * 9
    assert sizes["paths"] == 2 * 6 * 8 and sizes["activation"] == 6 * 8 and sizes["excitation"] == 2 * 6 * 8
    assert sizes["monotone"] == PredictSettings().monotone_samples == 71
