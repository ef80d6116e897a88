"""Marker set of Table A.6, body assignment and lab-label mapping."""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.errors import InputError
from gaitcli.kinematics.markerset import (LANDMARKS, MARKERS, SEGMENT_MARKERS, apply_marker_map, body_of_marker,
                                          landmarks_to_markers, required_landmarks, standing_template,
                                          tracking_landmarks)
from gaitcli.kinematics.model import BODIES
from gaitcli.core.recording import Markers


def test_table_a6_has_28_markers_each_on_one_body():
    assert len(MARKERS) == 28 == len(set(MARKERS))
    assert {"ASISr", "PSISl", "GTr", "MRFr", "LEFr", "MEFr", "TTr", "LMr", "MMr", "CAr", "VMr", "FMr", "ACr",
            "C7", "ST"} <= set(MARKERS)
    owners = [body_of_marker(m) for m in MARKERS]
    assert sorted(set(owners)) == sorted(BODIES)
    assert all(len(SEGMENT_MARKERS[b]) >= 3 for b in BODIES)
    assert body_of_marker("LEFl") == "thigh_l" and body_of_marker("LMr") == "shank_r"
    assert SEGMENT_MARKERS["hat"] == ("C7", "ST", "ACr", "ACl")


def test_virtual_joint_centres_join_both_adjacent_bodies():
    assert "KJCr" in tracking_landmarks("thigh_r") and "KJCr" in tracking_landmarks("shank_r")
    assert "HJCl" in tracking_landmarks("pelvis") and "AJCl" in tracking_landmarks("foot_l")
    assert "KJCr" not in tracking_landmarks("thigh_l")


def test_required_landmarks_drop_markers_replaced_by_virtual_centres():
    full = required_landmarks()
    assert {"ASISr", "LEFr", "MEFl", "LMr", "MMl", "CAr", "VMl", "FMr"} <= set(full)
    assert "GTr" not in full and "C7" not in full
    reduced = required_landmarks(virtual_joint_centres=("KJCr", "AJCl"))
    assert "LEFr" not in reduced and "MEFr" not in reduced and "LMl" not in reduced
    assert "LEFl" in reduced and "LMr" in reduced


def _lab_markers():
    pos = np.arange(2 * 3 * 3, dtype=float).reshape(2, 3, 3)
    return Markers(("RASI", "LASI", "EXTRA"), pos, 100.0)


def test_apply_marker_map_renames_and_keeps_other_labels():
    out = apply_marker_map(_lab_markers(), {"RASI": "ASISr", "LASI": "ASISl"})
    assert out.labels == ("ASISr", "ASISl", "EXTRA")
    np.testing.assert_array_equal(out.get("ASISl"), _lab_markers().get("LASI"))


def test_apply_marker_map_lists_every_missing_label():
    with pytest.raises(InputError) as err:
        apply_marker_map(_lab_markers(), {"RASI": "ASISr", "RPSI": "PSISr", "LPSI": "PSISl"}, source="trial.c3d")
    message = str(err.value)
    assert "trial.c3d" in message and "RPSI" in message and "LPSI" in message and "RASI, LASI" in message


def test_apply_marker_map_rejects_unknown_landmarks_and_duplicates():
    with pytest.raises(InputError,
                       match=r"marker_map\.RASI: got 'ASIS_r' \(expected one of .*; did you mean 'ASISr'\?\)"):
        apply_marker_map(_lab_markers(), {"RASI": "ASIS_r"})
    with pytest.raises(InputError, match="more than once"):
        apply_marker_map(_lab_markers(), {"RASI": "ASISr", "LASI": "ASISr"})


def test_standing_template_is_complete_and_symmetric():
    t = standing_template(1.8, with_virtual_joint_centres=True)
    assert set(t) == set(LANDMARKS)
    mirror = np.array([1.0, -1.0, 1.0])
    for name in MARKERS[:-2]:
        if name.endswith("r"):
            np.testing.assert_allclose(t[name] * mirror, t[name[:-1] + "l"])
    m = landmarks_to_markers(t)
    assert m.positions_m.shape == (1, len(LANDMARKS), 3)
