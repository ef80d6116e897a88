"""The tables' anatomical angles (kinematics/conventions.py: ``anatomical_to_degrees``): degrees, and the ankle
inversion in Plug-in Gait's sign, the one Vicon Nexus writes as AnkleAngles Y."""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.kinematics.anatomical import ANATOMICAL_ANGLES, PIG_FOOT_AXES, SEGMENTS, anatomical_angles
from gaitcli.kinematics.conventions import anatomical_to_degrees
from gaitcli.kinematics.rotations import rot_y, rot_z


@pytest.mark.parametrize("ankle", ["plug_in_gait", "isb"])
@pytest.mark.parametrize("side", ["r", "l"])
def test_a_foot_turned_about_its_toe_to_heel_axis_reads_as_vicons_ankle_angles_y(side, ankle):
    """Vicon's AnkleAngles Y is the turn of its foot frame (x up, y left, z toe → heel) about z in the shank, the
    left's negated. A foot turned 6° that way (the left −6°) reads +6° in the table's ankle inversion, through
    either ankle convention; every other column is the rad angle in degrees."""
    turn = np.radians(6.0) * (1.0 if side == "r" else -1.0)
    frames = {name: np.eye(3) for name in SEGMENTS}
    frames[f"foot_{side}"] = rot_y(-np.pi / 2) @ rot_z(turn) @ PIG_FOOT_AXES.T  # segment axes x fwd, z up
    radians = anatomical_angles(frames, ankle=ankle)
    table = anatomical_to_degrees(radians)
    column = ANATOMICAL_ANGLES.index(f"ankle_{side}_inversion")
    assert table[column] == pytest.approx(6.0, abs=1e-9)
    others = [k for k in range(len(ANATOMICAL_ANGLES)) if k != column]
    np.testing.assert_allclose(table[others], np.degrees(radians[others]), atol=1e-12)
    assert np.allclose(table[others], 0.0, atol=1e-9)  # the foot turned about that axis alone


def test_many_frames_keep_their_shape():
    """(frames, 23) in, (frames, 23) out: the ankle columns of every frame turned, nothing else."""
    radians = np.random.default_rng(0).normal(size=(5, len(ANATOMICAL_ANGLES)))
    table = anatomical_to_degrees(radians)
    flip = np.ones(len(ANATOMICAL_ANGLES))
    flip[[ANATOMICAL_ANGLES.index("ankle_r_inversion"), ANATOMICAL_ANGLES.index("ankle_l_inversion")]] = -1.0
    np.testing.assert_allclose(table, np.degrees(radians) * flip, rtol=1e-15)
