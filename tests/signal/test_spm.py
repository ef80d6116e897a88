"""SPM two-sample t-test over strides (gaitcli/signal/spm.py) on curves with truth: smooth stride-to-stride
variation (as people walk: a few degrees, low frequency) around a known mean, and a known inserted difference."""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.signal.cycles import CYCLE_PCT
from gaitcli.signal.spm import comparable, complete_strides, family_alpha, two_sample

#: a knee-flexion-like mean curve (deg)
MEAN = 30 + 25 * np.sin(2 * np.pi * (CYCLE_PCT - 40) / 100)


def strides(n: int, seed: int, *, bump_deg: float = 0.0, span=(60.0, 80.0), sd_deg: float = 2.0) -> np.ndarray:
    """``n`` strides: MEAN plus a random low-order Fourier series per stride (SD ≈ ``sd_deg`` at every point),
    plus ``bump_deg`` over ``span`` (% of the cycle, both ends included)."""
    rng = np.random.default_rng(seed)
    harmonics = 4
    phase = rng.uniform(0, 2 * np.pi, (n, harmonics, 1))
    amplitude = rng.normal(0, sd_deg * np.sqrt(2 / harmonics), (n, harmonics, 1))
    k = np.arange(1, harmonics + 1)[None, :, None]
    out = MEAN + (amplitude * np.sin(2 * np.pi * k * CYCLE_PCT / 100 + phase)).sum(axis=1)
    out[:, (CYCLE_PCT >= span[0]) & (CYCLE_PCT <= span[1])] += bump_deg
    return out


def test_an_inserted_difference_is_found_where_it_is():
    result = two_sample(strides(10, 1), strides(10, 2, bump_deg=10.0), family_alpha(0.05, 13))
    assert len(result.spans) == 1 and result.strides == (10, 10)
    span = result.spans[0]
    assert span.start_pct == pytest.approx(60, abs=3) and span.end_pct == pytest.approx(80, abs=3)
    assert span.p < 0.001 and span.largest_difference == pytest.approx(10, abs=4)
    assert np.all(np.abs(result.t[(CYCLE_PCT < 55) | (CYCLE_PCT > 85)]) < result.t_critical)


def test_two_samples_of_one_condition_are_flagged_at_most_at_the_rate_alpha():
    """Random field theory's critical t: of 100 pairs of samples of one condition at most about α flagged
    (measured: 2.7 % of 300 pairs at α = 0.05; 10 of 100 would be a false-alarm rate twice α)."""
    flagged = [bool(two_sample(strides(8, 1000 + 2 * k), strides(8, 1001 + 2 * k), 0.05).spans) for k in range(100)]
    assert sum(flagged) < 10


def test_a_lower_level_raises_the_critical_t():
    a, b = strides(6, 9), strides(6, 10)
    assert two_sample(a, b, family_alpha(0.05, 20)).t_critical > two_sample(a, b, 0.05).t_critical
    assert family_alpha(0.05, 1) == pytest.approx(0.05) and family_alpha(0.05, 13) == pytest.approx(
        1 - 0.95 ** (1 / 13))


def test_strides_with_gaps_and_too_few_are_left_out():
    a = strides(4, 11)
    a[1, 30] = np.nan  # a moment off the plates at one point
    assert complete_strides(a).shape == (3, 101)
    assert comparable(a, strides(2, 12)) and not comparable(a, strides(1, 12))
    assert not comparable(a, np.repeat(MEAN[None], 3, axis=0))  # no spread
    assert not comparable(a, np.repeat(MEAN[None], 3, axis=0) + [[0.0], [1e-12], [0.0]])  # none but round-off
