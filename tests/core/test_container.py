"""Which frames a foot's load is known in (``core/container.load_known_frames``)."""

from __future__ import annotations

import numpy as np

from gaitcli.core.container import EVENT_SLACK_S, load_known_frames
from gaitcli.core.events import Events

RATE_HZ = 200.0


def _events(strike_s: float, off_s: float) -> Events:
    return Events(frame=np.array([round(strike_s * RATE_HZ), round(off_s * RATE_HZ)]),
                  time_s=np.array([strike_s, off_s]), side=np.array(["r", "r"]),
                  kind=np.array(["heel_strike", "toe_off"]), source=np.array(["file", "file"]))


def test_a_stance_that_starts_a_frame_or_two_before_its_plate_is_measured():
    """The lab's heel strike 8 ms before the plate's onset (Qualisys.c3d's right foot): known throughout; the
    plate's load ending 10 ms before the toe off: known too."""
    t = np.arange(0, 1.0, 1 / RATE_HZ)
    loaded = (t >= 0.54) & (t <= 0.69)
    known = load_known_frames(_events(0.53, 0.70), t, loaded, "r")
    assert known.all()


def test_a_stance_whose_start_is_off_the_plate_longer_than_the_slack_is_not():
    t = np.arange(0, 1.0, 1 / RATE_HZ)
    onset = 0.53 + EVENT_SLACK_S + 0.02
    loaded = (t >= onset) & (t <= 0.70)
    known = load_known_frames(_events(0.53, 0.70), t, loaded, "r")
    stance = (t >= 0.53) & (t <= 0.70)
    assert not known[stance & (t < onset)].any()
    assert known[~stance].all() and known[loaded].all()


def test_a_stance_with_no_plate_stays_unknown():
    t = np.arange(0, 1.0, 1 / RATE_HZ)
    known = load_known_frames(_events(0.53, 0.70), t, np.zeros(t.size, bool), "r")
    assert np.array_equal(known, ~((t >= 0.53) & (t <= 0.70)))
