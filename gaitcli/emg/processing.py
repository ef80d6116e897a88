"""Surface EMG from raw channels to linear envelopes and on/off timing (Diss. 4.5.4 compares EID's activations
with EMG envelopes).

    raw (V or mV) → the channel's mean removed (DC offset) → zero-lag Butterworth band-pass (default 20–450 Hz;
    the upper edge at most :data:`NYQUIST_FRACTION` of the Nyquist frequency) → full-wave rectification →
    zero-lag low-pass (default 6 Hz; the record's ends extended evenly, as a rectified signal's level continues):
    the linear envelope, in the channel's unit

Every filter runs forward and backward (no lag), each edge designed so that the net response is −3 dB there
(``butterworth.design_frequency_hz``). On/off (:func:`activity`): a muscle is on where its onset envelope (the
rectified signal low-passed at :data:`ONSET_CUTOFF_HZ`, sharp enough to place an edge within a few ms) exceeds
``baseline + fraction·(peak − baseline)`` of its linear envelope (baseline its :data:`BASELINE_PERCENTILE`-th
percentile, peak its maximum; fraction :data:`ONSET_FRACTION`), bursts and gaps shorter than
:data:`MIN_BURST_S` removed. Our choices: the literature's thresholds vary (baseline + 3 SD, 10–25 % of the
peak); a fraction of the envelope's range does not depend on how quiet a trial's quietest moment is.
"""

from __future__ import annotations

import numpy as np

from gaitcli.core.numerics import true_runs
from gaitcli.errors import InputError, shown
from gaitcli.signal.butterworth import design_sos, lowpass, zero_lag

#: the band-pass's edges, Hz (surface EMG's power lies between them)
BAND_HZ = (20.0, 450.0)
#: the linear envelope's low-pass cut-off, Hz (Winter's envelopes: 6 Hz)
ENVELOPE_CUTOFF_HZ = 6.0
#: the band's upper edge at most this fraction of the Nyquist frequency (an analog rate of 1 kHz: 450 Hz stays)
NYQUIST_FRACTION = 0.9
#: the onset envelope's low-pass cut-off, Hz: its edges within ~2 ms of a step's (Hodges and Bui's 50 Hz)
ONSET_CUTOFF_HZ = 50.0
#: on above baseline + this fraction of the envelope's range
ONSET_FRACTION = 0.2
#: the baseline: this percentile of the linear envelope
BASELINE_PERCENTILE = 5.0
#: bursts and gaps shorter than this are not kept, s
MIN_BURST_S = 0.03


def band_edges(rate_hz: float, band_hz: tuple[float, float] = BAND_HZ) -> tuple[float, float]:
    """The band-pass's edges at ``rate_hz``: the upper one lowered to :data:`NYQUIST_FRACTION` of the Nyquist
    frequency where it lies above; an InputError naming ``band_hz`` where no band is left."""
    low, high = (float(f) for f in band_hz)
    high = min(high, NYQUIST_FRACTION * rate_hz / 2)
    if not (0 < low < high):
        raise InputError(None, "band_hz", f"got {shown(band_hz)} Hz at {rate_hz:g} Hz (expected 0 < low < high, high "
                                          f"below {NYQUIST_FRACTION:g} of the Nyquist frequency {rate_hz / 2:g} Hz)")
    return low, high


def bandpass(x, /, *, rate_hz: float, band_hz: tuple[float, float] = BAND_HZ, order: int = 2,
             axis: int = 0) -> np.ndarray:
    """Zero-lag Butterworth band-pass along ``axis``: a high-pass at the lower edge and a low-pass at the upper
    (:func:`band_edges`), each ``order``-th order per pass and −3 dB at its edge after the two passes."""
    low, high = band_edges(rate_hz, band_hz)
    passed = zero_lag(x, design_sos(low, rate_hz, order=order, btype="high"), axis=axis)
    return zero_lag(passed, design_sos(high, rate_hz, order=order), axis=axis)


def rectified(raw, /, *, rate_hz: float, band_hz: tuple[float, float] = BAND_HZ) -> np.ndarray:
    """|band-passed raw − its mean| (samples, channels), the channels' unit: full-wave rectified EMG."""
    x = np.asarray(raw, float)
    return np.abs(bandpass(x - np.nanmean(x, axis=0), rate_hz=rate_hz, band_hz=band_hz))


def linear_envelope(raw, /, *, rate_hz: float, band_hz: tuple[float, float] = BAND_HZ,
                    cutoff_hz: float = ENVELOPE_CUTOFF_HZ) -> np.ndarray:
    """The linear envelope (module docstring) of raw EMG (samples, channels), in the channels' unit."""
    return _envelope_of(rectified(raw, rate_hz=rate_hz, band_hz=band_hz), rate_hz, cutoff_hz)


def envelope_and_activity(raw, /, *, rate_hz: float, band_hz: tuple[float, float] = BAND_HZ,
                          envelope_cutoff_hz: float = ENVELOPE_CUTOFF_HZ, fraction: float = ONSET_FRACTION,
                          min_burst_s: float = MIN_BURST_S) -> tuple[np.ndarray, np.ndarray]:
    """The linear envelope of raw EMG (samples, channels), in the channels' unit, and whether each channel is on
    at each sample (module docstring), from one rectification."""
    rect = rectified(raw, rate_hz=rate_hz, band_hz=band_hz)
    envelope = _envelope_of(rect, rate_hz, envelope_cutoff_hz)
    return envelope, on_off(rect, envelope, rate_hz=rate_hz, fraction=fraction, min_burst_s=min_burst_s)


def activity(raw, /, **options) -> np.ndarray:
    """Whether each channel of raw EMG (samples, channels) is on at each sample (:func:`envelope_and_activity`'s
    options)."""
    return envelope_and_activity(raw, **options)[1]


def _envelope_of(rect: np.ndarray, rate_hz: float, cutoff_hz: float) -> np.ndarray:
    """Rectified EMG low-passed at ``cutoff_hz``, zero-lag, its ends extended evenly (module docstring)."""
    return lowpass(rect, rate_hz=rate_hz, cutoff_hz=cutoff_hz, padtype="even")


def on_off(rect: np.ndarray, envelope: np.ndarray, *, rate_hz: float, fraction: float = ONSET_FRACTION,
           min_burst_s: float = MIN_BURST_S) -> np.ndarray:
    """On/off (samples, channels) from rectified EMG and its linear envelope (module docstring); False where
    either is NaN."""
    onset = lowpass(rect, rate_hz=rate_hz, cutoff_hz=min(ONSET_CUTOFF_HZ, NYQUIST_FRACTION * rate_hz / 2),
                    padtype="even")
    with np.errstate(invalid="ignore"):
        on = onset > on_threshold(envelope, fraction)
    shortest = max(1, int(round(min_burst_s * rate_hz)))
    for k in range(on.shape[1]):
        on[:, k] = _without_short_runs(on[:, k], shortest)
    return on


def on_threshold(values: np.ndarray, fraction: float = ONSET_FRACTION) -> np.ndarray:
    """Per column of ``values`` (samples, channels): its :data:`BASELINE_PERCENTILE`-th percentile + ``fraction``
    of its range above that (NaN samples ignored)."""
    baseline = np.nanpercentile(values, BASELINE_PERCENTILE, axis=0)
    return baseline + fraction * (np.nanmax(values, axis=0) - baseline)


def _without_short_runs(on: np.ndarray, shortest: int) -> np.ndarray:
    """``on`` with its gaps, then its bursts, shorter than ``shortest`` samples removed (a gap at either end
    stays: nothing is known beyond it)."""
    out = on.copy()
    for value in (False, True):  # fill short gaps first, so that a burst broken by noise counts whole
        starts, stops = true_runs(out == value)
        for start, stop in zip(starts, stops):
            inside = start > 0 and stop < out.size
            if stop - start < shortest and (inside or value):
                out[start:stop] = not value
    return out


def bursts(on: np.ndarray, rate_hz: float, start_s: float = 0.0) -> list[tuple[float, float]]:
    """The (on, off) times, s, of one channel's bursts: the first sample on and the first sample off again."""
    starts, stops = true_runs(np.asarray(on, bool))
    return [(start_s + a / rate_hz, start_s + b / rate_hz) for a, b in zip(starts, stops)]
