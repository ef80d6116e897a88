"""Table 3.1's stride and the steps (gaitcli/signal/cycles.py) of a walker whose heels are planted at known
footprints: right at x = 0, 1.4, 2.8 m (y −0.06 m), left at 0.7, 2.1, 3.5 m (y +0.05 m); strides of 1 s."""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.core.events import Events
from gaitcli.signal.cycles import gait_features, steps, strides, walking_events

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


# --- events that cannot describe walking (issue 53, item 2) -------------------------------------------------

def _walk(period: float = 1.1, stance: float = 0.6, n: int = 4) -> list[tuple[float, str, str]]:
    """(time s, side, kind) of ``n`` right and left strides: the left half a period later."""
    out = []
    for side, shift in (("r", 0.0), ("l", period / 2)):
        for k in range(n + 1):
            out.append((shift + k * period, side, "heel_strike"))
            if k < n:
                out.append((shift + (k + stance) * period, side, "toe_off"))
    return out


def _events(rows) -> Events:
    rows = sorted(rows)
    return Events(frame=[round(t * 100) for t, _, _ in rows], time_s=[t for t, _, _ in rows],
                  side=[s for _, s, _ in rows], kind=[k for _, _, k in rows], source=["file"] * len(rows))


def test_a_walk_keeps_every_event():
    events = _events(_walk())
    kept, set_aside = walking_events(events)
    assert set_aside == [] and len(kept) == len(events)


def test_a_spurious_heel_strike_goes_and_its_stride_is_whole_again():
    rows = _walk() + [(1.25, "r", "heel_strike")]  # 0.15 s after the right strike at 1.1 s
    kept, set_aside = walking_events(_events(rows))
    assert [(s, a, b) for s, a, b, _ in set_aside] == [("r", 1.1, 1.25)]
    assert len(kept) == len(rows) - 1
    right = [st for st in strides(kept) if st.side == "r"]
    assert [st.period_s for st in right] == pytest.approx([1.1] * 4)
    assert [100 * (st.toe_off_s - st.start_s) / st.period_s for st in right] == pytest.approx([60.0] * 4)


def test_of_two_toe_offs_the_walking_one_stays_and_a_stance_of_95_percent_goes():
    rows = _walk() + [(1.5, "l", "toe_off")]  # a second left toe off in the stride 0.55–1.65 s: stance 86 %
    rows = [r for r in rows if not (r[1] == "r" and r[2] == "toe_off" and abs(r[0] - 2.86) < 1e-9)]
    rows.append((2.2 + 0.95 * 1.1, "r", "toe_off"))  # the right stride 2.2–3.3 s with a 95 % stance
    kept, set_aside = walking_events(_events(rows))
    reasons = {(s, round(a, 3)): why for s, a, _, why in set_aside}
    assert reasons == {("l", 0.55): "2 toe offs of one foot in it (the one at 60 % kept)",
                       ("r", 2.2): "stance 95 % (expected 40–80 %)"}
    stances = {(st.side, round(st.start_s, 3)): st.toe_off_s for st in strides(kept)}
    assert stances[("l", 0.55)] == pytest.approx(0.55 + 0.66) and np.isnan(stances[("r", 2.2)])
    assert np.isfinite(stances[("r", 0.0)]) and np.isfinite(stances[("l", 1.65)])


def test_random_events_leave_few_strides_that_could_be_walking():
    """255 random events over 4.3 s (issue 53's damaged EVENT group): nearly every stride set aside; the filter
    stage refuses a trial with fewer strides that can be walking than cannot (tests/cli/test_hostile_inputs.py)."""
    rng = np.random.default_rng(0)
    times = np.sort(rng.uniform(0, 4.3, 255))
    rows = [(t, str(rng.choice(["r", "l"])), str(rng.choice(["heel_strike", "toe_off"]))) for t in times]
    kept, set_aside = walking_events(_events(rows))
    usable = [st for st in strides(kept) if np.isfinite(st.toe_off_s)]
    assert len(set_aside) > 20 * len(usable)


def test_a_gap_longer_than_a_stride_is_no_stride():
    rows = [r for r in _walk(n=4) if not (r[1] == "r" and 1.0 < r[0] < 3.0)]  # the right strikes at 1.1, 2.2 lost
    kept, set_aside = walking_events(_events(rows))
    assert [(s, a, b) for s, a, b, _ in set_aside] == [("r", 0.0, pytest.approx(3.3))]
    assert all(st.period_s <= 3.0 for st in strides(kept))


def test_feet_that_do_not_alternate_are_set_aside():
    """The left foot striking at 85 % of every right stride (its events shifted, say, or another trial's): the
    right strides are set aside with the reason, and with them more strides than can be walking."""
    rows = [(t + (0.935 - 0.55 if side == "l" else 0.0), side, kind) for t, side, kind in _walk()]
    kept, set_aside = walking_events(_events(rows))
    right = [why for side, _, _, why in set_aside if side == "r"]
    assert right and right[0] == "the other foot strikes at 85 % in it (expected once, at 25–75 %)"
