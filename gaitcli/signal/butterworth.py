"""Zero-lag low-pass Butterworth filter for marker and force-plate signals (3.1.4).

The dissertation filters all measured signals with a 2nd-order Butterworth filter
run forward and then backward in time, which cancels the phase shift and squares
the magnitude response. So that the net (4th-order) filter has its half-power
point at the wanted cut-off ``f_c``, the single-pass filter is designed at a
higher frequency ``f_d`` (docs/model_constants.md §3):

    C   = (2^(1/passes) - 1)^(1/(2 order))         (0.802 for order 2, 2 passes)
    f_d = (f_s/pi) atan( tan(pi f_c / f_s) / C )   (7.43 Hz for 6 Hz at 100 Hz)

This is exact for the digital (bilinear, pre-warped) filter that
``scipy.signal.butter`` returns; the dissertation's ``6/0.802 = 7.48 Hz`` is its
limit for ``f_s -> inf``. A gap (NaN) never spreads: :func:`lowpass` filters each
finite run on its own.
"""

from __future__ import annotations

import math

import numpy as np

from gaitcli.core.numerics import true_runs
from gaitcli.errors import InputError, shown

__all__ = ["correction_factor", "design_frequency_hz", "design_sos", "edge_frames", "pad_length", "lowpass",
           "zero_lag"]


def correction_factor(*, order: int = 2, passes: int = 2) -> float:
    """Cut-off correction ``C = (2^(1/passes) - 1)^(1/(2 order))`` of a cascaded Butterworth filter."""
    return (2.0 ** (1.0 / passes) - 1.0) ** (1.0 / (2.0 * order))


def design_frequency_hz(cutoff_hz: float, rate_hz: float, *, order: int = 2, passes: int = 2,
                        btype: str = "low") -> float:
    """Single-pass design frequency (Hz) giving a net half-power cut-off ``cutoff_hz`` after ``passes`` passes.

    Low-pass: ``f_d = (f_s/pi) atan(tan(pi f_c/f_s) / C)`` (3.1.4; docs/model_constants.md §3); high-pass
    (``btype="high"``, |H|² = 1/(1 + (tan(pi f_d/f_s)/tan(pi f/f_s))^(2n))): ``atan(C tan(pi f_c/f_s))``.
    Raises :class:`InputError` unless ``0 < cutoff_hz < rate_hz / 2``.
    """
    _check_rates(cutoff_hz, rate_hz)
    if int(order) != order or order < 1:
        raise InputError(None, "order", f"got {shown(order)} (expected an integer >= 1)")
    if int(passes) != passes or passes < 1:
        raise InputError(None, "passes", f"got {shown(passes)} (expected an integer >= 1)")
    c = correction_factor(order=order, passes=passes)
    scale = c if btype == "high" else 1.0 / c
    return rate_hz / math.pi * math.atan(math.tan(math.pi * cutoff_hz / rate_hz) * scale)


def design_sos(cutoff_hz: float, rate_hz: float, *, order: int = 2, btype: str = "low") -> np.ndarray:
    """Second-order sections of the single-pass low- (or high-) pass filter, designed at
    :func:`design_frequency_hz`."""
    f_d = design_frequency_hz(cutoff_hz, rate_hz, order=order, passes=2, btype=btype)
    from scipy.signal import butter  # here, not at import: scipy.signal slows every command's start-up

    return butter(int(order), f_d, btype=btype, fs=rate_hz, output="sos")


#: the longest impulse response :func:`pad_length` looks for (a cut-off of ~1e-5 of the rate)
MAX_IMPULSE_SAMPLES = 1 << 22


def pad_length(sos: np.ndarray) -> int:
    """Odd-extension padding (samples) for :func:`scipy.signal.sosfiltfilt`: the single-pass impulse response length.

    The length is where ``|h|`` last exceeds 1e-3 of its peak (24 samples for 6 Hz at
    100 Hz, 241 at 1 kHz), and at least scipy's default. scipy's default (9 samples for order 2) is far shorter
    than the response at analog rates and leaves start-up transients of the order of
    a centimetre on marker data sampled at 1 kHz; padding by the response length keeps
    the edge error at the level set by the signal's own curvature.
    """
    from scipy.signal import sosfilt

    n = 64
    while n <= MAX_IMPULSE_SAMPLES:
        impulse = np.zeros(n)
        impulse[0] = 1.0
        h = np.abs(sosfilt(sos, impulse))
        above = np.flatnonzero(h > 1e-3 * h.max())
        if above[-1] < n // 2:
            return int(max(above[-1], 3 * (2 * len(sos) + 1)))
        n *= 2
    raise InputError(None, "cutoff_hz", f"its impulse response is longer than {MAX_IMPULSE_SAMPLES // 2:,} samples "
                                        "(expected a cut-off nearer the signal's rate)")


#: the fraction of an end's acceleration step :func:`edge_frames` allows to remain
EDGE_TOLERANCE = 0.01


def edge_frames(sos: np.ndarray) -> int:
    """Samples at each end of a run filtered by :func:`zero_lag` whose second derivative the odd extension corrupts.

    The odd extension about an end sample continues the signal's position and velocity but reverses its
    acceleration: a trajectory accelerating at ``a`` there is filtered as if its acceleration stepped from
    ``-a`` to ``+a`` at the end. The filtered acceleration is then ``a·y(k)`` at ``k`` samples in, ``y`` the
    zero-lag filter's response to that ±1 step; the count is the first ``k`` at which ``1 - y(k)`` falls to
    :data:`EDGE_TOLERANCE` (5 samples for 6 Hz at 100 Hz and at 120 Hz: ``y(0) = 0.16``, ``y(3) = 0.88``).
    No padding recovers those samples (Vint and Hinrichs, J. Biomech. 29:1637, 1996; docs/decisions.md).
    """
    from scipy.signal import sosfiltfilt

    half = 4 * pad_length(sos)
    step = np.concatenate([-np.ones(half), np.ones(half)])
    error = 1.0 - sosfiltfilt(sos, step, padlen=0)[half:]
    return int(np.argmax(error <= EDGE_TOLERANCE))


def lowpass(x, /, *, rate_hz: float, cutoff_hz: float, order: int = 2, axis: int = 0,
            padtype: str = "odd") -> np.ndarray:
    """Zero-lag low-pass Butterworth filter along ``axis`` (3.1.4); net half-power cut-off ``cutoff_hz``.

    An ``order``-th order filter designed at :func:`design_frequency_hz` is run forward and
    backward (``sosfiltfilt``, odd extension over :func:`pad_length` samples). NaN samples stay
    NaN and split the signal: each finite run is filtered on its own (columns with one NaN
    pattern together); runs shorter than the padding get ``padlen = run length - 1``, single
    samples are left as they are.

    Parameters
    ----------
    x : array_like
        Samples along ``axis``, any units (marker positions (frames, markers, 3) in m, plate
        forces (samples, 3) in N, ...).
    rate_hz : float
        Sampling rate of ``x``, Hz.
    cutoff_hz : float
        Net half-power cut-off of the forward-backward filter, Hz; ``0 < cutoff_hz < rate_hz / 2``.
    order : int
        Order of one pass (the net filter's is twice that).
    axis : int
        The time axis.
    padtype : str
        ``"odd"`` (a trajectory continues its trend) or ``"even"`` (a rectified signal keeps its level: EMG
        envelopes, whose odd extension about a sample near zero would be negative).

    Returns
    -------
    numpy.ndarray
        The filtered signal, same shape and units as ``x``.
    """
    return zero_lag(x, design_sos(cutoff_hz, rate_hz, order=order), axis=axis, padtype=padtype)


def zero_lag(x, sos: np.ndarray, *, axis: int = 0, padtype: str = "odd") -> np.ndarray:
    """``x`` filtered by the sections ``sos`` forward and backward along ``axis`` (:func:`lowpass`'s rules for
    NaN and padding)."""
    from scipy.signal import sosfiltfilt

    x = np.asarray(x, dtype=float)
    padlen = pad_length(sos)
    moved = np.moveaxis(x, axis, 0)
    n = moved.shape[0]
    flat = moved.reshape(n, -1)
    out = np.full_like(flat, np.nan)
    if flat.size == 0:
        return np.moveaxis(out.reshape(moved.shape), 0, axis)
    finite = np.isfinite(flat)
    groups: dict[bytes, list[int]] = {}  # columns by their pattern of finite samples (np.unique's rows: slow)
    for k in range(flat.shape[1]):
        groups.setdefault(np.packbits(finite[:, k]).tobytes(), []).append(k)
    for columns in groups.values():
        cols, pattern = np.array(columns), finite[:, columns[0]]
        for start, stop in zip(*true_runs(pattern)):
            seg = flat[start:stop][:, cols]
            if stop - start < 2:
                out[start:stop, cols] = seg
                continue
            out[start:stop, cols] = sosfiltfilt(sos, seg, axis=0, padtype=padtype,
                                                padlen=min(padlen, stop - start - 1))
    return np.moveaxis(out.reshape(moved.shape), 0, axis)


def _check_rates(cutoff_hz: float, rate_hz: float) -> None:
    if not (np.isfinite(rate_hz) and rate_hz > 0):
        raise InputError(None, "rate_hz", f"got {shown(rate_hz)} (expected a sampling rate > 0 Hz)")
    if not (np.isfinite(cutoff_hz) and 0 < cutoff_hz < rate_hz / 2):
        raise InputError(None, "cutoff_hz",
                         f"got {shown(cutoff_hz)} Hz (expected 0 < cutoff < Nyquist = {rate_hz / 2:g} Hz)")
