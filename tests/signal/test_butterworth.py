"""Zero-lag Butterworth: design frequency, gain at the cut-off, zero phase, NaN runs, edges."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import sosfiltfilt, sosfreqz

from gaitcli.errors import InputError
from gaitcli.signal.butterworth import (
    EDGE_TOLERANCE,
    correction_factor,
    design_frequency_hz,
    design_sos,
    edge_frames,
    lowpass,
    pad_length,
)

RATES_HZ = (100.0, 200.0, 1000.0)
HALF_POWER_DB = 10 * np.log10(0.5)  # -3.0103 dB


def _fit_sine(y, t, f_hz):
    """Amplitude and phase (rad) of the f_hz component of y by least squares."""
    basis = np.stack([np.sin(2 * np.pi * f_hz * t), np.cos(2 * np.pi * f_hz * t), np.ones_like(t)], axis=1)
    (a, b, _), *_ = np.linalg.lstsq(basis, y, rcond=None)
    return np.hypot(a, b), np.arctan2(b, a)


def test_correction_factor_and_design_frequency_match_model_constants():
    # docs/model_constants.md §3: C = 0.8022; 7.30 / 7.43 / 7.47 Hz at 50 / 100 / 200 Hz; 6/C in the limit.
    assert correction_factor() == pytest.approx(0.8022, abs=5e-5)
    assert design_frequency_hz(6.0, 50.0) == pytest.approx(7.30, abs=0.005)
    assert design_frequency_hz(6.0, 100.0) == pytest.approx(7.43, abs=0.005)
    assert design_frequency_hz(6.0, 200.0) == pytest.approx(7.47, abs=0.005)
    assert design_frequency_hz(6.0, 1e6) == pytest.approx(6.0 / correction_factor(), rel=1e-6)
    # one pass needs no correction
    assert design_frequency_hz(6.0, 100.0, passes=1) == pytest.approx(6.0, rel=1e-12)


@pytest.mark.parametrize("rate_hz", RATES_HZ)
def test_gain_at_cutoff_from_coefficients_is_half_power(rate_hz):
    sos = design_sos(6.0, rate_hz)
    _, h = sosfreqz(sos, worN=[6.0], fs=rate_hz)
    gain_db = 20 * np.log10(np.abs(h[0]) ** 2)  # forward + backward pass: |H|^2
    assert gain_db == pytest.approx(HALF_POWER_DB, abs=0.2)
    assert gain_db == pytest.approx(HALF_POWER_DB, abs=1e-9)  # exact for the pre-warped design


@pytest.mark.parametrize("rate_hz", RATES_HZ)
def test_gain_at_cutoff_measured_on_a_sine(rate_hz):
    t = np.arange(int(20 * rate_hz)) / rate_hz
    y = lowpass(np.sin(2 * np.pi * 6.0 * t), rate_hz=rate_hz, cutoff_hz=6.0)
    middle = slice(len(t) // 4, 3 * len(t) // 4)
    amplitude, _ = _fit_sine(y[middle], t[middle], 6.0)
    assert 20 * np.log10(amplitude) == pytest.approx(HALF_POWER_DB, abs=0.2)


@pytest.mark.parametrize("rate_hz", RATES_HZ)
def test_two_hz_sine_has_no_phase_shift(rate_hz):
    t = np.arange(int(10 * rate_hz)) / rate_hz
    x = np.sin(2 * np.pi * 2.0 * t + 0.4)
    y = lowpass(x, rate_hz=rate_hz, cutoff_hz=6.0)
    middle = slice(len(t) // 4, 3 * len(t) // 4)
    _, phase_in = _fit_sine(x[middle], t[middle], 2.0)
    _, phase_out = _fit_sine(y[middle], t[middle], 2.0)
    shift_ms = 1e3 * (phase_out - phase_in) / (2 * np.pi * 2.0)
    assert abs(shift_ms) < 1e-3
    # cross-correlation peak at lag 0 as a second measure
    lags = np.arange(-5, 6)
    xc = [np.dot(x[middle], np.roll(y, -lag)[middle]) for lag in lags]
    assert lags[int(np.argmax(xc))] == 0


@pytest.mark.parametrize("rate_hz", RATES_HZ)
def test_impulse_response_symmetric_and_dc_gain_one(rate_hz):
    n = 2 * int(rate_hz) + 1
    impulse = np.zeros(n)
    impulse[n // 2] = 1.0
    h = lowpass(impulse, rate_hz=rate_hz, cutoff_hz=6.0)
    assert int(np.argmax(h)) == n // 2
    np.testing.assert_allclose(h[n // 2 + 1:], h[n // 2 - 1::-1], atol=1e-12 * h.max())
    assert h.sum() == pytest.approx(1.0, abs=1e-6)  # area = DC gain
    const = lowpass(np.full(n, 3.7), rate_hz=rate_hz, cutoff_hz=6.0)
    np.testing.assert_allclose(const, 3.7, rtol=1e-12)


def test_nan_runs_filtered_separately_and_columns_grouped():
    rate = 100.0
    rng = np.random.default_rng(1)
    t = np.arange(300) / rate
    x = np.stack([np.sin(2 * np.pi * 1.0 * t + k) + 0.01 * rng.normal(size=t.size) for k in range(4)], axis=1)
    x[100:110, 0] = np.nan  # column 0: gap
    x[100:110, 1] = np.nan  # column 1: same pattern as 0
    x[200:297, 2] = np.nan  # column 2: leaves a 3-sample run at the end
    x[50, 2] = np.nan
    x[52, 2] = np.nan  # single finite sample at 51
    y = lowpass(x, rate_hz=rate, cutoff_hz=6.0)
    np.testing.assert_array_equal(np.isnan(y), np.isnan(x))
    sos = design_sos(6.0, rate)
    pad = pad_length(sos)
    for col, (a, b) in ((0, (0, 100)), (0, (110, 300)), (1, (110, 300)), (2, (53, 200)), (3, (0, 300))):
        expected = sosfiltfilt(sos, x[a:b, col], padlen=min(pad, b - a - 1))
        np.testing.assert_allclose(y[a:b, col], expected, rtol=1e-12, atol=1e-12)
    # a run shorter than the padding: reduced padding; a single sample: unchanged
    np.testing.assert_allclose(y[297:, 2], sosfiltfilt(sos, x[297:, 2], padlen=2), rtol=1e-12)
    assert y[51, 2] == x[51, 2]


def test_axis_and_marker_shaped_arrays():
    rate = 100.0
    rng = np.random.default_rng(2)
    x = np.cumsum(rng.normal(size=(200, 5, 3)), axis=0)
    x[40:60, 2, :] = np.nan
    y0 = lowpass(x, rate_hz=rate, cutoff_hz=6.0)
    y1 = lowpass(np.moveaxis(x, 0, 2), rate_hz=rate, cutoff_hz=6.0, axis=2)
    np.testing.assert_allclose(np.moveaxis(y1, 2, 0), y0, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(np.isnan(y0), np.isnan(x))


def test_edge_error_small_at_analog_rate():
    """Padding by the impulse-response length keeps start-up transients small at 1 kHz.

    Reference: the same signal filtered as the middle of a record three times longer.
    A 0.9 Hz, 0.3 m sine plus harmonics and a 1.2 m/s drift (a heel-marker-like
    trajectory): the edge error stays at the level set by the signal's curvature
    (about 2 mm), where scipy's default 9-sample padding leaves about 12 mm.
    """
    rate = 1000.0

    def signal(t):
        return (0.3 * np.sin(2 * np.pi * 0.9 * t + 0.3) + 0.05 * np.sin(2 * np.pi * 1.8 * t + 1)
                + 0.02 * np.sin(2 * np.pi * 2.7 * t + 2) + 1.2 * t)

    t_long = np.arange(-3000, 6000) / rate
    reference = lowpass(signal(t_long), rate_hz=rate, cutoff_hz=6.0)[3000:6000]
    y = lowpass(signal(t_long[3000:6000]), rate_hz=rate, cutoff_hz=6.0)
    assert np.abs(y - reference).max() < 0.0025
    default = sosfiltfilt(design_sos(6.0, rate), signal(t_long[3000:6000]))
    assert np.abs(default - reference).max() > 0.005


@pytest.mark.parametrize("rate_hz", (100.0, 120.0, 250.0))
def test_edge_frames_are_where_a_constant_acceleration_is_lost(rate_hz):
    """A trajectory of constant acceleration (x = a t²/2, a = 9.81 m/s²) passes the filter unchanged inside (a
    symmetric filter of DC gain 1 keeps a parabola), but the odd extension reverses its acceleration beyond each
    end: the filtered second difference is off by more than :data:`EDGE_TOLERANCE` of ``a`` in the first
    ``edge_frames`` samples at each end, and by less than 8 % (the filter's ringing) from there on, dying away
    over the padding's length (6 Hz: 5 samples at 100 and 120 Hz, 11 at 250 Hz)."""
    a = 9.81
    t = np.arange(int(2 * rate_hz)) / rate_hz
    y = lowpass(0.5 * a * t ** 2, rate_hz=rate_hz, cutoff_hz=6.0)
    acceleration = np.diff(y, 2) * rate_hz ** 2  # at samples 1 … n-2
    edge = edge_frames(design_sos(6.0, rate_hz))
    assert edge == {100.0: 5, 120.0: 5, 250.0: 11}[rate_hz]
    error = np.abs(acceleration - a) / a
    far = pad_length(design_sos(6.0, rate_hz))
    assert error[far:-far].max() < 0.01  # the parabola itself passes, where the ends' ringing has died away
    for ends in (error, error[::-1]):  # the start, then the end read backwards
        assert ends[edge - 2] > EDGE_TOLERANCE  # sample edge - 1, the last one counted
        assert ends[0] > 0.5
        assert ends[edge - 1:error.size // 2].max() < 0.08


@pytest.mark.parametrize("cutoff", [0.0, -1.0, 50.0, 80.0, float("nan")])
def test_cutoff_outside_zero_to_nyquist_is_an_input_error(cutoff):
    with pytest.raises(InputError) as info:
        lowpass(np.zeros(100), rate_hz=100.0, cutoff_hz=cutoff)
    assert info.value.field == "cutoff_hz"
    assert "Nyquist" in str(info.value)


def test_a_cut_off_whose_impulse_response_is_unbounded_is_an_input_error():
    """1e-9 of the rate: the response would be ~1e10 samples long; refused after at most 2²² (once it ran out of
    memory)."""
    with pytest.raises(InputError, match="impulse response is longer than") as info:
        lowpass(np.zeros(100), rate_hz=100.0, cutoff_hz=1e-7)
    assert info.value.field == "cutoff_hz"


def test_bad_rate_is_an_input_error():
    with pytest.raises(InputError) as info:
        design_frequency_hz(6.0, 0.0)
    assert info.value.field == "rate_hz"
