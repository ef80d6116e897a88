"""A session's strides pooled (gaitcli/signal/session.py) on walks with known strides and curves: which strides
are used, their features, the mean ± SD over the used strides of both walks, and Table 3.1 over the walks."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from gaitcli.core.events import Events
from gaitcli.signal.cycles import CYCLE_PCT
from gaitcli.signal.session import STATUS_KINEMATICS, STATUS_REJECTED, STATUS_USED, Walk, pool

SPEED = 1.3  # m/s of the pelvis


def _walk(name: str, flexion: dict[int, float], off_plates: set[int] = frozenset(), stride_length_m=None) -> Walk:
    """Right strikes at 0, 1, 2 s, left at 0.5, 1.5, 2.5 s, toe offs 0.6 s after each strike: strides 1–4 in time
    order (r, l, r, l); stride k's knee flexion the constant ``flexion[k]`` (° on both sides' columns), its
    moments 1 N·m/kg, NaN over its first 60 % when k is ``off_plates``."""
    strikes = {"r": [0.0, 1.0, 2.0], "l": [0.5, 1.5, 2.5]}
    times, sides, kinds = [], [], []
    for side, ts in strikes.items():
        for t in ts:
            times += [t, t + 0.6]
            sides += [side, side]
            kinds += ["heel_strike", "toe_off"]
    events = Events(frame=np.round(np.array(times) * 100).astype(int), time_s=times, side=sides, kind=kinds,
                    source=["plate"] * len(times))
    starts = [("r", 0.0), ("l", 0.5), ("r", 1.0), ("l", 1.5)]
    blocks = []
    for k, (side, start) in enumerate(starts, start=1):
        moment = np.ones(CYCLE_PCT.size)
        if k in off_plates:
            moment[:61] = np.nan
        blocks.append(pd.DataFrame({"cycle_pct": CYCLE_PCT, "side": side, "stride": k, "start_s": start,
                                    "pelvis_tilt": float(k), f"knee_{side}_flexion": flexion[k],
                                    f"knee_{side}_extensor_moment_per_kg": moment}))
    time_s = np.arange(0, 3.001, 0.01)
    features = {"stride_length_m": stride_length_m or SPEED, "period_s": 1.0, "speed_m_s": SPEED,
                "stance_right_pct": 60.0, "stance_left_pct": 60.0, "double_stance_pct": 20.0}
    return Walk(name=name, events=events, time_s=time_s, pelvis_x_m=SPEED * time_s,
                cycles=pd.concat(blocks, ignore_index=True), features=features)


@pytest.fixture
def session():
    walks = [_walk("Walking 01", {1: 10.0, 2: 20.0, 3: 30.0, 4: 40.0}, off_plates={3}),
             _walk("Walking 02", {1: 50.0, 2: 60.0, 3: 70.0, 4: 80.0}, stride_length_m=1.5)]
    return walks, pool(walks)


def test_every_stride_and_each_sides_last_strike_is_listed_with_its_features(session):
    _, pooled = session
    s = pooled.strides
    assert len(s) == 2 * (4 + 2)
    complete = s[s.status != STATUS_REJECTED]
    np.testing.assert_allclose(complete.period_s, 1.0)
    np.testing.assert_allclose(complete.stance_pct, 60.0)
    np.testing.assert_allclose(complete.stride_length_m, SPEED)  # the pelvis's travel over one stride
    np.testing.assert_allclose(complete.speed_m_s, SPEED)
    rejected = s[s.status == STATUS_REJECTED]
    assert sorted(zip(rejected.walk, rejected.side, rejected.start_s)) == [
        ("Walking 01", "l", 2.5), ("Walking 01", "r", 2.0), ("Walking 02", "l", 2.5), ("Walking 02", "r", 2.0)]
    assert set(rejected.reason) == {"the walk ends before the next heel strike"}
    off = s[s.status == STATUS_KINEMATICS]
    assert list(zip(off.walk, off.stride)) == [("Walking 01", 3)] and "off the force plates" in off.reason.iloc[0]
    assert (s.status == STATUS_USED).sum() == 7


def test_the_means_are_over_the_used_strides_of_every_walk(session):
    _, pooled = session
    right = pooled.cycle[pooled.cycle.side == "r"]
    # right strides 1 and 3 of each walk: 10, 30, 50, 70 → mean 40, SD of the four
    np.testing.assert_allclose(right.knee_r_flexion_mean, 40.0)
    np.testing.assert_allclose(right.knee_r_flexion_sd, np.std([10, 30, 50, 70], ddof=1))
    assert (right.knee_r_flexion_n == 4).all()
    # the moments leave out walk 1's stride 3 (off the plates) everywhere, not only where it is NaN
    np.testing.assert_allclose(right.knee_r_extensor_moment_per_kg_mean, 1.0)
    assert (right.knee_r_extensor_moment_per_kg_n == 3).all()
    np.testing.assert_allclose(right.pelvis_tilt_mean, np.mean([1, 3, 1, 3]))
    left = pooled.cycle[pooled.cycle.side == "l"]
    np.testing.assert_allclose(left.knee_l_flexion_mean, np.mean([20, 40, 60, 80]))
    assert "knee_r_flexion_mean" not in left.dropna(axis=1, how="all").columns


def test_table_3_1_per_walk_and_over_the_walks(session):
    _, pooled = session
    walks = pooled.walks.set_index("walk")
    assert list(walks.index) == ["Walking 01", "Walking 02", "mean", "sd"]
    assert walks.loc["mean", "stride_length_m"] == pytest.approx(1.4)
    assert walks.loc["sd", "stride_length_m"] == pytest.approx(np.std([1.3, 1.5], ddof=1))
    info = pooled.summary()
    assert info["walks"] == 2 and info["strides"]["r"] == {"used": 3, "kinematics only": 1, "rejected": 2}
    assert info["per_stride"]["speed_m_s_mean"] == pytest.approx(SPEED)
    assert info["table_3_1_mean"]["stride_length_m"] == pytest.approx(1.4)
