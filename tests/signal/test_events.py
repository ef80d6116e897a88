"""Gait events on a synthetic walk with known heel strikes and toe offs.

Tolerances, and why:

* Plate events: within 1 frame (measured 0.25-0.3 frames). The raw vertical force
  of the synthetic rises at about 7900 N/s, so it crosses the 20 N threshold 2.5 ms
  after contact; the interpolation of the crossing is exact on a linear ramp.
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
from gaitcli.core.events import Events
from gaitcli.signal.events import (Contact, assign_contacts, detect_events, kinematic_events,
                                   plate_contacts, plate_owner)
from gaitcli.signal.forceplates import PlateLoad, plate_load

RATE_HZ = 100.0
THRESHOLD_N = 20.0
PLATE = (0.0, 0.6, 0.4)  # dx, length, width: a plate centred under the foot


def _loads(walk):
    return [plate_load(p, cutoff_hz=6.0, threshold_N=THRESHOLD_N, rate_hz=RATE_HZ) for p in walk.plates]


def _truth(walk, side, kind):
    return (walk.heel_strikes if kind == "heel_strike" else walk.toe_offs)[side]


def _errors_frames(events, walk, side, kind):
    truth = _truth(walk, side, kind)
    found = events.of(side, kind).time_s
    return np.array([(t - truth[np.argmin(np.abs(truth - t))]) * RATE_HZ for t in found])


def _zeni_bias_s(walk):
    """Time from the speed match to heel strike (and from toe off to it) for the half-cosine swing."""
    swing_s = walk.stride_s - walk.stance_s
    peak_speed = walk.stride_m * np.pi / (2 * swing_s)
    return swing_s * np.arcsin(walk.speed_m_s / peak_speed) / np.pi


def _assert_all_truth_found_once(events, walk, margin_s=0.15):
    for side in "rl":
        for kind in ("heel_strike", "toe_off"):
            truth = _truth(walk, side, kind)
            truth = truth[(truth > margin_s) & (truth < walk.time_s[-1] - margin_s)]
            found = events.of(side, kind).time_s
            distance = np.abs(found[:, None] - truth[None, :])
            assert np.all(distance.min(axis=0) < 0.045), (side, kind)  # every truth event found
            assert np.all(distance.min(axis=1) < 0.045), (side, kind)  # nothing else
            assert len(found) == len(truth), (side, kind)  # once


def test_plate_events_within_one_frame_and_assignment(walk_factory):
    walk = walk_factory(plates=[("r", 1) + PLATE, ("l", 1) + PLATE])
    loads = _loads(walk)
    detection = detect_events(loads, walk.feet, walk.pelvis, RATE_HZ, THRESHOLD_N)
    assert [c.side for c in detection.contacts] == ["r", "l"]
    assert [c.flag for c in detection.contacts] == ["", ""]
    for c, stances in zip(detection.contacts, walk.plate_stances):
        assert {(c.side, 1)} == stances
        assert c.margin_m > 0.3
    plate = detection.events.of(source="plate")
    assert len(plate) == 4
    for side in "rl":
        for kind in ("heel_strike", "toe_off"):
            error = _errors_frames(plate, walk, side, kind)
            assert error.size == 1 and abs(error[0]) < 1.0
    assert np.all(plate.frame == np.rint(plate.time_s * RATE_HZ))
    _assert_all_truth_found_once(detection.events, walk)


def test_kinematic_events_match_zeni_prediction(walk_factory):
    walk = walk_factory()
    bias_frames = _zeni_bias_s(walk) * RATE_HZ
    assert bias_frames == pytest.approx(3.6, abs=0.05)
    for side in "rl":
        events = kinematic_events(*walk.feet[side], walk.pelvis, RATE_HZ, side)
        assert set(events.source) == {"kinematics"} and set(events.side) == {side}
        strikes = _errors_frames(events, walk, side, "heel_strike")
        offs = _errors_frames(events, walk, side, "toe_off")
        assert strikes.size >= 3 and offs.size >= 3
        np.testing.assert_allclose(strikes, -bias_frames, atol=0.05)
        np.testing.assert_allclose(offs, bias_frames, atol=0.05)
        assert np.abs(np.concatenate([strikes, offs])).max() < 4.0


def test_refined_heel_strikes_within_one_and_a_half_frames(walk_factory):
    walk = walk_factory()
    for side in "rl":
        plain = kinematic_events(*walk.feet[side], walk.pelvis, RATE_HZ, side)
        events = kinematic_events(*walk.feet[side], walk.pelvis, RATE_HZ, side, refine=True)
        errors = _errors_frames(events, walk, side, "heel_strike")
        assert errors.size >= 3
        assert np.abs(errors).max() <= 1.5 + 1e-9
        np.testing.assert_array_equal(events.of(kind="toe_off").time_s, plain.of(kind="toe_off").time_s)


def test_no_plates(walk_factory):
    walk = walk_factory()
    detection = detect_events([], walk.feet, walk.pelvis, RATE_HZ, THRESHOLD_N)
    assert detection.contacts == [] and detection.owner.shape == (0, 0)
    assert set(detection.events.source) == {"kinematics"}
    _assert_all_truth_found_once(detection.events, walk)


def test_walking_towards_minus_x(walk_factory):
    walk = walk_factory()
    flip = np.array([-1.0, -1.0, 1.0])  # turned round: x and y reversed, sides unchanged
    feet = {s: (h * flip, t * flip) for s, (h, t) in walk.feet.items()}
    detection = detect_events([], feet, walk.pelvis * flip, RATE_HZ, THRESHOLD_N)
    _assert_all_truth_found_once(detection.events, walk)


def test_marker_gap_hides_only_its_events(walk_factory):
    walk = walk_factory()
    heel, toe = (a.copy() for a in walk.feet["r"])
    heel[230:270] = np.nan  # hides the right heel strike at 2.5 s
    events = kinematic_events(heel, toe, walk.pelvis, RATE_HZ, "r")
    strikes = events.of(kind="heel_strike").time_s
    np.testing.assert_allclose(strikes, [0.3, 1.4, 3.6], atol=0.045)
    assert len(events.of(kind="toe_off")) == len(walk.toe_offs["r"][walk.toe_offs["r"] > 0.15])


def test_both_feet_on_one_plate_flagged_not_assigned(walk_factory):
    # a 1.4 m plate under the right stance and the following left stance
    walk = walk_factory(plates=[("r", 1, 0.33, 1.4, 0.4)])
    assert walk.plate_stances == [{("r", 1), ("l", 1)}]
    loads = _loads(walk)
    detection = detect_events(loads, walk.feet, walk.pelvis, RATE_HZ, THRESHOLD_N)
    assert len(detection.contacts) == 1
    contact = detection.contacts[0]
    assert contact.flag == "both_feet" and contact.side == ""
    assert np.all(detection.owner == "")
    assert set(detection.events.source) == {"kinematics"}
    _assert_all_truth_found_once(detection.events, walk)


def test_foot_straddling_two_plates(walk_factory):
    walk = walk_factory(plates=[("r", 1, -0.2, 0.3, 0.4), ("r", 1, 0.1, 0.3, 0.4)])
    detection = detect_events(_loads(walk), walk.feet, walk.pelvis, RATE_HZ, THRESHOLD_N)
    heel_plate, fore_plate = detection.contacts
    assert heel_plate.side == fore_plate.side == "r"
    assert heel_plate.heel_inside and fore_plate.toe_inside
    plate = detection.events.of(source="plate")
    assert list(plate.kind) == ["heel_strike", "toe_off"]
    assert plate.time_s[0] == heel_plate.on_time_s and plate.time_s[1] == fore_plate.off_time_s
    assert abs(_errors_frames(plate, walk, "r", "heel_strike")[0]) < 1.0
    assert abs(_errors_frames(plate, walk, "r", "toe_off")[0]) < 1.0
    _assert_all_truth_found_once(detection.events, walk)


def test_heel_off_the_plate_gives_a_kinematic_heel_strike(walk_factory):
    # plate moved forward: the heel lands behind it, only the forefoot loads it
    walk = walk_factory(plates=[("r", 1, 0.25, 0.4, 0.4)])
    detection = detect_events(_loads(walk), walk.feet, walk.pelvis, RATE_HZ, THRESHOLD_N)
    (contact,) = detection.contacts
    assert contact.side == "r" and not contact.heel_inside and contact.toe_inside
    assert contact.on_time_s - walk.heel_strikes["r"][1] > 0.05  # the plate saw the foot late
    right = detection.events.of("r")
    assert list(right.of(source="plate").kind) == ["toe_off"]
    strike = right.of(kind="heel_strike").time_s
    assert np.min(np.abs(strike - walk.heel_strikes["r"][1])) < 0.04  # from kinematics instead
    _assert_all_truth_found_once(detection.events, walk)


def _ramp_load(fz, rate_hz=1000.0, frames=None):
    n = frames or len(fz) // 10
    force = np.zeros((n, 3))
    return PlateLoad("FP1", force, np.full((n, 3), np.nan), np.full(n, np.nan), np.zeros(n, bool), 100.0,
                     threshold_N=THRESHOLD_N, raw_vertical_force_N=fz, raw_rate_hz=rate_hz)


def test_contact_timing_interpolated_and_short_runs_handled():
    t = np.arange(3000) / 1000.0
    fz = np.clip(1000.0 * (t - 0.5), 0, 400) * (t < 2.0)  # ramp 1000 N/s from 0.5 s, drop at 2 s
    fz = fz.copy()
    fz[1500:1510] = 0.0  # a 10 ms dip: bridged
    fz[2500:2520] = 100.0  # a 20 ms spike: dropped
    (contact,) = plate_contacts([_ramp_load(fz)], threshold_N=THRESHOLD_N)
    assert contact.on_time_s == pytest.approx(0.52, abs=1e-9)  # 0.5 s + 20 N / (1000 N/s)
    assert contact.off_time_s == pytest.approx(1.999 + 380 / 400 * 0.001, abs=1e-9)
    assert (contact.first_frame, contact.last_frame) == (52, 199)  # frames at or after the onset
    # loaded from the start: no onset time
    (edge,) = plate_contacts([_ramp_load(np.full(1000, 500.0))], threshold_N=THRESHOLD_N)
    assert np.isnan(edge.on_time_s) and np.isnan(edge.off_time_s)
    assert (edge.first_frame, edge.last_frame) == (0, 99)
    # a raw contact whose filtered load never passed the threshold has no COP to assign by
    feet = np.zeros((300, 3))
    (weak,) = assign_contacts([contact], [_ramp_load(fz)], feet, feet, feet, feet)
    assert weak.flag == "no_cop" and weak.side == ""


def test_assignment_ambiguous_and_missing_markers(walk_factory):
    walk = walk_factory(plates=[("r", 1) + PLATE])
    loads = _loads(walk)
    contacts = plate_contacts(loads, threshold_N=THRESHOLD_N)
    heel_r, toe_r = walk.feet["r"]
    nan = np.full_like(heel_r, np.nan)
    (c,) = assign_contacts(contacts, loads, heel_r, toe_r, heel_r + [0, 0.02, 0], toe_r + [0, 0.02, 0])
    assert c.flag == "ambiguous" and c.side == ""
    (c,) = assign_contacts(contacts, loads, nan, nan, nan, nan)
    assert c.flag == "no_markers" and c.side == ""
    (c,) = assign_contacts(contacts, loads, heel_r, toe_r, nan, nan)  # left foot unseen: right foot fits
    assert c.side == "r" and c.flag == "" and np.isnan(c.margin_m)


def test_owner_covers_the_filtered_loaded_frames(walk_factory):
    walk = walk_factory(plates=[("r", 1) + PLATE, ("l", 1) + PLATE])
    loads = _loads(walk)
    detection = detect_events(loads, walk.feet, walk.pelvis, RATE_HZ, THRESHOLD_N)
    for p, side in enumerate("rl"):
        np.testing.assert_array_equal(detection.owner[p] == side, loads[p].loaded)
        assert np.all(detection.owner[p][~loads[p].loaded] == "")
    unassigned = [Contact(0, "FP1", 140, 206, 1.4, 2.06)]
    assert np.all(plate_owner(unassigned, loads[:1]) == "")


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
    walk = walk_factory(plates=[("r", 1) + PLATE])
    with pytest.raises(InputError) as info:
        detect_events(_loads(walk), {"r": walk.feet["r"]}, walk.pelvis, RATE_HZ, THRESHOLD_N)
    assert info.value.field == "feet"
    with pytest.raises(InputError) as info:
        detect_events(_loads(walk), walk.feet, walk.pelvis, 200.0, THRESHOLD_N)
    assert info.value.field == "rate_hz"
    with pytest.raises(InputError) as info:
        kinematic_events(*walk.feet["r"], walk.pelvis, RATE_HZ, "right")
    assert info.value.field == "side"
