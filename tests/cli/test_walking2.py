"""A Cleveland-style lab trial with only ``marker_set: cleveland``: ``gait filter`` then ``gait idyn`` on
OpenSim's walking2.c3d with docs/examples/walking2/subject.yaml (marker set, mass, stature, sex; no marker_map,
no static trial, no static_frames).

Measured: speed 1.667 m/s (pelvis markers 1.64 m/s), stride 1.601 m, period 0.960 s, stance
62.7 % right and 62.3 % left, double stance 25 %; calibrated on file frame 652 (auto). The right heel lands
behind plate 1 and its marker stays more than 2 cm behind the plate's edge until file frame 693: the right foot's
load is unknown (partly off the plate, warned) over the first 22 % of its stance. From there, sagittal moments
(N·m/kg, % of stance): hip −0.98 at 22 % rising to +1.40 at 84 %, knee −1.35 at 26 %, ankle −1.73 at 80 % and
−0.01 at 22 %. The left heel stands 16 cm behind plate 2 until heel off (file frames 561–594 unknown); after it
the forefoot alone is on the plate.
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
    runs = gait_many({"filter": (("filter", trial), root), "idyn": (("idyn", trial, "--export", "c3d"), root)},
                     workers=1)
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
    """(percent of the loaded stance, {joint: sagittal moment N·m/kg, flexion/dorsiflexion positive}) over the right
    foot's frames on plate 1 (joint_moments.csv's Plug-in Gait extensor/plantarflexor moments, sign turned)."""
    events, moments = walking2["events"], walking2["moments"]
    off = events.time_s[(events.side == "r") & (events.event == "toe_off") & (events.source == "plate")].to_numpy()
    assert off.size == 1
    strike = events.time_s[(events.side == "r") & (events.event == "heel_strike")].to_numpy()
    strike = strike[strike < off[0]].max()
    t = moments.time_s.to_numpy()
    stance = (t >= strike) & (t <= off[0])
    known = moments["right_foot_load_known"].to_numpy() == 1
    # the first 34 frames (136 ms, 22 % of the stance) are not: the heel lands behind plate 1 and its marker stays
    # more than 2 cm behind the plate's edge while on the ground
    assert 0.7 < known[stance].mean() < 0.85
    assert known[stance][-int(0.75 * stance.sum()):].all()
    loaded = stance & known
    pct = (t[loaded] - strike) / (off[0] - strike) * 100  # percent of the whole stance
    extensor = {"hip": "extensor", "knee": "extensor", "ankle": "plantarflexor"}
    return pct, {j: -moments[f"{j}_r_{e}_moment_per_kg"].to_numpy()[loaded] for j, e in extensor.items()}


def test_right_stance_moments_have_the_textbook_shapes(walking2):
    """From 22 % of the stance on (the loading response is off the plate): a hip extension moment giving way to
    a flexion moment before toe off, a knee extension moment at the start of mid-stance, the ankle
    plantarflexion moment rising to its push-off peak and falling to zero at toe off."""
    pct, m = right_stance(walking2)
    hip, knee, ankle = m["hip"], m["knee"], m["ankle"]
    assert hip[pct <= 30].min() < -0.2 and hip[pct >= 60].max() > 0.3
    assert pct[np.argmin(hip)] < 35 and pct[np.argmax(hip)] > 60
    assert knee[pct <= 35].min() < -0.3 and pct[np.argmin(knee)] < 40
    peak = int(np.argmin(ankle))
    assert 60 < pct[peak] < 95 and -2.2 < ankle[peak] < -0.8  # push-off plantarflexion moment
    assert ankle[pct <= 35].min() > ankle[peak] / 2 and abs(ankle[-1]) < 0.3
