"""EMG processing (gaitcli/emg/processing.py) on synthetic EMG with known truth: the band-pass is zero-phase with its
−3 dB points at the stated edges, the linear envelope recovers the activation that modulates band-limited noise,
and on/off detection finds known bursts within 10 ms."""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.emg.processing import BAND_HZ, activity, band_edges, bandpass, bursts, linear_envelope
from gaitcli.errors import InputError

RATE_HZ = 1000.0


def synthetic_emg(activation: np.ndarray, seed: int = 0, floor: float = 0.02) -> np.ndarray:
    """Band-limited (20–450 Hz) unit noise modulated by ``activation`` (samples,), plus baseline noise of
    ``floor`` and a DC offset of 0.3: one channel's raw EMG in V."""
    rng = np.random.default_rng(seed)
    carrier = bandpass(rng.normal(size=(activation.size, 1)), rate_hz=RATE_HZ)[:, 0]
    carrier /= carrier.std()
    return (activation * carrier + floor * rng.normal(size=activation.size) + 0.3)[:, None]


def test_the_band_pass_is_zero_phase_with_its_half_power_points_at_the_edges():
    n = 8000
    impulse = np.zeros((n, 1))
    impulse[n // 2] = 1.0
    h = bandpass(impulse, rate_hz=RATE_HZ)[:, 0]
    np.testing.assert_allclose(h[n // 2 + 1:n // 2 + 400], h[n // 2 - 1:n // 2 - 400:-1], atol=1e-12)  # symmetric
    gain = np.abs(np.fft.rfft(np.roll(h, -n // 2)))
    at = {f: gain[int(round(f * n / RATE_HZ))] for f in (*BAND_HZ, 100.0)}
    assert at[BAND_HZ[0]] == pytest.approx(1 / np.sqrt(2), rel=0.01)
    assert at[BAND_HZ[1]] == pytest.approx(1 / np.sqrt(2), rel=0.01)
    assert at[100.0] == pytest.approx(1.0, abs=0.01)


def test_the_upper_edge_stays_below_the_nyquist_frequency_and_a_slow_channel_has_no_band():
    assert band_edges(1000.0) == BAND_HZ
    assert band_edges(800.0) == (20.0, 360.0)  # 0.9 of 400 Hz
    with pytest.raises(InputError, match="band_hz"):
        band_edges(40.0)  # 0.9 of 20 Hz is below the lower edge


def test_the_linear_envelope_recovers_the_activation_that_modulates_the_noise():
    t = np.arange(0, 10.0, 1 / RATE_HZ)
    # a gait-like activation: two bursts per 1.1 s cycle, smooth, 0.05 … 1
    cycle = (t % 1.1) / 1.1
    activation = 0.05 + 0.95 * (np.exp(-((cycle - 0.1) / 0.06) ** 2) + 0.6 * np.exp(-((cycle - 0.55) / 0.08) ** 2))
    envelope = linear_envelope(synthetic_emg(activation), rate_hz=RATE_HZ)[:, 0]
    inner = slice(int(RATE_HZ), -int(RATE_HZ))  # away from the record's ends
    e, a = envelope[inner] / envelope[inner].max(), activation[inner] / activation[inner].max()
    assert np.corrcoef(e, a)[0, 1] >= 0.95
    lags = np.arange(-50, 51)
    xcorr = [np.corrcoef(np.roll(e, k), a)[0, 1] for k in lags]
    assert abs(lags[int(np.argmax(xcorr))]) / RATE_HZ <= 0.010


def test_on_off_detection_finds_known_bursts_within_10_ms():
    t = np.arange(0, 6.0, 1 / RATE_HZ)
    truth = [(0.40, 0.75), (1.50, 1.62), (2.30, 3.10), (4.00, 4.45)]
    activation = np.full(t.size, 0.03)
    for on, off in truth:
        activation[(t >= on) & (t < off)] = 1.0
    found = bursts(activity(synthetic_emg(activation, seed=3), rate_hz=RATE_HZ)[:, 0], RATE_HZ)
    assert len(found) == len(truth), found
    np.testing.assert_allclose(np.array(found), np.array(truth), atol=0.010)


def test_bursts_and_gaps_shorter_than_the_minimum_are_not_kept():
    # a 10 ms blip stays off, a 10 ms dropout inside a burst stays on
    t = np.arange(0, 3.0, 1 / RATE_HZ)
    activation = np.full(t.size, 0.03)
    activation[(t >= 0.50) & (t < 0.51)] = 1.0
    activation[(t >= 1.00) & (t < 2.00)] = 1.0
    activation[(t >= 1.40) & (t < 1.41)] = 0.03
    found = bursts(activity(synthetic_emg(activation, seed=5), rate_hz=RATE_HZ)[:, 0], RATE_HZ)
    assert len(found) == 1 and found[0] == pytest.approx((1.0, 2.0), abs=0.010)
