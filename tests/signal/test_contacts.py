"""Plate contacts: timing of the raw vertical force's threshold crossings, and the foot that made each.

Tolerances: crossings are interpolated linearly, so a linear ramp gives them exactly (1e-9 s).
"""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.signal.contacts import (
    Contact,
    assign_contacts,
    not_wholly_on,
    other_foot_over,
    plate_contacts,
    plate_owner,
)
from gaitcli.signal.forceplates import PlateLoad
from tests.signal.conftest import CENTRED_PLATE, EVENT_THRESHOLD_N, walk_loads


def _ramp_load(fz, rate_hz=1000.0, frames=None):
    n = frames or len(fz) // 10
    force = np.zeros((n, 3))
    return PlateLoad("FP1", force, np.full((n, 3), np.nan), np.full(n, np.nan), np.zeros(n, bool), 100.0,
                     threshold_N=EVENT_THRESHOLD_N, raw_vertical_force_N=fz, raw_rate_hz=rate_hz)


def test_contact_timing_interpolated_and_short_runs_handled():
    t = np.arange(3000) / 1000.0
    fz = np.clip(1000.0 * (t - 0.5), 0, 400) * (t < 2.0)  # ramp 1000 N/s from 0.5 s, drop at 2 s
    fz = fz.copy()
    fz[1500:1510] = 0.0  # a 10 ms dip: bridged
    fz[2500:2520] = 100.0  # a 20 ms spike: dropped
    (contact,) = plate_contacts([_ramp_load(fz)], threshold_N=EVENT_THRESHOLD_N)
    assert contact.on_time_s == pytest.approx(0.52, abs=1e-9)  # 0.5 s + 20 N / (1000 N/s)
    assert contact.off_time_s == pytest.approx(1.999 + 380 / 400 * 0.001, abs=1e-9)
    assert (contact.first_frame, contact.last_frame) == (52, 199)  # frames at or after the onset
    # loaded from the start: no onset time
    (edge,) = plate_contacts([_ramp_load(np.full(1000, 500.0))], threshold_N=EVENT_THRESHOLD_N)
    assert np.isnan(edge.on_time_s) and np.isnan(edge.off_time_s)
    assert (edge.first_frame, edge.last_frame) == (0, 99)
    # a raw contact whose filtered load never passed the threshold has no COP to assign by
    feet = np.zeros((300, 3))
    (weak,) = assign_contacts([contact], [_ramp_load(fz)], feet, feet, feet, feet)
    assert weak.flag == "no_cop" and weak.side == ""


def test_assignment_ambiguous_and_missing_markers(walk_factory):
    walk = walk_factory(plates=[("r", 1) + CENTRED_PLATE])
    loads = walk_loads(walk)
    contacts = plate_contacts(loads, threshold_N=EVENT_THRESHOLD_N)
    heel_r, toe_r = walk.feet["r"]
    nan = np.full_like(heel_r, np.nan)
    (c,) = assign_contacts(contacts, loads, heel_r, toe_r, heel_r + [0, 0.02, 0], toe_r + [0, 0.02, 0])
    assert c.flag == "ambiguous" and c.side == ""
    (c,) = assign_contacts(contacts, loads, nan, nan, nan, nan)
    assert c.flag == "no_markers" and c.side == ""
    (c,) = assign_contacts(contacts, loads, heel_r, toe_r, nan, nan)  # left foot unseen: right foot fits
    assert c.side == "r" and c.flag == "" and np.isnan(c.margin_m)


def test_owner_covers_the_filtered_loaded_frames(walk_factory):
    walk = walk_factory(plates=[("r", 1) + CENTRED_PLATE, ("l", 1) + CENTRED_PLATE])
    loads = walk_loads(walk)
    contacts = assign_contacts(plate_contacts(loads, threshold_N=EVENT_THRESHOLD_N), loads,
                               *walk.feet["r"], *walk.feet["l"])
    owner = plate_owner(contacts, loads)
    for p, side in enumerate("rl"):
        np.testing.assert_array_equal(owner[p] == side, loads[p].loaded)
        assert np.all(owner[p][~loads[p].loaded] == "")
    unassigned = [Contact(0, "FP1", 140, 206, 1.4, 2.06)]
    assert np.all(plate_owner(unassigned, loads[:1]) == "")


def test_noise_spikes_before_a_loading_do_not_open_the_contact_early():
    """A real plate's noise (Vicon's stair trial: single samples above 20 N every few tens of ms) is not bridged
    into the contact: the onset stays the ramp's crossing, 0.52 s, not the first spike's 0.2 s."""
    t = np.arange(3000) / 1000.0
    fz = np.clip(1000.0 * (t - 0.5), 0, 400) * (t < 2.0)
    fz[200:500:30] = 35.0  # 1 ms spikes 30 ms apart, up to the loading
    (contact,) = plate_contacts([_ramp_load(fz)], threshold_N=EVENT_THRESHOLD_N)
    assert contact.on_time_s == pytest.approx(0.52, abs=1e-9)


def test_owner_reaches_at_most_reach_s_beyond_its_contact():
    """A plate whose filtered noise stays above the threshold the whole trial gives its foot only the contact
    and 0.1 s (10 frames) on either side, not the trial."""
    n = 300
    load = PlateLoad("FP1", np.zeros((n, 3)), np.zeros((n, 3)), np.zeros(n), np.ones(n, bool), 100.0,
                     threshold_N=EVENT_THRESHOLD_N)
    contact = Contact(0, "FP1", 120, 179, 1.2, 1.79, side="r")
    owner = plate_owner([contact], [load])[0]
    np.testing.assert_array_equal(np.flatnonzero(owner == "r"), np.arange(110, 190))


def _real_like(walk, seed=1):
    """The walk's feet and plates as a real trial gives them: 2 mm marker noise, heel markers 4 cm higher (above
    the plate, as a marker on the back of the heel sits), and the plates' COP jumping in some frames."""
    rng = np.random.default_rng(seed)
    feet = {s: tuple(m + rng.normal(0, 0.002, m.shape) + [0, 0, 0.04 * (k == 0)] for k, m in enumerate(walk.feet[s]))
            for s in "rl"}
    loads = walk_loads(walk)
    for load in loads:
        frames = np.flatnonzero(load.loaded & (load.force_N[:, 2] > 0.3 * load.force_N[:, 2].max()))
        load.cop_m[frames[5:13], 1] += 0.35  # 8 frames 35 cm to the side: off the plate
        load.cop_m[frames[20:24], 0] += 0.45  # 4 frames 45 cm ahead: on the plate, too short to be a foot
    return feet, loads


def test_a_one_foot_contact_stays_that_foots_in_real_like_data(walk_factory):
    """Marker noise, a raised heel marker, 10 N of plate noise and COP jumps do not make a plate one foot stands
    on a two-feet plate."""
    walk = walk_factory(plates=[("r", 1) + CENTRED_PLATE], noise_N=10.0)
    feet, loads = _real_like(walk)
    (contact,) = assign_contacts(plate_contacts(loads, threshold_N=EVENT_THRESHOLD_N), loads, *feet["r"], *feet["l"])
    assert (contact.side, contact.flag) == ("r", "")


def _square_plate(n, loaded, top_m=0.0):
    """A 0.4 m × 0.6 m plate (x 0–0.4, y 0–0.6) at height ``top_m``, loaded in the ``loaded`` frames."""
    corners = np.array([[0.0, 0.0, top_m], [0.4, 0.0, top_m], [0.4, 0.6, top_m], [0.0, 0.6, top_m]])
    return PlateLoad("FP1", np.zeros((n, 3)), np.full((n, 3), np.nan), np.full(n, np.nan), loaded, 100.0,
                     corners_m=corners)


def test_a_foot_resting_low_over_the_other_foots_plate_is_found_and_a_swing_passing_over_is_not():
    # 100 Hz. The right toe marker stands on the plate's near end (x = 0.05 m) 30 mm up while the right foot owns the
    # plate (frames 0-39: its standing height), stays there 32 mm up (2 mm above standing: low enough to touch)
    # while the left foot owns the loaded plate (40-59), swings over it at 2 m/s 3 mm above standing (60-79), then
    # rests over it 50 mm up (20 mm above standing: too high, 80-99). Frame 59's speed (central difference) is
    # already the swing's 1 m/s, so the resting frames are 40-58.
    n = 100
    owner = np.full((1, n), "l")
    owner[0, :40] = "r"
    toe = np.tile([0.05, 0.3, 0.03], (n, 1))
    toe[40:60, 2] = 0.032
    toe[60:80, 0] = 0.05 + 0.02 * np.arange(1, 21)  # 2 cm per frame at 100 Hz
    toe[60:80, 2] = 0.033
    toe[80:] = [0.3, 0.3, 0.05]
    over = other_foot_over(owner, [_square_plate(n, np.ones(n, bool))], {"r": [toe]}, rate_hz=100.0)
    assert np.array_equal(np.flatnonzero(over["r"][0]), np.arange(40, 59))
    # unloaded, the plate measures no one: no concern
    unloaded = other_foot_over(owner, [_square_plate(n, np.zeros(n, bool))], {"r": [toe]}, rate_hz=100.0)
    assert not unloaded["r"].any()


def test_a_foot_whose_marker_ball_crosses_the_plates_edge_does_not_lie_wholly_on_it():
    # a 14 mm marker (7 mm radius) 5 mm inside the plate's edge sticks 2 mm out of it; 10 mm inside it lies wholly on
    n = 4
    owner = np.full((1, n), "r")
    heel = np.tile([0.2, 0.3, 0.05], (n, 1))
    toe = np.tile([0.2, 0.3, 0.03], (n, 1))
    toe[:2, 0] = 0.4 - 0.005
    toe[2:, 0] = 0.4 - 0.010
    stance = {"r": np.array([True, False, True, True])}
    out = not_wholly_on(owner, [_square_plate(n, np.ones(n, bool))], {"r": [heel, toe]}, stance, radius_m=0.007)
    assert out["r"][0].tolist() == [True, False, False, False]  # frame 1 is swing
