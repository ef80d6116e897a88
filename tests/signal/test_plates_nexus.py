"""A Plug-in Gait session's plates as Vicon Nexus gives them (``filter`` auto: unfiltered, each frame the mean of the
analog samples centred on it): ``../shared/data/pig``'s own ``RGroundReactionForce``/``LGroundReactionForce``
(Nexus's outputs, N/kg, lab axes) against gaitcli's per-foot loads."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from gaitcli.io.c3d import read_c3d
from gaitcli.kinematics.markerset import marker_set
from gaitcli.signal.stage import FilterConfig, filter_trial

pytestmark = pytest.mark.shared
MASS_KG = 85.0  # Test.vsk


@pytest.fixture(scope="module")
def session(shared_pig_dir):
    """(gaitcli's per-foot loads in N/kg for a filter config, Nexus's per foot in model axes)."""
    ezc3d = pytest.importorskip("ezc3d")
    path = shared_pig_dir / "Movement_trial.c3d"
    recording = read_c3d(path)
    recording.markers = marker_set("plug_in_gait").apply(recording.markers)

    def feet(cfg: FilterConfig) -> dict[str, np.ndarray]:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = filter_trial(recording, cfg, marker_set="plug_in_gait")
        return {side: load.force_N / MASS_KG for side, load in result.plate_loads_per_foot.items()}

    c3d = ezc3d.c3d(str(path))
    labels = list(c3d["parameters"]["POINT"]["LABELS"]["value"])
    points = c3d["data"]["points"][:3].transpose(2, 1, 0)
    nexus = {side: points[:, labels.index(f"{side.upper()}GroundReactionForce")] @ np.asarray(recording.lab_to_model).T
             for side in "rl"}
    return feet, nexus


def _agreeing(ours: dict, nexus: dict) -> dict[str, tuple[int, int]]:
    """Per foot: (frames within 1e-5 N/kg of Nexus's, frames Nexus loads that foot: |vertical| > 0.5 N/kg)."""
    out = {}
    for side in "rl":
        loaded = np.abs(nexus[side][:, 2]) > 0.5
        error = np.abs(ours[side][loaded] - nexus[side][loaded]).max(axis=1)
        out[side] = (int(np.sum(error < 1e-5)), int(loaded.sum()))
    return out


def test_the_feet_carry_nexuss_ground_reactions(session):
    """Where Nexus gives a foot a load, gaitcli's auto settings give it the same to 1e-5 N/kg (Nexus stores float32):
    the right foot in all its 83 frames, the left in 82 of its 92. The other ten: the first two frames of its
    contact with plate 1 (926–927, which Nexus already gives the foot) and the last eight, where the trial ends
    during the stance and gaitcli gives the foot no load."""
    feet, nexus = session
    agree = _agreeing(feet(FilterConfig()), nexus)
    assert agree["r"] == (83, 83) and agree["l"] == (82, 92), agree


def test_sampled_at_the_frames_the_plates_are_not_nexuss(session):
    """Unfiltered but sampled at each frame (``plate_frames: sample``) the right foot agrees in few frames: the
    mean over the frame's samples is what Nexus does."""
    feet, nexus = session
    agree = _agreeing(feet(FilterConfig(plate_frames="sample")), nexus)
    assert agree["r"][0] < 10, agree
