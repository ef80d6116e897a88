"""Gap filling: short interior gaps filled to sub-millimetre accuracy, the rest left NaN and reported."""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.errors import InputError
from gaitcli.signal.gaps import Gap, fill_gaps, find_gaps

RATE_HZ = 100.0
LIMIT = 10  # frames (0.1 s)


def _walking_markers(n_frames=400, n_markers=3):
    """Smooth marker paths (m): 1.2 m/s progression plus harmonics of a 0.9 Hz stride."""
    t = np.arange(n_frames) / RATE_HZ
    out = np.empty((n_frames, n_markers, 3))
    for m in range(n_markers):
        out[:, m, 0] = 1.2 * t + 0.25 * np.sin(2 * np.pi * 0.9 * t + m) + 0.04 * np.sin(2 * np.pi * 1.8 * t + 2 * m)
        out[:, m, 1] = 0.1 * m + 0.02 * np.sin(2 * np.pi * 0.9 * t + 0.5 * m)
        out[:, m, 2] = 0.1 + 0.05 * np.sin(2 * np.pi * 1.8 * t + m) + 0.01 * np.sin(2 * np.pi * 2.7 * t)
    return out


@pytest.mark.parametrize("length", [1, 4, LIMIT])
def test_short_interior_gap_filled_below_one_millimetre(length):
    truth = _walking_markers()
    positions = truth.copy()
    first = 200
    positions[first:first + length, 1, :] = np.nan
    filled, gaps = fill_gaps(positions, max_gap_frames=LIMIT)
    assert gaps == [Gap(1, first, first + length - 1, length, True)]
    error_m = np.linalg.norm(filled[first:first + length, 1] - truth[first:first + length, 1], axis=1)
    assert error_m.max() < 1e-3
    np.testing.assert_array_equal(filled[:first, 1], truth[:first, 1])
    np.testing.assert_array_equal(filled[:, [0, 2]], truth[:, [0, 2]])
    assert np.isnan(positions[first, 1, 0])  # input untouched


def test_gap_longer_than_limit_stays_nan_and_is_reported():
    positions = _walking_markers()
    positions[100:100 + LIMIT + 1, 0, :] = np.nan
    positions[300:305, 0, :] = np.nan  # a fillable gap on the same marker
    filled, gaps = fill_gaps(positions, max_gap_frames=LIMIT)
    assert gaps == [Gap(0, 100, 100 + LIMIT, LIMIT + 1, False), Gap(0, 300, 304, 5, True)]
    assert np.isnan(filled[100:100 + LIMIT + 1, 0]).all()
    assert np.isfinite(filled[300:305, 0]).all()


def test_edge_gaps_stay_nan():
    positions = _walking_markers()
    positions[:3, 0, :] = np.nan
    positions[-2:, 2, :] = np.nan
    positions[:, 1, :] = np.nan  # never seen
    filled, gaps = fill_gaps(positions, max_gap_frames=LIMIT)
    n = positions.shape[0]
    assert gaps == [Gap(0, 0, 2, 3, False), Gap(1, 0, n - 1, n, False), Gap(2, n - 2, n - 1, 2, False)]
    np.testing.assert_array_equal(np.isnan(filled), np.isnan(positions))


def test_partly_missing_frame_counts_as_missing():
    truth = _walking_markers()
    positions = truth.copy()
    positions[150:153, 2, 1] = np.nan  # only y missing
    filled, gaps = fill_gaps(positions, max_gap_frames=LIMIT)
    assert gaps == [Gap(2, 150, 152, 3, True)]
    assert np.abs(filled[150:153, 2] - truth[150:153, 2]).max() < 1e-3
    assert find_gaps(positions) == [(2, 150, 152)]


def test_zero_limit_fills_nothing():
    positions = _walking_markers()
    positions[50, 0, :] = np.nan
    filled, gaps = fill_gaps(positions, max_gap_frames=0)
    assert gaps == [Gap(0, 50, 50, 1, False)]
    assert np.isnan(filled[50, 0]).all()


@pytest.mark.parametrize("limit", [-1, 2.5, "3", None])
def test_bad_limit_is_an_input_error(limit):
    with pytest.raises(InputError) as info:
        fill_gaps(_walking_markers(), max_gap_frames=limit)
    assert info.value.field == "max_gap_frames"


def test_bad_shape_is_an_input_error():
    with pytest.raises(InputError) as info:
        fill_gaps(np.zeros((10, 3)), max_gap_frames=5)
    assert info.value.field == "positions"
