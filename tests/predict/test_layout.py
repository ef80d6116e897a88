"""The design vector (gaitcli/predict/layout.py): sizes of the full (5.24) and the symmetric model (5.3.1;
docs/prediction.md), the half-cycle parity, pack/unpack round trips in numpy and CasADi, and the symmetric χ expanded
into the full model's."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from gaitcli.errors import InputError
from gaitcli.predict.layout import DesignLayout, full_from_symmetric, half_cycle_intervals
from gaitcli.predict.splines import cubic, design_vector_size, evaluate_fractions, quartic, quartic_midpoints


@pytest.mark.parametrize("nodes,full,symmetric", [(14, 22 * 13 + 6 * 7 + 10, 3 * 13 + 8 * 13 + 3 * 7 + 5),
                                                  (16, 22 * 15 + 6 * 9 + 10, 3 * 15 + 8 * 15 + 3 * 9 + 5),
                                                  (18, 438, 219),
                                                  (20, 22 * 19 + 6 * 11 + 10, 3 * 19 + 8 * 19 + 3 * 11 + 5)])
def test_sizes(nodes, full, symmetric):
    """The full model: (5.24)'s count with hip and HAT on 2·N_h intervals instead of N (layout.py)."""
    assert DesignLayout.build(nodes, symmetric=False).size == full
    assert full == design_vector_size(nodes) + 3 * (2 * half_cycle_intervals(nodes - 1) - (nodes - 1))
    assert DesignLayout.build(nodes, symmetric=True).size == symmetric  # 219 at nn = 18 (layout.py's table)


def test_half_cycle_interval_counts_are_odd():
    assert [half_cycle_intervals(n) for n in (13, 15, 17, 19)] == [7, 9, 9, 11]
    assert all(half_cycle_intervals(n) % 2 == 1 and half_cycle_intervals(n) >= n / 2 for n in range(3, 60))


def test_odd_node_counts_are_refused():
    with pytest.raises(InputError, match="nodes: got 17"):
        DesignLayout.build(17)


@pytest.mark.parametrize("symmetric", [True, False])
def test_pack_and_unpack_round_trip(symmetric):
    layout = DesignLayout.build(18, symmetric=symmetric)
    x = np.random.default_rng(4).normal(size=layout.size)
    blocks = layout.unpack(x)
    assert sum(b.size for b in blocks.values()) == layout.size
    np.testing.assert_array_equal(layout.pack(blocks), x)
    # one signal's nodal values are contiguous in χ (column-major blocks)
    first = "trunk"
    start, rows, _ = layout.blocks[first]
    np.testing.assert_array_equal(blocks[first][:, 1], x[start + rows:start + 2 * rows])
    symbolic = layout.unpack(ca.DM(x))
    for name, value in blocks.items():
        np.testing.assert_array_equal(np.array(symbolic[name]), value)


def _symmetric_gait(nodes):
    """A smooth symmetric χ: sinusoids over the cycle (right leg, stretch) and the half cycle (trunk)."""
    layout = DesignLayout.build(nodes, symmetric=True)
    n, n_h = nodes - 1, layout.blocks["trunk"][1]
    s, s_h = np.arange(n) / n, np.arange(n_h) / n_h
    wave = lambda f, cols: np.column_stack([np.sin(2 * np.pi * f + c) + 0.3 * np.cos(4 * np.pi * f + 2 * c)  # noqa
                                            for c in range(cols)])
    return layout.pack({"trunk": wave(s_h, 3), "right_leg": wave(s, 3), "right_stretch": 1 + 0.5 * wave(s, 8),
                        "durations": [0.1, 0.1, 0.3, 0.1], "steps": [0.6]})


def _values(spline, nodal, fractions):
    return evaluate_fractions(spline, nodal, 1.0, fractions)


def _expansion_errors(nodes):
    """Largest differences between the full χ's splines and the symmetric gait (right leg, right stretch,
    left leg, trunk, left stretch) over the cycle; asserts durations twice and L_l = L_r on the way."""
    x = _symmetric_gait(nodes)
    sym = DesignLayout.build(nodes, symmetric=True).unpack(x)
    full = DesignLayout.build(nodes, symmetric=False).unpack(full_from_symmetric(nodes, x))
    np.testing.assert_array_equal(full["durations"].ravel(), np.tile(sym["durations"].ravel(), 2))
    np.testing.assert_array_equal(full["steps"].ravel(), [0.6, 0.6])
    f = np.linspace(0, 1, 397, endpoint=False)
    leg, half, forces = quartic(nodes), quartic(half_cycle_intervals(nodes - 1) + 1), cubic(nodes)
    trunk = quartic_midpoints(2 * half_cycle_intervals(nodes - 1))
    left = f - 0.5  # the full model's left leg and muscles: their own nodes, half a cycle after the right's
    return np.array([np.abs(_values(leg, full["right_leg"], f) - _values(leg, sym["right_leg"], f)).max(),
                     np.abs(_values(forces, full["right_stretch"], f) - _values(forces, sym["right_stretch"], f)).max(),
                     np.abs(_values(leg, full["left_leg"], left) - _values(leg, sym["right_leg"], f + 0.5)).max(),
                     np.abs(_values(trunk, full["trunk"], f) - _values(half, sym["trunk"], 2 * f)).max(),
                     np.abs(_values(forces, full["left_stretch"], left)
                            - _values(forces, sym["right_stretch"], f + 0.5)).max()])


@pytest.mark.parametrize("nodes", [12, 18, 24])
def test_full_from_symmetric_is_the_same_gait(nodes):
    """The symmetric gait is a point of the full model's grid: every spline of the full χ equals the symmetric
    model's to round-off (the left leg the right half a cycle on, the trunk T/2-periodic) at 397 points, over 20
    of every interval: the same polynomials."""
    assert np.all(_expansion_errors(nodes) < 1e-12)


def test_midpoint_values_determine_an_even_count_quartic():
    """The full trunk's 2·N_h intervals are even: its midpoint values (unlike its nodal values) determine it."""
    spline = quartic_midpoints(18)
    values = np.random.default_rng(3).normal(size=18)
    np.testing.assert_allclose(_values(spline, values, (np.arange(18) + 0.5) / 18), values, atol=1e-12)
    assert np.linalg.cond(spline.nodal_from_bspline) < 10
