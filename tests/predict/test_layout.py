"""The design vector (gaitcli/predict/layout.py): sizes of the full (5.24) and the symmetric model (notes §3
item 6), the half-cycle parity, and pack/unpack round trips in numpy and CasADi."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from gaitcli.errors import InputError
from gaitcli.predict.layout import DesignLayout, half_cycle_intervals
from gaitcli.predict.splines import design_vector_size


@pytest.mark.parametrize("nodes,full,symmetric", [(14, 335, 3 * 13 + 8 * 13 + 3 * 7 + 5),
                                                  (16, 385, 3 * 15 + 8 * 15 + 3 * 9 + 5),
                                                  (18, 435, 219), (20, 485, 3 * 19 + 8 * 19 + 3 * 11 + 5)])
def test_sizes(nodes, full, symmetric):
    assert DesignLayout.build(nodes, symmetric=False).size == full == design_vector_size(nodes)
    assert DesignLayout.build(nodes, symmetric=True).size == symmetric  # notes §3 item 6: 219 at nn = 18


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
