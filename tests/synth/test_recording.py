"""The recorded synthetic trial and its options (``gaitcli.synth.recording``)."""

from __future__ import annotations

import pytest

from gaitcli.errors import InputError
from gaitcli.synth import simulate_trial


def test_period_outside_walking_range_is_an_input_error():
    with pytest.raises(InputError, match="period"):
        simulate_trial(period_s=0.2, strides=1)
