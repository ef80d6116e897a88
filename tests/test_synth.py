"""The synthetic gait generator's ground reactions and options (``gaitcli.synth``)."""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.dynamics.inverse import required_external_wrench
from gaitcli.errors import InputError
from gaitcli.kinematics.forward import forward_kinematics
from gaitcli.kinematics.model import JOINTS
from gaitcli.synth import ground_reactions, simulate_trial


@pytest.fixture(scope="module")
def walk():
    trial = simulate_trial(condition="normal", seed=0, noise_mm=0.0, artefact_mm=0.0, plate_noise_N=0.0,
                           strides=1, mass_kg=55.0, stature_m=1.65, period_s=1.40)
    design, params = trial.design, trial.calibration.body
    qd, qdd, feet, clip = ground_reactions(design, params)
    return design, params, qd, qdd, feet, clip


def test_period_option_sets_the_cycle(walk):
    design = walk[0]
    assert design.period_s == 1.40
    assert design.time_s[-1] + design.time_s[1] == pytest.approx(1.40)


def test_period_outside_walking_range_is_an_input_error():
    with pytest.raises(InputError, match="period"):
        simulate_trial(period_s=0.2, strides=1)


def test_feet_share_the_whole_body_wrench_exactly(walk):
    design, params, qd, qdd, feet, clip = walk
    force, _ = required_external_wrench(design.q, qd, qdd, params)
    total = feet["r"]["force_N"] + feet["l"]["force_N"]
    assert clip == 0.0
    np.testing.assert_allclose(total, force, atol=1e-6 * np.abs(force).max())


def test_trailing_foot_cop_stays_under_the_forefoot_in_double_support(walk):
    """A foot planted on the floor keeps its COP on the floor: in world coordinates the trailing foot's
    COP moves by millimetres, not by the walking speed × double-support time, and stays within the foot."""
    design, params, _, _, feet, _ = walk
    n = design.time_s.size
    trend = design.speed_m_s * design.time_s
    ankles = forward_kinematics(design.q, params).joint_centre_m
    both = design.stance["r"] & design.stance["l"]
    stature = 1.65
    for side in "rl":
        world_cop = feet[side]["cop_m"][:, 0] + trend
        ankle_x = ankles[:, JOINTS.index(f"ankle_{side}"), 0]
        stance = design.stance[side]
        lever = (world_cop - ankle_x)[stance]
        # Winter's foot: toes 0.092·H ahead of the ankle. Measured 0.098·H just before toe-off (the heel
        # is up, the COP at the toe tip); before the fix of the double-support split it ran to 0.146·H.
        assert lever.max() < 0.11 * stature
        assert lever.min() > -0.06 * stature  # behind the ankle by less than the heel
        # the double-support run where this foot is the trailing one: its last samples before toe-off
        off = int(np.flatnonzero(stance & ~np.roll(stance, -1))[0])
        run = [(off - k) % n for k in range(n) if both[(off - k) % n]]
        run = run[: int(np.argmax(np.diff(run) != -1)) + 1] if len(run) > 1 and np.any(np.diff(run) != -1) else run
        drift = np.ptp(world_cop[run])
        assert drift < 0.02, (side, drift, design.speed_m_s * len(run) * design.period_s / n)
