"""The body-mass estimate from the plates over stances the trial file's events time (``filter.events`` auto/file):
a loaded run of the foot that spans the stance within 50 ms of its events counts, as a plate-timed stance does."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from gaitcli.dynamics.stage import estimate_mass_kg, file_stances_on_plates
from gaitcli.signal.stage import FilterConfig, filter_trial
from tests.signal.conftest import make_walk
from tests.signal.test_file_events import PLATES, _lab_events
from tests.signal.test_stage import _recording


@pytest.fixture(scope="module")
def walk():
    return make_walk(plates=PLATES)


def test_the_mass_comes_from_the_plate_stances_the_files_events_time(walk):
    """Each plate holds one whole stance: 2 ∫Fz dt / (g T) per stance, the same with the file's events (20 ms
    late) as with the plates' own (70.20 and 70.17 kg; the walk's 700 N are 71.36 kg, the 20 N threshold and
    the 6 Hz filter take 1.6 % of the impulse)."""
    lab = _lab_events(walk, shift_s=0.02)
    from_file = filter_trial(dataclasses.replace(_recording(walk), events=lab), FilterConfig()).trial
    detected = filter_trial(_recording(walk), FilterConfig(events="detect")).trial
    for side in "rl":
        stances = file_stances_on_plates(from_file, side)
        assert len(stances) == 1
        strike = lab.times(side, "heel_strike")
        assert np.abs(strike - stances[0][0]).min() <= 0.05
    mass, reference = estimate_mass_kg(from_file), estimate_mass_kg(detected)
    assert mass == pytest.approx(reference, rel=2e-3)
    assert mass == pytest.approx(walk.body_weight_N / 9.81, rel=0.03)
