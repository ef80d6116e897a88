"""Kinematic gait events (Zeni et al. 2008) on a synthetic walk with known heel strikes and toe offs.

Tolerances, and why:

* Kinematic events (Zeni et al. 2008): the method marks the instant the foot's
  forward speed equals the pelvis's. In this synthetic the swing foot follows a
  half-cosine, so its speed 4.71 sin(pi s) m/s passes 1.2 m/s 36 ms before heel
  strike and 36 ms after toe off: a bias of 3.6 frames, which the test predicts
  analytically and checks to 0.05 frame, with a tolerance of 4 frames against the
  truth. Real heels decelerate more abruptly (Zeni et al. report 94-98 % of events
  within 1-2 frames at 60 Hz). With ``refine=True`` (heel vertical velocity
  crossing) heel strikes are within 1.5 frames: the velocity is a difference
  between frames, so its zero crossing is located to about one frame.
"""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.errors import InputError
from gaitcli.signal.kinematic_events import kinematic_events
from tests.signal.conftest import EVENT_RATE_HZ, event_errors_frames


def _zeni_bias_s(walk):
    """Time from the speed match to heel strike (and from toe off to it) for the half-cosine swing."""
    swing_s = walk.stride_s - walk.stance_s
    peak_speed = walk.stride_m * np.pi / (2 * swing_s)
    return swing_s * np.arcsin(walk.speed_m_s / peak_speed) / np.pi


def test_kinematic_events_match_zeni_prediction(walk_factory):
    walk = walk_factory()
    bias_frames = _zeni_bias_s(walk) * EVENT_RATE_HZ
    assert bias_frames == pytest.approx(3.6, abs=0.05)
    for side in "rl":
        events = kinematic_events(*walk.feet[side], walk.pelvis, EVENT_RATE_HZ, side)
        assert set(events.source) == {"kinematics"} and set(events.side) == {side}
        strikes = event_errors_frames(events, walk, side, "heel_strike")
        offs = event_errors_frames(events, walk, side, "toe_off")
        assert strikes.size >= 3 and offs.size >= 3
        np.testing.assert_allclose(strikes, -bias_frames, atol=0.05)
        np.testing.assert_allclose(offs, bias_frames, atol=0.05)
        assert np.abs(np.concatenate([strikes, offs])).max() < 4.0


def test_refined_heel_strikes_within_one_and_a_half_frames(walk_factory):
    walk = walk_factory()
    for side in "rl":
        plain = kinematic_events(*walk.feet[side], walk.pelvis, EVENT_RATE_HZ, side)
        events = kinematic_events(*walk.feet[side], walk.pelvis, EVENT_RATE_HZ, side, refine=True)
        errors = event_errors_frames(events, walk, side, "heel_strike")
        assert errors.size >= 3
        assert np.abs(errors).max() <= 1.5 + 1e-9
        np.testing.assert_array_equal(events.of(kind="toe_off").time_s, plain.of(kind="toe_off").time_s)


def test_marker_gap_hides_only_its_events(walk_factory):
    walk = walk_factory()
    heel, toe = (a.copy() for a in walk.feet["r"])
    heel[230:270] = np.nan  # hides the right heel strike at 2.5 s
    events = kinematic_events(heel, toe, walk.pelvis, EVENT_RATE_HZ, "r")
    strikes = events.of(kind="heel_strike").time_s
    np.testing.assert_allclose(strikes, [0.3, 1.4, 3.6], atol=0.045)
    assert len(events.of(kind="toe_off")) == len(walk.toe_offs["r"][walk.toe_offs["r"] > 0.15])


def test_bad_side_is_an_input_error(walk_factory):
    walk = walk_factory()
    with pytest.raises(InputError) as info:
        kinematic_events(*walk.feet["r"], walk.pelvis, EVENT_RATE_HZ, "right")
    assert info.value.field == "side"
