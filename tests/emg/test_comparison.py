"""Activations against EMG envelopes (gaitcli/emg/comparison.py) with known answers: an envelope that is
the activation delayed by a known time gives that lag and r = 1 there, on/off agreeing everywhere; the
channels of other muscles give low correlations."""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.emg.comparison import compare_with_emg
from gaitcli.emg.stage import EmgResult

RATE_HZ = 1000.0
NODES = np.linspace(1.0, 2.1, 51)  # a cycle's nodes, s


def bursts(t, centres, width=0.06):
    return 0.03 + sum(np.exp(-((t - c) / width) ** 2) for c in centres)


def emg_of(envelopes: dict[str, np.ndarray]) -> EmgResult:
    """An EmgResult whose channels' envelopes (at 1 kHz over 3 s) are given; on above 0.3 of the peak."""
    env = np.column_stack(list(envelopes.values()))
    env /= env.max(axis=0)
    n, m = env.shape
    empty = np.zeros((0, 101, m))
    return EmgResult(channels=tuple(f"ch{k}" for k in range(m)), muscles=tuple(envelopes), rate_hz=RATE_HZ,
                     raw_V=np.zeros((n, m)), envelope=env, on=env > 0.3, reference_V=np.ones(m),
                     normalisation="peak", stride_side=np.zeros(0, "<U1"), stride_start_s=np.zeros(0),
                     stride_end_s=np.zeros(0), stride_envelope=empty, stride_on=empty.astype(bool),
                     cycle_mean=np.zeros((101, m)), cycle_sd=np.zeros((101, m)), cycle_on=np.zeros((101, m)))


@pytest.mark.parametrize("delay_s", [0.0, 0.03, -0.02])
def test_an_envelope_that_is_the_activation_delayed_gives_the_delay(delay_s):
    t = np.arange(0, 3.0, 1 / RATE_HZ)
    centres = {"soleus": (1.4, 2.5), "tibialis_anterior": (1.05, 1.8)}
    # the EMG leads the activation by delay_s: e(t) = a(t + delay)
    emg = emg_of({f"{m}_r": bursts(t + delay_s, c) for m, c in centres.items()})
    activations = np.column_stack([bursts(NODES, centres[m]) for m in ("tibialis_anterior", "soleus")])
    out = compare_with_emg(NODES, activations, ("tibialis_anterior", "soleus"), "r", emg)
    assert out.muscles == ("tibialis_anterior", "soleus") and out.channels == ("ch1", "ch0")
    np.testing.assert_allclose(out.lag_s, delay_s, atol=1.01e-3)
    np.testing.assert_allclose(out.lagged_correlation, 1.0, atol=1e-4)
    if delay_s == 0:
        np.testing.assert_allclose(out.correlation, 1.0, atol=1e-9)
        # both on above their 5th percentile + 0.2 of the range: the same nodes but at the thresholds' edges
        assert np.all(out.on_off_agreement_pct >= 95)
    # the other leg has no EMG: nothing to compare
    assert compare_with_emg(NODES, activations, ("tibialis_anterior", "soleus"), "l", emg) is None


def test_swapped_channels_correlate_poorly():
    t = np.arange(0, 3.0, 1 / RATE_HZ)
    centres = {"soleus": (1.4, 2.5), "tibialis_anterior": (1.05, 1.8)}
    swapped = emg_of({"soleus_r": bursts(t, centres["tibialis_anterior"]),
                      "tibialis_anterior_r": bursts(t, centres["soleus"])})
    activations = np.column_stack([bursts(NODES, centres[m]) for m in ("tibialis_anterior", "soleus")])
    out = compare_with_emg(NODES, activations, ("tibialis_anterior", "soleus"), "r", swapped)
    assert np.all(out.correlation < 0) and np.all(out.on_off_agreement_pct < 70)
