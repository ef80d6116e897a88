"""Shared numerics (gaitcli/core/numerics.py) on inputs with known answers."""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.core.numerics import frame_ranges, true_runs


@pytest.mark.parametrize("mask, starts, stops", [
    ([], [], []),
    ([0, 0], [], []),
    ([1, 1, 1], [0], [3]),
    ([1, 0, 1, 1, 0, 0, 1], [0, 2, 6], [1, 4, 7]),  # runs at both edges
])
def test_true_runs_are_start_and_exclusive_stop(mask, starts, stops):
    a, b = true_runs(np.array(mask, dtype=bool))
    assert a.tolist() == starts and b.tolist() == stops
    rebuilt = np.zeros(len(mask), dtype=bool)
    for i, j in zip(a, b):
        rebuilt[i:j] = True
    assert rebuilt.tolist() == [bool(m) for m in mask]


def test_frame_ranges_are_the_runs_of_consecutive_indices():
    assert frame_ranges([3, 4, 5, 9, 11, 12]) == [(3, 5), (9, 9), (11, 12)]
