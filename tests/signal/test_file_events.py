"""The filter stage's ``events`` parameter on the synthetic walk of tests/signal/conftest.py: the file's own
events (``auto`` where there are any, ``file``) or the detected ones (``detect``, ``auto`` without any)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from gaitcli.core.events import Events
from gaitcli.errors import InputError
from gaitcli.signal.stage import FilterConfig, filter_trial
from tests.signal.test_stage import _recording

PLATES = [("r", 1, 0.0, 0.6, 0.4), ("l", 1, 0.0, 0.6, 0.4)]


def _lab_events(walk, shift_s=0.0) -> Events:
    """The walk's true events as a lab file would give them (rounded to frames, ``shift_s`` later)."""
    parts = []
    for side in "rl":
        for kind, times in (("heel_strike", walk.heel_strikes[side]), ("toe_off", walk.toe_offs[side])):
            t = np.round(np.asarray(times) * walk.rate_hz) / walk.rate_hz + shift_s
            t = t[(t >= 0) & (t <= walk.time_s[-1])]
            parts.append(Events.from_times(t, rate_hz=walk.rate_hz, side=side, kind=kind, source="file"))
    return Events.concatenate(parts)


@pytest.fixture(scope="module")
def walk():
    from tests.signal.conftest import make_walk

    return make_walk(plates=PLATES)


def test_auto_and_file_take_the_files_events_detect_ignores_them(walk):
    lab = _lab_events(walk, shift_s=0.02)
    recording = dataclasses.replace(_recording(walk), events=lab)
    for mode in ("auto", "file"):
        result = filter_trial(recording, FilterConfig(events=mode))
        np.testing.assert_array_equal(result.events.time_s, lab.time_s)
        assert set(result.events.source) == {"file"}
        assert "EVENT group" in result.trial.history[-1]
        assert set(result.plate_owner[0]) - {""} == {"r"} and set(result.plate_owner[1]) - {""} == {"l"}
    detected = filter_trial(recording, FilterConfig(events="detect"))
    assert set(detected.events.source) <= {"plate", "kinematics"} and len(detected.events.of(source="plate")) == 4


def test_auto_without_file_events_detects_as_before(walk):
    recording = _recording(walk)
    auto, detect = (filter_trial(recording, FilterConfig(events=mode)) for mode in ("auto", "detect"))
    for name in ("frame", "time_s", "side", "kind", "source"):
        np.testing.assert_array_equal(getattr(auto.events, name), getattr(detect.events, name))


def test_file_without_events_is_an_input_error_naming_event(walk, tmp_path):
    with pytest.raises(InputError) as info:
        filter_trial(_recording(walk), FilterConfig(events="file"), path=tmp_path / "trial.c3d")
    text = str(info.value)
    assert str(tmp_path / "trial.c3d") in text and "EVENT" in text and "\n" not in text
    assert info.value.exit_code == 2
