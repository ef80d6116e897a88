"""A Cleveland-style lab trial with only ``marker_set: cleveland``: ``gait filter`` then ``gait idyn`` on
OpenSim's walking2.c3d with docs/examples/walking2/subject.yaml (marker set, mass, stature, sex; no marker_map,
no static trial, no static_frames).

Measured (2026-12-02): speed 1.667 m/s (pelvis markers 1.64 m/s), stride 1.601 m, period 0.960 s, stance
62.7 % right and 62.3 % left, double stance 25 %; calibrated on file frame 652 (auto). Right stance on plate 1
(loaded from 2.674 s, 38 ms after the kinematic heel strike: the heel lands behind the plate), sagittal moments
in N·m/kg at 0, 10, …, 100 % of the loaded part:

| joint | values |
| --- | --- |
| hip | −1.16 −0.37 −0.59 0.34 0.26 0.21 0.60 0.92 1.42 1.19 0.23 |
| knee | 0.33 −0.69 −1.46 −0.94 −0.19 0.06 0.15 0.30 0.01 −0.32 −0.05 |
| ankle | 0.05 0.17 −0.15 −0.60 −0.65 −0.65 −0.95 −1.56 −1.86 −1.13 −0.14 |

The left foot stands with its heel 16 cm behind plate 2 through its stance; its moments are not tested here.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from .conftest import Result, build_once, gait_many
from .test_qualisys import lab_markers

EXAMPLE = Path(__file__).resolve().parents[2] / "docs" / "examples" / "walking2"
PELVIS = ("RASI", "LASI", "RPSI", "LPSI")


def _build(shared_c3d_dir: Path, root: Path) -> dict:
    trial = root / "trial"
    trial.mkdir()
    shutil.copy(shared_c3d_dir / "walking2.c3d", trial / "trial.c3d")
    shutil.copy(EXAMPLE / "subject.yaml", trial / "subject.yaml")
    runs = gait_many({"filter": (("filter", trial), root), "idyn": (("idyn", trial), root)}, workers=1)
    return {"results": [runs["filter"].to_json(), runs["idyn"].to_json()]}


@pytest.fixture(scope="module")
def walking2(shared_c3d_dir, tmp_path_factory):
    root, record = build_once(tmp_path_factory, "cli_walking2", lambda root: _build(shared_c3d_dir, root))
    results = [Result.from_json(r) for r in record["results"]]
    for r in results:
        assert r.returncode == 0, r.describe()
        assert "Traceback" not in r.stderr
    out = root / "trial" / "gait_out"
    return {"trial": root / "trial", "idyn": results[1],
            "summary": json.loads((out / "idyn" / "summary.json").read_text()),
            "events": pd.read_csv(out / "filter" / "events.csv"),
            "moments": pd.read_csv(out / "idyn" / "joint_moments.csv")}


def test_the_subject_file_names_a_marker_set_and_no_labels():
    subject = yaml.safe_load((EXAMPLE / "subject.yaml").read_text())
    assert set(subject) == {"marker_set", "mass_kg", "stature_m", "sex"}
    assert subject["marker_set"] == "cleveland"


def test_every_segment_is_tracked_by_the_presets_markers(walking2):
    summary = walking2["summary"]
    assert summary["marker_set"] == "cleveland" and summary["hip_joint_centre"] == "bell"
    assert summary["locked_segments"] == []
    errors = summary["segment_rms_marker_error_mm"]
    assert all(value is not None and 0.1 < value < 15.0 for value in errors.values()), errors
    # no static trial: calibrated on one frame of the walk, said on stderr and in summary.json
    assert summary["static"].startswith("auto: no quiet standing") and summary["static_frames"][0] == \
        summary["static_frames"][1]
    assert f"calibrated on file frame {summary['static_frames'][0]} of the trial" in walking2["idyn"].stderr


def test_gait_features_are_plausible_and_match_the_pelvis(walking2, shared_c3d_dir):
    summary = walking2["summary"]
    time_s, points, labels, _ = lab_markers(shared_c3d_dir / "walking2.c3d")
    pelvis_x = points[:, [labels.index(p) for p in PELVIS], 0].mean(axis=1)  # the walk is along lab +x
    seen = np.isfinite(pelvis_x)
    assert 0.8 < summary["speed_m_s"] < 2.0
    assert 1.0 < summary["stride_length_m"] < 1.9
    assert 0.8 < summary["period_s"] < 1.4
    for key in ("stance_right_pct", "stance_left_pct"):
        assert 52.0 < summary[key] < 68.0, key
    pelvis_speed = np.polyfit(time_s[seen], pelvis_x[seen], 1)[0]
    assert summary["speed_m_s"] == pytest.approx(pelvis_speed, rel=0.03)
    events = walking2["events"]
    displacement = []
    for side in "rl":
        strikes = np.sort(events.time_s[(events.side == side) & (events.event == "heel_strike")].to_numpy())
        displacement += list(np.diff(np.interp(strikes, time_s[seen], pelvis_x[seen])))
    assert len(displacement) == summary["strides"] == 2
    assert summary["stride_length_m"] == pytest.approx(np.mean(displacement), rel=0.03)


def right_stance(walking2):
    """(percent of the loaded stance, {joint: sagittal moment N·m/kg}) over the right foot's frames on plate 1."""
    events, moments = walking2["events"], walking2["moments"]
    off = events.time_s[(events.side == "r") & (events.event == "toe_off") & (events.source == "plate")].to_numpy()
    assert off.size == 1
    strike = events.time_s[(events.side == "r") & (events.event == "heel_strike")].to_numpy()
    strike = strike[strike < off[0]].max()
    t = moments.time_s.to_numpy()
    stance = (t >= strike) & (t <= off[0])
    known = moments["right_foot_load_known"].to_numpy() == 1
    assert known[stance].mean() > 0.9  # the first 38 ms (heel behind the plate) are not
    loaded = stance & known
    pct = (t[loaded] - t[loaded][0]) / (t[loaded][-1] - t[loaded][0]) * 100
    return pct, {j: moments[f"{j}_r_flexion_moment_per_kg"].to_numpy()[loaded] for j in ("hip", "knee", "ankle")}


def test_right_stance_moments_have_the_textbook_shapes(walking2):
    pct, m = right_stance(walking2)
    hip, knee, ankle = m["hip"], m["knee"], m["ankle"]
    assert hip[pct <= 25].min() < -0.3 and hip[pct >= 60].max() > 0.3  # extension at loading, flexion late
    assert pct[np.argmin(hip)] < 30 and pct[np.argmax(hip)] > 60
    assert knee[pct <= 5].max() > 0.0 and 10 < pct[np.argmin(knee)] < 40  # brief flexion, then extension
    assert knee.min() < -0.3
    peak = int(np.argmin(ankle))
    assert 50 < pct[peak] < 95 and -2.2 < ankle[peak] < -0.8  # push-off plantarflexion moment
    assert np.all(ankle[pct <= 15] > -0.5) and abs(ankle[-1]) < 0.3
