"""Coordinate derivatives against the analytic derivatives of sines, NaN runs and angle unwrapping."""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.dynamics.derivatives import coordinate_derivatives
from gaitcli.errors import GaitWarning, InputError

RATE_HZ = 100.0
T = np.arange(200) / RATE_HZ
AMP = np.array([0.5, 0.3, 0.1])
W = 2 * np.pi * np.array([0.9, 1.7, 3.0])
PHASE = np.array([0.3, 1.0, 2.0])


def _sines(t=T):
    arg = W * t[:, None] + PHASE
    return AMP * np.sin(arg), AMP * W * np.cos(arg), -AMP * W**2 * np.sin(arg)


def test_quintic_spline_matches_analytic_derivatives():
    # measured (100 Hz, 0.9-3 Hz sines, peaks 3.2 rad/s and 36 rad/s²): interior (10 frames in from
    # each end) qd error 1.8e-8, qdd 6.3e-5; at the ends qd 4.5e-5, qdd 0.022 (6e-4 of the peak)
    q, qd, qdd = _sines()
    d1, d2 = coordinate_derivatives(q, RATE_HZ)
    np.testing.assert_allclose(d1[10:-10], qd[10:-10], atol=1e-7)
    np.testing.assert_allclose(d2[10:-10], qdd[10:-10], atol=2e-4)
    np.testing.assert_allclose(d1, qd, atol=2e-4)
    np.testing.assert_allclose(d2, qdd, atol=0.05)


def test_central_difference_matches_to_second_order():
    # measured: interior qd error 0.011 rad/s, qdd 0.42 rad/s² (1.2 % of the 3 Hz component's 36 rad/s²,
    # the second-order truncation (ωh)²/3); ends qd 0.012, qdd 2.7
    q, qd, qdd = _sines()
    d1, d2 = coordinate_derivatives(q, RATE_HZ, method="central_difference")
    np.testing.assert_allclose(d1[10:-10], qd[10:-10], atol=0.02)
    np.testing.assert_allclose(d2[10:-10], qdd[10:-10], atol=0.6)


def test_nan_runs_are_differentiated_separately():
    q, qd, qdd = _sines()
    gapped = q.copy()
    gapped[80:95, 1] = np.nan  # one coordinate not tracked for 15 frames
    d1, d2 = coordinate_derivatives(gapped, RATE_HZ)
    np.testing.assert_array_equal(np.isnan(d1), np.isnan(gapped))
    np.testing.assert_array_equal(np.isnan(d2), np.isnan(gapped))
    full1, _ = coordinate_derivatives(q, RATE_HZ)
    np.testing.assert_array_equal(d1[:, [0, 2]], full1[:, [0, 2]])  # other columns untouched
    _, before2 = coordinate_derivatives(q[:80, 1:2], RATE_HZ)
    np.testing.assert_array_equal(d2[:80, 1:2], before2)  # each run on its own
    np.testing.assert_allclose(d1[100:-10, 1], qd[100:-10, 1], atol=1e-7)
    np.testing.assert_allclose(d2[100:-10, 1], qdd[100:-10, 1], atol=2e-4)


def test_angles_are_unwrapped_before_differentiation():
    # a 27-column q whose pelvis rotation about z turns through ±π: derivatives stay those of the ramp
    q = np.zeros((T.size, 27))
    q[:, 5] = np.angle(np.exp(1j * (2.0 + 3.0 * T)))  # wrapped 2 + 3t rad
    q[:, 0] = 1.3 * T
    d1, d2 = coordinate_derivatives(q, RATE_HZ)
    np.testing.assert_allclose(d1[:, 5], 3.0, atol=1e-9)
    np.testing.assert_allclose(d2[:, 5], 0.0, atol=1e-6)
    np.testing.assert_allclose(d1[:, 0], 1.3, atol=1e-9)


def test_runs_too_short_warn_and_stay_nan():
    q, _, _ = _sines()
    q[3, :] = np.nan  # frames 0-2 form a 3-frame run
    with pytest.warns(GaitWarning, match="shorter than 4"):
        d1, d2 = coordinate_derivatives(q, RATE_HZ)
    assert np.isnan(d1[:4]).all() and np.isnan(d2[:4]).all() and np.isfinite(d2[4:]).all()


def test_bad_arguments():
    with pytest.raises(InputError, match="method"):
        coordinate_derivatives(np.zeros((10, 3)), RATE_HZ, method="spline")
    with pytest.raises(InputError, match="rate_hz"):
        coordinate_derivatives(np.zeros((10, 3)), 0.0)
    with pytest.raises(InputError, match="q"):
        coordinate_derivatives(np.zeros(10), RATE_HZ)
