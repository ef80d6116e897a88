"""The starts of a prediction (gaitcli/predict/guess.py): the shipped walk on other nodes, speeds and models."""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.predict.guess import SHIPPED_WALK, SHIPPED_WALK_NODES, shipped_walk
from gaitcli.predict.layout import DesignLayout, box_bounds, half_cycle_intervals
from gaitcli.predict.settings import PredictSettings
from gaitcli.predict.splines import cubic, evaluate_fractions, quartic


def test_the_shipped_walk_on_its_own_nodes_and_speed_is_the_file():
    np.testing.assert_allclose(shipped_walk(SHIPPED_WALK_NODES, symmetric=True), np.loadtxt(SHIPPED_WALK),
                               rtol=1e-14, atol=0)


@pytest.mark.parametrize(("nodes", "degrees", "stretch", "trunk"), [(14, 4.0, 0.25, 0.003), (20, 1.0, 0.05, 0.001)])
def test_on_other_nodes_the_walk_keeps_its_curves_and_walks_at_the_speed(nodes, degrees, stretch, trunk):
    # the fitted splines follow the shipped ones, closer on more nodes (the ankle's push-off and the vasti's
    # loading-response burst are the hardest parts for few: 14 nodes miss them by 2.2° and a stretch of 0.20),
    # and the durations make ΣT = ΔS/v (5.43) at the settings' speed; inside the box
    settings = PredictSettings(speed_m_s=1.3)
    x = shipped_walk(nodes, settings, symmetric=True)
    layout, shipped = DesignLayout.build(nodes, symmetric=True), DesignLayout.build(SHIPPED_WALK_NODES, symmetric=True)
    new, old = layout.unpack(x), shipped.unpack(np.loadtxt(SHIPPED_WALK))
    s = np.linspace(0, 1, 200, endpoint=False)
    for block, make, tolerance in (("right_leg", quartic, np.radians(degrees)), ("right_stretch", cubic, stretch)):
        np.testing.assert_allclose(evaluate_fractions(make(nodes), new[block], 1.0, s),
                                   evaluate_fractions(make(SHIPPED_WALK_NODES), old[block], 1.0, s), atol=tolerance)
    halves = [quartic(half_cycle_intervals(n - 1) + 1) for n in (nodes, SHIPPED_WALK_NODES)]
    np.testing.assert_allclose(evaluate_fractions(halves[0], new["trunk"], 1.0, s),
                               evaluate_fractions(halves[1], old["trunk"], 1.0, s), atol=trunk)
    assert layout.phase_durations(x).sum() == pytest.approx(sum(layout.step_lengths(x)) / 1.3, rel=1e-12)
    low, high = box_bounds(layout)
    assert np.all((low <= x) & (x <= high))


def test_a_fixed_step_and_the_full_model():
    x = shipped_walk(18, PredictSettings(step_m=0.7, speed_m_s=1.4), symmetric=False)
    layout = DesignLayout.build(18, symmetric=False)
    assert layout.step_lengths(x) == (0.7, 0.7) and x.size == layout.size
    assert layout.phase_durations(x).sum() == pytest.approx(1.0, rel=1e-12)
