"""Gait events from plates and kinematics combined, on a synthetic walk with known heel strikes and toe offs.

Tolerances, and why:

* Plate events: within 1 frame (measured 0.25-0.3 frames). The raw vertical force
  of the synthetic rises at about 7900 N/s, so it crosses the 20 N threshold 2.5 ms
  after contact; the interpolation of the crossing is exact on a linear ramp.
* Kinematic events: see ``test_kinematic_events.py``; here every true event must
  be found once, within 45 ms, whichever source gives it.
"""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.core.events import Events
from gaitcli.errors import InputError
from gaitcli.signal.contacts import partly_off, plate_owner
from gaitcli.signal.events import detect_events
from gaitcli.signal.stage import calibrate_kinematic_events
from tests.signal.conftest import (
    CENTRED_PLATE,
    EVENT_RATE_HZ,
    EVENT_THRESHOLD_N,
    event_errors_frames,
    true_event_times,
    walk_loads,
)


def _assert_all_truth_found_once(events, walk, margin_s=0.15):
    for side in "rl":
        for kind in ("heel_strike", "toe_off"):
            truth = true_event_times(walk, side, kind)
            truth = truth[(truth > margin_s) & (truth < walk.time_s[-1] - margin_s)]
            found = events.of(side, kind).time_s
            distance = np.abs(found[:, None] - truth[None, :])
            assert np.all(distance.min(axis=0) < 0.045), (side, kind)  # every truth event found
            assert np.all(distance.min(axis=1) < 0.045), (side, kind)  # nothing else
            assert len(found) == len(truth), (side, kind)  # once


def test_plate_events_within_one_frame_and_assignment(walk_factory):
    walk = walk_factory(plates=[("r", 1) + CENTRED_PLATE, ("l", 1) + CENTRED_PLATE])
    loads = walk_loads(walk)
    detection = detect_events(loads, walk.feet, walk.pelvis, EVENT_RATE_HZ, EVENT_THRESHOLD_N)
    assert [c.side for c in detection.contacts] == ["r", "l"]
    assert [c.flag for c in detection.contacts] == ["", ""]
    for c, stances in zip(detection.contacts, walk.plate_stances):
        assert {(c.side, 1)} == stances
        assert c.margin_m > 0.3
    plate = detection.events.of(source="plate")
    assert len(plate) == 4
    for side in "rl":
        for kind in ("heel_strike", "toe_off"):
            error = event_errors_frames(plate, walk, side, kind)
            assert error.size == 1 and abs(error[0]) < 1.0
    assert np.all(plate.frame == np.rint(plate.time_s * EVENT_RATE_HZ))
    _assert_all_truth_found_once(detection.events, walk)


def test_no_plates(walk_factory):
    walk = walk_factory()
    detection = detect_events([], walk.feet, walk.pelvis, EVENT_RATE_HZ, EVENT_THRESHOLD_N)
    assert detection.contacts == [] and detection.owner.shape == (0, 0)
    assert set(detection.events.source) == {"kinematics"}
    _assert_all_truth_found_once(detection.events, walk)


def test_walking_towards_minus_x(walk_factory):
    walk = walk_factory()
    flip = np.array([-1.0, -1.0, 1.0])  # turned round: x and y reversed, sides unchanged
    feet = {s: (h * flip, t * flip) for s, (h, t) in walk.feet.items()}
    detection = detect_events([], feet, walk.pelvis * flip, EVENT_RATE_HZ, EVENT_THRESHOLD_N)
    _assert_all_truth_found_once(detection.events, walk)


def test_a_plate_both_feet_stand_on_is_split_at_the_steps_between(walk_factory):
    """A 1.4 m plate under the right stance and the following left stance: the right foot owns it alone until the
    left heel strike, nobody while both stand on it, the left foot from the right toe off; the plate times the
    right heel strike and the left toe off, the kinematics (calibrated on those) the two steps in between."""
    walk = walk_factory(plates=[("r", 1, 0.33, 1.4, 0.4)])
    assert walk.plate_stances == [{("r", 1), ("l", 1)}]
    loads = walk_loads(walk)
    detection = detect_events(loads, walk.feet, walk.pelvis, EVENT_RATE_HZ, EVENT_THRESHOLD_N)
    (contact,) = detection.contacts
    assert contact.flag == "both_feet" and contact.side == ""
    assert (contact.first_side, contact.last_side) == ("r", "l")
    plate = detection.events.of(source="plate")
    assert list(zip(plate.side, plate.kind)) == [("r", "heel_strike"), ("l", "toe_off")]
    assert abs(event_errors_frames(plate, walk, "r", "heel_strike")[0]) < 1.0
    assert abs(event_errors_frames(plate, walk, "l", "toe_off")[0]) < 1.0
    events = calibrate_kinematic_events(detection.events, walk.feet, walk.pelvis, EVENT_RATE_HZ)
    owner = plate_owner(detection.contacts, loads, events)[0]
    left_strike = walk.heel_strikes["l"][(walk.heel_strikes["l"] > contact.on_time_s)][0]
    right_off = walk.toe_offs["r"][(walk.toe_offs["r"] > contact.on_time_s)][0]
    t = np.arange(owner.size) / EVENT_RATE_HZ
    both = (t > left_strike) & (t < right_off)  # both feet load it (at the strike and the toe off one is at 0 N)
    inside = (np.arange(owner.size) >= contact.first_frame) & (np.arange(owner.size) <= contact.last_frame)
    np.testing.assert_array_equal(np.flatnonzero(inside & (owner == "")), np.flatnonzero(both))  # frames 196–205
    loaded = np.arange(contact.first_frame, contact.last_frame + 1)
    assert set(owner[loaded][:5]) == {"r"} and set(owner[loaded][-5:]) == {"l"}
    _assert_all_truth_found_once(events, walk)


def test_a_second_foot_on_the_far_end_of_a_real_like_plate_is_found(walk_factory):
    """A 0.6 m plate under the right forefoot and the left heel (the right heel lands behind it, the left forefoot
    beyond it), in data as real trials give it (2 mm marker noise, heel markers above the plate, 10 N plate noise,
    COP jumps): the COP stays with the right foot alone, then with the left alone, so both feet loaded it. The
    right foot owns it until the left heel strike, nobody while both stand on it, the left foot from the right toe
    off. Before, its median COP
    distance to the right foot (3 mm) hid the left foot's 28 frames and the right foot owned it throughout."""
    from tests.signal.test_contacts import _real_like

    walk = walk_factory(plates=[("r", 1, 0.31, 0.6, 0.4)], noise_N=10.0)
    assert walk.plate_stances == [{("r", 1), ("l", 1)}]
    feet, loads = _real_like(walk)
    pelvis = walk.pelvis
    detection = detect_events(loads, feet, pelvis, EVENT_RATE_HZ, EVENT_THRESHOLD_N)
    (contact,) = detection.contacts
    assert (contact.flag, contact.first_side, contact.last_side) == ("both_feet", "r", "l")
    events = calibrate_kinematic_events(detection.events, feet, pelvis, EVENT_RATE_HZ)
    owner = plate_owner(detection.contacts, loads, events)[0]
    left_strike = walk.heel_strikes["l"][walk.heel_strikes["l"] > contact.first_frame / EVENT_RATE_HZ][0]
    right_off = walk.toe_offs["r"][walk.toe_offs["r"] > contact.first_frame / EVENT_RATE_HZ][0]
    frames = np.arange(contact.first_frame, contact.last_frame + 1)
    nobody = frames[owner[frames] == ""]
    assert nobody.size and np.all(np.diff(nobody) == 1)
    # those two steps are timed from the noisy markers: within 4 frames (the 45 ms of the kinematic events), and
    # never on the unsafe side (the right foot owning it after the left heel strike, or the left before the toe off)
    assert left_strike * EVENT_RATE_HZ - 4 <= nobody[0] <= left_strike * EVENT_RATE_HZ + 1
    assert right_off * EVENT_RATE_HZ - 1 <= nobody[-1] <= right_off * EVENT_RATE_HZ + 4
    assert set(owner[contact.first_frame:nobody[0]]) == {"r"}
    assert set(owner[nobody[-1] + 1:contact.last_frame + 1]) == {"l"}


def test_foot_straddling_two_plates(walk_factory):
    walk = walk_factory(plates=[("r", 1, -0.2, 0.3, 0.4), ("r", 1, 0.1, 0.3, 0.4)])
    detection = detect_events(walk_loads(walk), walk.feet, walk.pelvis, EVENT_RATE_HZ, EVENT_THRESHOLD_N)
    heel_plate, fore_plate = detection.contacts
    assert heel_plate.side == fore_plate.side == "r"
    assert heel_plate.heel_inside and fore_plate.toe_inside
    plate = detection.events.of(source="plate")
    assert list(plate.kind) == ["heel_strike", "toe_off"]
    assert plate.time_s[0] == heel_plate.on_time_s and plate.time_s[1] == fore_plate.off_time_s
    assert abs(event_errors_frames(plate, walk, "r", "heel_strike")[0]) < 1.0
    assert abs(event_errors_frames(plate, walk, "r", "toe_off")[0]) < 1.0
    _assert_all_truth_found_once(detection.events, walk)


def test_heel_off_the_plate_gives_a_kinematic_heel_strike(walk_factory):
    # plate moved forward: the heel lands behind it, only the forefoot loads it
    walk = walk_factory(plates=[("r", 1, 0.25, 0.4, 0.4)])
    detection = detect_events(walk_loads(walk), walk.feet, walk.pelvis, EVENT_RATE_HZ, EVENT_THRESHOLD_N)
    (contact,) = detection.contacts
    assert contact.side == "r" and not contact.heel_inside and contact.toe_inside
    assert contact.on_time_s - walk.heel_strikes["r"][1] > 0.05  # the plate saw the foot late
    right = detection.events.of("r")
    assert list(right.of(source="plate").kind) == ["toe_off"]
    strike = right.of(kind="heel_strike").time_s
    assert np.min(np.abs(strike - walk.heel_strikes["r"][1])) < 0.04  # from kinematics instead
    _assert_all_truth_found_once(detection.events, walk)


@pytest.mark.parametrize("dx,partly", [(0.0, False), (0.25, True)])
def test_a_foot_partly_off_its_plate_is_found_in_every_frame_it_owns_the_plate(walk_factory, dx, partly):
    """The walk's feet stand flat through stance (heel and toe markers on the ground): on a centred plate the
    right foot is wholly on it; with the plate 0.25 m forward its heel marker is 0.2 m behind the plate, so in
    every frame the plate is given to it, it stands partly off."""
    walk = walk_factory(plates=[("r", 1, dx, 0.4, 0.4)])
    loads = walk_loads(walk)
    detection = detect_events(loads, walk.feet, walk.pelvis, EVENT_RATE_HZ, EVENT_THRESHOLD_N)
    t = np.arange(loads[0].n_frames) / EVENT_RATE_HZ
    stance = {side: detection.events.stance_mask(side, t) for side in "rl"}
    points = {side: ([heel], [toe]) for side, (heel, toe) in walk.feet.items()}
    off = partly_off(detection.owner, loads, points, stance)
    owned = (detection.owner[0] == "r") & stance["r"]
    assert owned.sum() > 20 and not off["l"].any()
    np.testing.assert_array_equal(off["r"], owned if partly else np.zeros(t.size, bool))


def test_events_container():
    events = Events.concatenate([
        Events.from_times([1.0, 0.2], rate_hz=100.0, side="r", kind="heel_strike", source="plate"),
        Events.from_times([0.5], rate_hz=100.0, side="l", kind="toe_off", source="kinematics"),
    ])
    np.testing.assert_array_equal(events.time_s, [0.2, 0.5, 1.0])
    np.testing.assert_array_equal(events.frame, [20, 50, 100])
    assert len(events.of("r")) == 2 and len(events.of(kind="toe_off")) == 1
    assert events.rows()[1] == {"time_s": 0.5, "frame": 50, "side": "l", "kind": "toe_off", "source": "kinematics"}
    assert len(Events()) == 0 and len(Events.concatenate([])) == 0
    with pytest.raises(InputError) as info:
        Events([1], [0.01], ["x"], ["heel_strike"], ["plate"])
    assert info.value.field == "events.side"


def test_bad_inputs_are_input_errors(walk_factory):
    walk = walk_factory(plates=[("r", 1) + CENTRED_PLATE])
    with pytest.raises(InputError) as info:
        detect_events(walk_loads(walk), {"r": walk.feet["r"]}, walk.pelvis, EVENT_RATE_HZ, EVENT_THRESHOLD_N)
    assert info.value.field == "feet"
    with pytest.raises(InputError) as info:
        detect_events(walk_loads(walk), walk.feet, walk.pelvis, 200.0, EVENT_THRESHOLD_N)
    assert info.value.field == "rate_hz"
