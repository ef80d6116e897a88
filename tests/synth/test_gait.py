"""The designed gait cycle (``gaitcli.synth.gait``)."""

from __future__ import annotations

import pytest


def test_period_option_sets_the_cycle(walk):
    design = walk[0]
    assert design.period_s == 1.40
    assert design.time_s[-1] + design.time_s[1] == pytest.approx(1.40)
