"""The designed gait cycle (``gaitcli.synth.gait``)."""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.synth.gait import (
    DOUBLE_SUPPORT,
    ROLL_RADIUS_M,
    cycle_events,
    inverted_pendulum_com,
    pelvis_over_rocker,
)


def test_period_option_sets_the_cycle(walk):
    design = walk[0]
    assert design.period_s == 1.40
    assert design.time_s[-1] + design.time_s[1] == pytest.approx(1.40)


def test_the_pendulum_com_satisfies_its_equation_of_motion():
    """``inverted_pendulum_com``: the periodic x(t) of ẍ = ω² (x − p) over a two-harmonic COP path p; checked by
    a second central difference (error ~ (kΔt)²/12 ≈ 1e-5 relative), and a fixed COP keeps the CoM above it."""
    T, n, omega2 = 1.2, 1200, 9.81 / 0.95
    t = np.arange(n) * T / n
    w = 2 * np.pi / T
    cop = 0.3 + 0.10 * np.cos(w * t) + 0.03 * np.sin(2 * w * t + 0.3)
    com = inverted_pendulum_com(cop, omega2, T)
    dt = T / n
    acceleration = (np.roll(com, -1) - 2 * com + np.roll(com, 1)) / dt ** 2
    assert np.max(np.abs(acceleration - omega2 * (com - cop))) < 1e-4 * omega2 * 0.10
    # a harmonic is scaled by ω²/(ω² + k²) < 1: the CoM swings less than the COP
    assert 0.3 - 0.10 < com.min() and com.max() < 0.3 + 0.10
    assert inverted_pendulum_com(np.full(n, 0.25), omega2, T) == pytest.approx(np.full(n, 0.25), abs=1e-15)


def test_the_events_are_where_the_warped_phase_reaches_the_designed_instants():
    """``cycle_events``: with no warp the events fall on the designed phases; a warp running 0.05 ahead of the
    output phase moves every event 0.05 earlier (right heel strike wrapping to 0.95)."""
    tau = np.arange(1000) / 1000
    designed = [(0.0, "r", "heel_strike"), (DOUBLE_SUPPORT, "l", "toe_off"), (0.5, "l", "heel_strike"),
                (0.5 + DOUBLE_SUPPORT, "r", "toe_off")]
    assert cycle_events(tau, tau) == [(pytest.approx(at, abs=1e-12), side, kind) for at, side, kind in designed]
    early = cycle_events(tau + 0.05, tau)
    assert early == [(pytest.approx((at - 0.05) % 1.0, abs=1e-12), side, kind) for at, side, kind in designed]


def test_a_rocker_rolls_forward_its_radius_times_its_pitch():
    """``pelvis_over_rocker``: rolling without slip, the rocker's centre moves forward R·Δβ from where it landed
    while staying R above the floor at the landing's y; the pelvis is that centre less the rocker's offset."""
    pitch = np.linspace(0.0, 0.4, 50)
    centre_rel = np.column_stack([np.linspace(0.1, 0.2, 50), np.full(50, -0.1), np.full(50, -0.6)])
    idx = np.arange(10, 40)
    pelvis = pelvis_over_rocker(centre_rel, pitch, np.array([1.5, 0.2]), 10, idx)
    centre = pelvis + centre_rel[idx]
    np.testing.assert_allclose(centre[:, 0], 1.5 + ROLL_RADIUS_M * (pitch[idx] - pitch[10]), rtol=0, atol=1e-15)
    np.testing.assert_allclose(centre[:, 1:], np.tile([0.2, ROLL_RADIUS_M], (idx.size, 1)), rtol=0, atol=1e-15)
