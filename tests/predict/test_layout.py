"""The design vector (gaitcli/predict/layout.py): sizes of the full (5.24) and the symmetric model (5.3.1;
docs/prediction.md), the half-cycle parity, pack/unpack round trips in numpy and CasADi, and the symmetric χ expanded
into the full model's."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from gaitcli.errors import InputError
from gaitcli.predict.layout import DesignLayout, full_from_symmetric, half_cycle_intervals
from gaitcli.predict.splines import cubic, design_vector_size, evaluate_fractions, quartic


@pytest.mark.parametrize("nodes,full,symmetric", [(14, 335, 3 * 13 + 8 * 13 + 3 * 7 + 5),
                                                  (16, 385, 3 * 15 + 8 * 15 + 3 * 9 + 5),
                                                  (18, 435, 219), (20, 485, 3 * 19 + 8 * 19 + 3 * 11 + 5)])
def test_sizes(nodes, full, symmetric):
    assert DesignLayout.build(nodes, symmetric=False).size == full == design_vector_size(nodes)
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
    first = "trunk" if symmetric else "coordinates"
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
    coordinates, stretch = _values(leg, full["coordinates"], f), _values(forces, full["tendon_stretch"], f)
    return np.array([np.abs(coordinates[:, 3:6] - _values(leg, sym["right_leg"], f)).max(),
                     np.abs(stretch[:, :8] - _values(forces, sym["right_stretch"], f)).max(),
                     np.abs(coordinates[:, 6:9] - _values(leg, sym["right_leg"], f + 0.5)).max(),
                     np.abs(coordinates[:, :3] - _values(half, sym["trunk"], 2 * f)).max(),
                     np.abs(stretch[:, 8:] - _values(forces, sym["right_stretch"], f + 0.5)).max()])


def test_full_from_symmetric_describes_the_same_gait():
    """The full χ's splines reproduce the symmetric gait: the right leg exactly (same nodal values); the left
    leg (= right leg half a cycle on) and the trunk (T/2-periodic) up to the least-squares fit's error, which falls
    with the node count at least as N⁻⁴ for the quartics and N⁻³ for the cubics."""
    coarse, fine = _expansion_errors(12), _expansion_errors(24)
    assert np.all(coarse[:2] < 1e-12) and np.all(fine[:2] < 1e-12)
    assert fine[2] < 1e-4 and fine[3] < 1e-3 and fine[4] < 1e-3  # of sinusoids of amplitude ~1.3
    assert coarse[2] / fine[2] > 16 and coarse[3] / fine[3] > 16 and coarse[4] / fine[4] > 8
