"""Table 3.1's stride and the steps (gaitcli/signal/cycles.py) of a walker whose heels are planted at known
footprints: right at x = 0, 1.4, 2.8 m (y −0.06 m), left at 0.7, 2.1, 3.5 m (y +0.05 m); strides of 1 s."""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.core.events import Events
from gaitcli.signal.cycles import gait_features, steps

RATE_HZ = 100.0
TIME_S = np.arange(0.0, 3.2, 1 / RATE_HZ)
STRIKES = {"r": np.array([0.0, 1.0, 2.0]), "l": np.array([0.5, 1.5, 2.5])}
FOOTPRINT_X = {"r": np.array([0.0, 1.4, 2.8]), "l": np.array([0.7, 2.1, 3.5])}
WIDTH_Y = {"r": -0.06, "l": 0.05}
STANCE_S = 0.6


def heel(side: str) -> np.ndarray:
    """(frames, 2): planted over each stance, then a smooth swing to the next footprint (one beyond the last)."""
    prints = np.append(FOOTPRINT_X[side], FOOTPRINT_X[side][-1] + 1.4)
    x = np.full(TIME_S.size, prints[0])
    for k, strike in enumerate(STRIKES[side]):
        stance = (TIME_S >= strike) & (TIME_S < strike + STANCE_S)
        swing = (TIME_S >= strike + STANCE_S) & (TIME_S < strike + 1.0)
        x[stance] = prints[k]
        phase = (TIME_S[swing] - strike - STANCE_S) / (1.0 - STANCE_S)
        x[swing] = prints[k] + (prints[k + 1] - prints[k]) * (1 - np.cos(np.pi * phase)) / 2
    x[TIME_S < STRIKES[side][0]] = prints[0] - 1.4 * (STRIKES[side][0] - TIME_S[TIME_S < STRIKES[side][0]])
    return np.column_stack([x, np.full(TIME_S.size, WIDTH_Y[side])])


def events() -> Events:
    rows = [(t, s, "heel_strike") for s in STRIKES for t in STRIKES[s]]
    rows += [(t + STANCE_S, s, "toe_off") for s in STRIKES for t in STRIKES[s]]
    rows.sort()
    return Events(frame=[round(t * RATE_HZ) for t, _, _ in rows], time_s=[t for t, _, _ in rows],
                  side=[s for _, s, _ in rows], kind=[k for _, _, k in rows], source=["kinematics"] * len(rows))


def test_each_step_is_the_distance_between_footprints():
    found = steps(events(), {s: heel(s) for s in ("r", "l")}, TIME_S)
    # every strike after the other foot's first: left at 0.5, 1.5, 2.5; right at 1.0, 2.0
    assert [(st.side, st.strike_s) for st in found] == [("l", 0.5), ("r", 1.0), ("l", 1.5), ("r", 2.0), ("l", 2.5)]
    for st in found:
        assert st.length_m == pytest.approx(0.7, abs=1e-9) and st.width_m == pytest.approx(0.11, abs=1e-9)


def test_table_3_1_has_the_stride_and_the_steps():
    features = gait_features(events(), {s: heel(s) for s in ("r", "l")}, TIME_S)
    assert features.stride_length_m == pytest.approx(1.4) and features.period_s == pytest.approx(1.0)
    assert features.step_length_right_m == pytest.approx(0.7) and features.step_length_left_m == pytest.approx(0.7)
    assert features.step_width_m == pytest.approx(0.11)
    assert features.stance_right_pct == pytest.approx(60.0) and features.double_stance_pct == pytest.approx(20.0)
    forward_only = gait_features(events(), {s: heel(s)[:, 0] for s in ("r", "l")}, TIME_S)
    assert forward_only.stride_length_m == pytest.approx(1.4) and np.isnan(forward_only.step_width_m)
