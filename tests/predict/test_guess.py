"""The starts of a prediction (gaitcli/predict/guess.py): the shipped walk on other nodes, speeds and models."""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.predict.guess import SHIPPED_WALK_NODES, SPEED_WALKS, nearest_walk, shipped_walk, walk_speed_m_s
from gaitcli.predict.layout import DesignLayout, box_bounds, half_cycle_intervals
from gaitcli.predict.settings import PredictSettings
from gaitcli.predict.splines import cubic, evaluate_fractions, quartic


def test_each_shipped_walk_on_its_own_nodes_and_speed_is_the_file():
    # one walk per speed group and the default speed, each the one nearest its own speed
    assert len(SPEED_WALKS) == 4
    for path in SPEED_WALKS:
        speed = walk_speed_m_s(path)
        assert nearest_walk(speed) == path and nearest_walk(speed + 0.01) == path
        np.testing.assert_allclose(shipped_walk(SHIPPED_WALK_NODES, PredictSettings(speed_m_s=speed), symmetric=True),
                                   np.loadtxt(path), rtol=1e-13, atol=1e-15)
    assert nearest_walk(PredictSettings.speed_m_s).name == "walk_default_nn18.csv"


def test_a_start_outside_the_stride_bounds_is_brought_inside_and_retimed():
    settings = PredictSettings(speed_m_s=1.3272, step_range_m=(0.71, 0.8))  # the walk's step: 0.697 m
    x = shipped_walk(SHIPPED_WALK_NODES, settings, symmetric=True)
    layout = DesignLayout.build(SHIPPED_WALK_NODES, symmetric=True)
    assert layout.step_lengths(x) == (0.71, 0.71)
    assert layout.phase_durations(x).sum() == pytest.approx(1.42 / 1.3272, rel=1e-12)


@pytest.mark.parametrize(("nodes", "degrees", "stretch", "trunk"), [(14, 4.0, 0.25, 0.003), (20, 1.0, 0.05, 0.001)])
def test_on_other_nodes_the_walk_keeps_its_curves_and_walks_at_the_speed(nodes, degrees, stretch, trunk):
    # the fitted splines follow the shipped ones, closer on more nodes (the ankle's push-off and the vasti's
    # loading-response burst are the hardest parts for few: 14 nodes miss them by 2.2° and a stretch of 0.20),
    # and the durations make ΣT = ΔS/v (5.43) at the settings' speed; inside the box
    settings = PredictSettings(speed_m_s=1.3)
    x = shipped_walk(nodes, settings, symmetric=True)
    layout, shipped = DesignLayout.build(nodes, symmetric=True), DesignLayout.build(SHIPPED_WALK_NODES, symmetric=True)
    new, old = layout.unpack(x), shipped.unpack(np.loadtxt(nearest_walk(1.3)))
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
