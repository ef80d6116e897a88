"""Time derivatives of the generalized coordinates for inverse dynamics (3.4.1).

Method (default ``"quintic_spline"``): the angle columns are unwrapped (2π jumps of
the Cardan angles removed), then each finite run of frames is interpolated by a
quintic B-spline through every sample (``scipy.interpolate.make_interp_spline``,
``k=5``, not-a-knot end conditions) and the spline's first and second derivatives
are evaluated at the samples. The coordinates are expected to be low-pass filtered
already (6 Hz Butterworth, 3.1.4), so interpolation rather than smoothing is used.
Runs of 4–5 frames use a cubic spline; runs shorter than 4 frames give NaN.

Alternative ``"central_difference"``: second-order central differences
(``numpy.gradient`` with second-order one-sided edges), applied twice for ``q̈``.

NaN frames (segment not tracked) stay NaN and do not affect other frames: each
run of consecutive finite frames is differentiated on its own.
"""

from __future__ import annotations

import warnings

import numpy as np
from scipy.interpolate import make_interp_spline

from gaitcli.core.numerics import true_runs
from gaitcli.core.validate import one_of
from gaitcli.errors import GaitWarning, InputError
from gaitcli.kinematics.model import COORDINATES

METHODS = ("quintic_spline", "central_difference")
#: shortest run (frames) each method can differentiate twice
_MIN_RUN = {"quintic_spline": 4, "central_difference": 3}


def _differentiate_run(y, dt, method):
    """First and second derivatives of ``y`` (m, c) sampled every ``dt`` s."""
    if method == "central_difference":
        d1 = np.gradient(y, dt, axis=0, edge_order=2)
        return d1, np.gradient(d1, dt, axis=0, edge_order=2)
    t = np.arange(y.shape[0]) * dt
    spline = make_interp_spline(t, y, k=5 if y.shape[0] >= 6 else 3, axis=0)
    return spline.derivative(1)(t), spline.derivative(2)(t)


def coordinate_derivatives(q, rate_hz: float, *, method: str = "quintic_spline", angle_columns=None):
    """First and second time derivatives of coordinates sampled at ``rate_hz`` (see the module docstring).

    Parameters
    ----------
    q : array_like
        (frames, columns), NaN where untracked.
    rate_hz : float
        Sampling rate, Hz.
    method : str
        ``"quintic_spline"`` or ``"central_difference"``.
    angle_columns : sequence of int, optional
        Columns in rad, unwrapped first; default the 24 Cardan angles when ``q`` has the 27
        model columns, none otherwise.

    Returns
    -------
    qd, qdd : numpy.ndarray
        The units of ``q`` per s and per s².
    """
    one_of(method, METHODS, where="method")
    if not np.isfinite(rate_hz) or rate_hz <= 0:
        raise InputError(None, "rate_hz", f"got {rate_hz} (expected a number > 0)")
    q = np.asarray(q, dtype=float)
    if q.ndim != 2:
        raise InputError(None, "q", f"got shape {q.shape} (expected (frames, columns))")
    if angle_columns is None:
        angle_columns = range(3, len(COORDINATES)) if q.shape[1] == len(COORDINATES) else ()
    angle = np.zeros(q.shape[1], dtype=bool)
    angle[list(angle_columns)] = True

    dt = 1.0 / rate_hz
    qd = np.full(q.shape, np.nan)
    qdd = np.full(q.shape, np.nan)
    finite = np.isfinite(q)
    short = 0
    # columns sharing a pattern of finite frames are differentiated together
    patterns, group = np.unique(finite.T, axis=0, return_inverse=True)
    for g, pattern in enumerate(patterns):
        cols = np.flatnonzero(group.ravel() == g)
        for start, stop in zip(*true_runs(pattern)):
            if stop - start < _MIN_RUN[method]:
                short += stop - start
                continue
            y = q[start:stop][:, cols].copy()
            ang = angle[cols]
            y[:, ang] = np.unwrap(y[:, ang], axis=0)
            d1, d2 = _differentiate_run(y, dt, method)
            qd[start:stop, cols] = d1
            qdd[start:stop, cols] = d2
    if short:
        warnings.warn(f"{short} finite samples in runs shorter than {_MIN_RUN[method]} frames "
                      f"could not be differentiated and were set to NaN", GaitWarning, stacklevel=2)
    return qd, qdd
