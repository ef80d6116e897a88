"""Marker set of Table A.6, body assignment and lab-label mapping."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from gaitcli.core.recording import Markers
from gaitcli.errors import InputError
from gaitcli.kinematics.calibration import calibrate
from gaitcli.kinematics.markerset import (
    LANDMARKS,
    MARKERS,
    SEGMENT_MARKERS,
    VIRTUAL_JOINT_CENTRES,
    apply_marker_map,
    body_of_marker,
    landmarks_to_markers,
    marker_set,
    marker_set_names,
    required_landmarks,
    standing_template,
    tracking_landmarks,
)
from gaitcli.kinematics.model import BODIES


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
    assert set(t) == set(MARKERS + VIRTUAL_JOINT_CENTRES)  # Table A.6's, not the extra MT2
    mirror = np.array([1.0, -1.0, 1.0])
    for name in MARKERS[:-2]:
        if name.endswith("r"):
            np.testing.assert_allclose(t[name] * mirror, t[name[:-1] + "l"])
    m = landmarks_to_markers(t)
    assert m.positions_m.shape == (1, len(MARKERS + VIRTUAL_JOINT_CENTRES), 3)


# ------------------------------------------------------------------ presets (marker_set: in subject.yaml)

def test_every_bundled_preset_reads_and_names_only_model_landmarks_and_bodies():
    assert set(marker_set_names()) == {"cast", "cleveland", "dissertation", "plug_in_gait"}
    for name in marker_set_names():
        preset = marker_set(name)
        assert preset.name == name
        assert set(preset.landmarks) <= set(LANDMARKS) and set(preset.tracking) <= set(BODIES)
        tracking = [lab for labels in preset.tracking.values() for lab in labels]
        assert len(tracking) == len(set(tracking)), name  # a tracking marker is fixed to one body
        anatomical = {lab for labels in preset.landmarks.values() for lab in labels}
        assert not anatomical & set(tracking), name
    assert all(marker_set("dissertation").landmarks[n] == (n,) for n in LANDMARKS)


def _file(labels) -> Markers:
    pos = np.arange(len(labels) * 3, dtype=float).reshape(1, len(labels), 3)
    return Markers(tuple(labels), pos, 100.0)


def test_a_preset_uses_the_first_label_a_file_has_and_copies_a_shared_one():
    lab = _file(["SACR", "RASI", "LASI", "R.Knee", "RKNE", "RTH1", "junk"])
    out = marker_set("cleveland").apply(lab)
    assert out.labels[:5] == ("ASISr", "ASISl", "PSISr", "PSISl", "LEFr")
    np.testing.assert_array_equal(out.get("PSISr"), lab.get("SACR"))  # one sacral marker for both PSIS
    np.testing.assert_array_equal(out.get("PSISl"), lab.get("SACR"))
    np.testing.assert_array_equal(out.get("LEFr"), lab.get("RKNE"))  # RKNE comes before R.Knee in the preset
    assert {"R.Knee", "RTH1", "junk"} <= set(out.labels) and "SACR" not in out.labels


def test_marker_map_overrides_a_preset_and_adds_tracking_markers():
    merged = marker_set("cleveland", {"RKNX": "LEFr", "RTH1": "shank_r", "RWAND": "thigh_r"})
    assert merged.landmarks["LEFr"] == ("RKNX",)
    assert merged.tracking["thigh_r"][-1] == "RWAND" and "RTH1" not in merged.tracking["thigh_r"]
    assert "RTH1" in merged.tracking["shank_r"]
    assert merged.name == "cleveland with marker_map"
    with pytest.raises(InputError, match=r"subject\.yaml: marker_map\.RTHI: got 'thigh' \(expected one of"):
        marker_set("cleveland", {"RTHI": "thigh"}, source="subject.yaml")
    with pytest.raises(InputError, match=r"subject\.yaml: marker_set: got 'vicon' \(expected one of cast, cleveland"):
        marker_set("vicon", source="subject.yaml")


def test_a_missing_preset_marker_is_one_line_naming_the_preset_the_label_and_its_purpose():
    t = standing_template(1.78)
    cleveland = {"MEFr": "RMFC", "ASISr": "RASI"}
    labels = {lab: t[landmark] for landmark, lab in cleveland.items()}
    labels.update({k: v for k, v in t.items() if k not in cleveland})
    static = marker_set("cleveland").apply(landmarks_to_markers(labels))
    static = Markers(tuple(n for n in static.labels if n != "MEFr"),
                     static.positions_m[:, [i for i, n in enumerate(static.labels) if n != "MEFr"]], 100.0)
    with pytest.raises(InputError) as err:
        calibrate(static, mass_kg=75.0, stature_m=1.78, marker_set=marker_set("cleveland"), source="static.c3d")
    assert str(err.value) == ("static.c3d: RMFC: marker missing from the static trial: RMFC or RKNM or R.Knee.Medial "
                              "(marker_set cleveland: the right medial femoral epicondyle, MEFr; needed for the knee "
                              "joint centre)")
    assert "\n" not in str(err.value)


@pytest.mark.shared
def test_the_cast_preset_maps_qualisys_like_the_worked_example(shared_c3d_dir):
    """docs/examples/qualisys maps every landmark by hand; the preset finds the same labels, and the wands."""
    import yaml

    from gaitcli.io.c3d import read_c3d

    example = yaml.safe_load((Path(__file__).resolve().parents[2] / "docs" / "examples" / "qualisys"
                              / "subject.yaml").read_text())["marker_map"]
    labels = read_c3d(shared_c3d_dir / "Qualisys.c3d").markers.labels
    cast = marker_set("cast")
    assert {landmark: cast.label_of(landmark, labels) for landmark in example.values()} == \
        {landmark: lab for lab, landmark in example.items()}
    assert cast.tracking["thigh_r"] == ("R_WAND1",) and "R_WAND2" in cast.tracking["shank_r"]


@pytest.mark.shared
def test_the_cleveland_preset_finds_walking2s_landmarks_clusters_and_joint_centres(shared_c3d_dir):
    from gaitcli.io.c3d import read_c3d

    markers = read_c3d(shared_c3d_dir / "walking2.c3d").markers
    out = marker_set("cleveland").apply(markers)
    needed = set(required_landmarks()) | {"C7", "ST"} | set(VIRTUAL_JOINT_CENTRES)
    assert needed <= set(out.labels)
    for side in "rl":
        clusters = marker_set("cleveland").tracking
        assert {f"{side.upper()}TH{k}" for k in (1, 2, 3)} <= set(clusters[f"thigh_{side}"]) & set(out.labels)
        assert {f"{side.upper()}TB{k}" for k in (1, 2, 3)} <= set(clusters[f"shank_{side}"]) & set(out.labels)
        # RMT2/LMT2 is the fifth metatarsal head: lateral of RMT1/LMT1 (model y: left), behind it
        with np.errstate(invalid="ignore"):
            lateral = (out.get(f"VM{side}")[:, 1] - out.get(f"FM{side}")[:, 1]) * (1 if side == "l" else -1)
            behind = out.get(f"FM{side}")[:, 0] - out.get(f"VM{side}")[:, 0]
        assert 0.06 < np.nanmedian(lateral) < 0.11 and 0.0 < np.nanmedian(behind) < 0.04


def test_a_new_preset_is_one_yaml_file(tmp_path, monkeypatch):
    """A lab's marker set added as one file beside the bundled ones is a ``marker_set:`` choice of subject.yaml
    with its labels, and nothing else changes."""
    import shutil

    from gaitcli.kinematics import markerset
    from gaitcli.kinematics.subject import subject_from_dict

    folder = tmp_path / "marker_sets"
    shutil.copytree(markerset.MARKER_SETS_DIR, folder)
    text = (markerset.MARKER_SETS_DIR / "dissertation.yaml").read_text()
    text = text.replace("name: dissertation", "name: our_lab").replace("ASISr: [ASISr]", "ASISr: [R_ASIS_OURS]")
    (folder / "our_lab.yaml").write_text(text)
    monkeypatch.setattr(markerset, "MARKER_SETS_DIR", folder)
    assert "our_lab" in marker_set_names()
    subject = subject_from_dict({"mass_kg": 70.0, "stature_m": 1.7, "sex": "male", "marker_set": "our_lab"})
    ours = subject.markers
    assert ours.name == "our_lab" and ours.landmarks["ASISr"][0] == "R_ASIS_OURS"
