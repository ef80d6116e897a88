"""Event queries of the container (gaitcli/core/events.py) on a hand-made event list with known answers."""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.core.events import Events
from gaitcli.errors import InputError


@pytest.fixture
def events() -> Events:
    # right: on the ground from the start until 0.10 s, strikes at 0.50 (plate) and 1.50 (kinematics),
    # toe offs 0.10, 1.10 (plate); left: strikes 0.00, 1.00, toe off 0.60, last strike without a toe off
    rows = [(0.10, "r", "toe_off", "kinematics"), (0.50, "r", "heel_strike", "plate"),
            (1.10, "r", "toe_off", "plate"), (1.50, "r", "heel_strike", "kinematics"),
            (0.00, "l", "heel_strike", "kinematics"), (0.60, "l", "toe_off", "kinematics"),
            (1.00, "l", "heel_strike", "kinematics")]
    t, side, kind, source = zip(*rows)
    return Events(np.rint(np.array(t) * 100).astype(int), t, side, kind, source)


def test_times_are_sorted_per_side_kind_and_source(events):
    np.testing.assert_array_equal(events.times("r", "heel_strike"), [0.5, 1.5])
    np.testing.assert_array_equal(events.times("r", "heel_strike", "plate"), [0.5])
    np.testing.assert_array_equal(events.times("l", "toe_off"), [0.6])
    assert events.mask(side="l").sum() == 3 and events.mask(kind="toe_off", source="plate").sum() == 1


def test_stances_from_strike_to_the_next_toe_off(events):
    assert events.stances("r") == [(0.5, 1.1)]
    assert events.stances("r", "plate") == [(0.5, 1.1)]
    assert events.stances("l") == [(0.0, 0.6)]
    assert events.stances("l", max_s=0.5) == []  # a 0.6 s stance is longer than 0.5 s


def test_open_ends_count_the_trial_ends_as_stance(events):
    assert events.stances("r", open_ends=True) == [(-np.inf, 0.1), (0.5, 1.1), (1.5, np.inf)]
    assert events.stances("l", open_ends=True) == [(0.0, 0.6), (1.0, np.inf)]


def test_swings_from_toe_off_to_the_next_strike(events):
    assert events.swings("r") == [(0.1, 0.5), (1.1, 1.5)]
    assert events.swings("l") == [(0.6, 1.0)]


def test_unknown_side_is_an_input_error_with_a_hint():
    with pytest.raises(InputError, match=r"events.side: got 'right' \(expected one of r, l"):
        Events([0], [0.0], ["right"], ["heel_strike"], ["plate"])
