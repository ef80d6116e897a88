"""The ground reactions of the designed gait and their split between the feet (``gaitcli.synth.ground``)."""

from __future__ import annotations

import numpy as np

from gaitcli.dynamics.inverse import required_external_wrench
from gaitcli.kinematics.forward import forward_kinematics
from gaitcli.kinematics.model import JOINTS


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
