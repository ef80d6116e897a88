"""A real walking trial end to end: ``gait filter`` then ``gait idyn`` on Qualisys.c3d with the subject
file of docs/examples/qualisys/ (marker map, static frame, mass from the plates).

The trial (../shared/data/c3d/Qualisys.c3d, 200 Hz, two plates): one left stance on plate 1 and
one right stance on plate 2. Measured (subject.yaml as shipped): mass 63.95 kg (auto); speed
1.445 m/s, stride 1.421 m, period 0.983 s, stance r 59.0 %, l 55.1 %, double stance 14.1 %;
residual RMS 82 N and 36 N·m over 175 frames. Sagittal moments over the plate stances (N·m/kg,
% of stance):

| side | hip | knee | ankle |
| --- | --- | --- | --- |
| left | −1.01 @ 11 %, +0.98 @ 81 % | +0.35 @ 0 %, −0.67 @ 22 % | −1.31 @ 79 % |
| right | −0.59 @ 11 %, +1.40 @ 82 % | +0.19 @ 0 %, −1.08 @ 18 % | +0.11 @ 8 %, −1.06 @ 77 % |

The runs here detect the events (``filter.events: detect``; by default gaitcli takes the file's own,
see test_file_events_cli.py). The lab's own events (the file's EVENT group) give periods of 0.945 s
(left) and 0.98 s (right) and stances of 59 % (left) and 61 % (right). gaitcli's kinematic heel strikes are late
here: the left foot loads from about 1.01 s (the vertical residual rises from there; the lab says 1.015 s),
its event is at 1.050 s (right: 1.528 s, the lab 1.51 s), which lengthens the period by 2 % and
leaves 8 loaded frames flagged as all contacts measured (without them the residual RMS is 71 N);
and the 20 N plate threshold ends the left stance 23 ms before the lab's toe off. Hence the
tolerances against the lab's events below: period 4 %, stance 5 points.

Signs: the table above keeps each moment positive in the sense of its angle (hip and knee flexion,
ankle dorsiflexion); joint_moments.csv has Plug-in Gait's (hip and knee extensor, ankle
plantarflexor positive), which ``stance_curve`` turns into the table's by one sign.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import ezc3d
import numpy as np
import pandas as pd
import pytest
import yaml

from .conftest import Result, build_once, gait_many

EXAMPLE = Path(__file__).resolve().parents[2] / "docs" / "examples" / "qualisys"
PELVIS = ("R_IAS", "L_IAS", "R_IPS", "L_IPS")
SIDES = {"l": "left", "r": "right"}


def _build(shared_c3d_dir: Path, root: Path) -> dict:
    """The trial folder (a copy of the C3D next to the example subject.yaml), then filter and idyn."""
    trial = root / "trial"
    trial.mkdir()
    shutil.copy(shared_c3d_dir / "Qualisys.c3d", trial / "trial.c3d")
    shutil.copy(EXAMPLE / "subject.yaml", trial / "subject.yaml")
    detect = root / "detect.yaml"  # gaitcli's own events, compared below with the lab's (the file's EVENT group)
    detect.write_text("filter:\n  events: detect\n")
    # no figures: nothing here looks at them, and test_qualisys_doc.py's run draws every stage's of this trial
    runs = gait_many({"filter": (("filter", trial, "--pipeline", detect, "--no-plots"), root),
                      "idyn": (("idyn", trial, "--pipeline", detect, "--export", "c3d", "--no-plots"), root),
                      "eid": (("muscles", trial, "--method", "eid", "--side", "r", "--pipeline", detect, "--no-plots"),
                              root)}, workers=1)
    return {"results": [runs["filter"].to_json(), runs["idyn"].to_json()], "eid": runs["eid"].to_json()}


@pytest.fixture(scope="module")
def qualisys(shared_c3d_dir, tmp_path_factory):
    root, record = build_once(tmp_path_factory, "cli_qualisys", lambda root: _build(shared_c3d_dir, root))
    for r in map(Result.from_json, record["results"]):
        assert r.returncode == 0, r.describe()
        assert "Traceback" not in r.stderr
    out = root / "trial" / "gait_out"
    return {
        "trial": root / "trial",
        "summary": json.loads((out / "idyn" / "summary.json").read_text()),
        "events": pd.read_csv(out / "filter" / "events.csv"),
        "moments": pd.read_csv(out / "idyn" / "joint_moments.csv"),
        "eid": Result.from_json(record["eid"]),
    }


def lab_markers(path: Path):
    """Time (s from the first frame) and the raw marker array (frames, markers, 3) in m, with labels."""
    c = ezc3d.c3d(str(path))
    labels = list(c["parameters"]["POINT"]["LABELS"]["value"])
    rate = float(c["parameters"]["POINT"]["RATE"]["value"][0])
    points = np.transpose(c["data"]["points"][:3], (2, 1, 0)) / 1000.0  # mm → m (POINT:UNITS is mm)
    return np.arange(points.shape[0]) / rate, points, labels, c


def lab_events(c) -> dict:
    """The file's own EVENT group: (side, kind) → times in s from the first frame."""
    labels = c["parameters"]["EVENT"]["LABELS"]["value"]
    times = np.asarray(c["parameters"]["EVENT"]["TIMES"]["value"])[1]
    rate = float(c["parameters"]["POINT"]["RATE"]["value"][0])
    start = c["header"]["points"]["first_frame"] / rate
    out = {}
    for label, t in zip(labels, times):
        key = ({"L": "l", "R": "r"}[label[0]], {"HS": "heel_strike", "TO": "toe_off"}[label[1:]])
        out.setdefault(key, []).append(float(t) - start)
    return {k: np.array(sorted(v)) for k, v in out.items()}


def test_example_files_are_complete():
    subject = yaml.safe_load((EXAMPLE / "subject.yaml").read_text())
    landmarks = set(subject["marker_map"].values())
    wanted = {f"{d}{s}" for d in ("ASIS", "PSIS", "GT", "LEF", "MEF", "TT", "LM", "MM", "CA", "FM", "VM")
              for s in "rl"} | {"C7", "ST", "ACr", "ACl"}
    assert landmarks == wanted
    assert subject["mass_kg"] == "auto"
    readme = (EXAMPLE / "README.md").read_text()
    assert "gait idyn" in readme and "trial.c3d" in readme


def test_model_markers_are_all_used(qualisys):
    summary = qualisys["summary"]
    assert summary["locked_segments"] == []
    errors = summary["segment_rms_marker_error_mm"]
    assert all(value is not None and 0.1 < value < 15.0 for value in errors.values()), errors
    assert summary["mass_source"].startswith("estimated from the force plates")
    assert 45.0 < summary["mass_kg"] < 90.0


def test_gait_features_are_plausible_and_match_the_pelvis(qualisys, shared_c3d_dir):
    summary = qualisys["summary"]
    time_s, points, labels, c = lab_markers(shared_c3d_dir / "Qualisys.c3d")
    pelvis_x = points[:, [labels.index(p) for p in PELVIS], 0].mean(axis=1)
    # physiological ranges for adult walking
    assert 0.8 < summary["speed_m_s"] < 2.0
    assert 1.0 < summary["stride_length_m"] < 1.9
    assert 0.8 < summary["period_s"] < 1.4
    for key in ("stance_right_pct", "stance_left_pct"):
        assert 52.0 < summary[key] < 68.0, key
    assert 5.0 < summary["double_stance_pct"] < 35.0
    # speed: the pelvis's mean forward velocity
    pelvis_speed = np.polyfit(time_s, pelvis_x, 1)[0]
    assert summary["speed_m_s"] == pytest.approx(pelvis_speed, rel=0.03)
    # stride length: the pelvis's displacement between the heel strikes that bound each stride
    events = qualisys["events"]
    displacement = []
    for side in "rl":
        strikes = np.sort(events.time_s[(events.side == side) & (events.event == "heel_strike")].to_numpy())
        displacement += list(np.diff(np.interp(strikes, time_s, pelvis_x)))
    assert len(displacement) == summary["strides"] == 2
    assert summary["stride_length_m"] == pytest.approx(np.mean(displacement), rel=0.03)
    assert summary["speed_m_s"] == pytest.approx(summary["stride_length_m"] / summary["period_s"], rel=1e-9)
    # the lab's own events
    lab = lab_events(c)
    lab_period = np.mean([np.diff(lab[(s, "heel_strike")]).mean() for s in "rl"])
    assert summary["period_s"] == pytest.approx(lab_period, rel=0.04)
    for side, key in (("r", "stance_right_pct"), ("l", "stance_left_pct")):
        strikes, offs = lab[(side, "heel_strike")], lab[(side, "toe_off")]
        stance = np.mean([offs[offs > a][0] - a for a in strikes if (offs > a).any()])
        assert summary[key] == pytest.approx(stance / lab_period * 100, abs=5.0), key


def test_pelvis_residuals_are_reported(qualisys):
    summary = qualisys["summary"]
    assert summary["residual_frames"] > 100  # one foot on a plate, the other in swing or on the other plate
    weight_N = summary["mass_kg"] * 9.81
    assert 0.0 < summary["rms_residual_force_N"] < 0.3 * weight_N
    assert 0.0 < summary["rms_residual_moment_Nm"] < 100.0
    assert np.isfinite(summary["rms_residual_force_all_frames_N"])
    residuals = pd.read_csv(qualisys["trial"] / "gait_out" / "idyn" / "residuals.csv")
    measured = residuals["all_contacts_measured"].to_numpy() == 1
    assert np.isfinite(residuals.to_numpy()[measured]).all()


def stance_curve(qualisys, side: str, joint: str):
    """(percent of stance, sagittal moment N·m/kg, flexion/dorsiflexion positive) over the stance this side made
    on a plate."""
    events = qualisys["events"]
    mine = (events.side == side) & (events.source == "plate")
    strike = events.time_s[mine & (events.event == "heel_strike")].to_numpy()
    off = events.time_s[mine & (events.event == "toe_off")].to_numpy()
    assert strike.size == 1 and off.size == 1 and off[0] > strike[0]
    moments = qualisys["moments"]
    t = moments.time_s.to_numpy()
    inside = (t >= strike[0]) & (t <= off[0])
    assert (moments[f"{SIDES[side]}_foot_load_known"].to_numpy()[inside] == 1).all()
    pct = (t[inside] - strike[0]) / (off[0] - strike[0]) * 100
    extensor = "plantarflexor" if joint == "ankle" else "extensor"
    return pct, -moments[f"{joint}_{side}_{extensor}_moment_per_kg"].to_numpy()[inside]


@pytest.mark.parametrize("side", ["l", "r"])
def test_hip_extension_moment_early_flexion_moment_late(qualisys, side):
    pct, hip = stance_curve(qualisys, side, "hip")
    early, late = hip[pct <= 25], hip[pct >= 60]
    assert early.min() < -0.3  # extension moment in loading response (measured −1.01 l, −0.59 r)
    assert late.max() > 0.3  # flexion moment in terminal stance (measured +0.98 l, +1.40 r)
    assert pct[np.argmin(hip)] < 30 and pct[np.argmax(hip)] > 60


@pytest.mark.parametrize("side", ["l", "r"])
def test_knee_extension_moment_after_heel_strike(qualisys, side):
    pct, knee = stance_curve(qualisys, side, "knee")
    # after a brief flexion moment at impact, an extension moment (negative) in the loading response
    assert knee[pct <= 5].max() > 0.0
    assert np.mean(knee[(pct >= 15) & (pct <= 25)]) < -0.3  # measured −0.61 l, −1.00 r
    assert 12 < pct[np.argmin(knee)] < 35  # peak at 22 % (l), 18 % (r)


@pytest.mark.parametrize("side", ["l", "r"])
def test_ankle_plantarflexion_moment_peaks_in_the_second_half_of_stance(qualisys, side):
    pct, ankle = stance_curve(qualisys, side, "ankle")
    peak = int(np.argmin(ankle))
    assert 50 < pct[peak] < 95  # measured 79 % (l), 77 % (r)
    assert -2.0 < ankle[peak] < -0.8  # measured −1.31 l, −1.06 r
    assert np.all(ankle[pct <= 15] > -0.5)  # little plantarflexion moment while the heel loads (−0.20, +0.02)
    assert abs(ankle[-1]) < 0.3  # unloaded at toe off (−0.05, −0.01)


def test_eid_on_the_right_stride_of_real_data(qualisys):
    """EID on measured data (the right stride whose stance is on plate 2): converges with 0 ≤ u, a ≤ 1.
    Measured: 191 J for one leg's stride, cost of transport (both legs) 267 J/m beside Ralston's
    218 J/m at the stride's 1.46 m/s (the dissertation's subject 1: 311 against 247 J/m)."""
    run = qualisys["eid"]
    assert run.returncode == 0, run.describe()
    folder = qualisys["trial"] / "gait_out" / "muscles" / "eid"
    info = json.loads((folder / "summary.json").read_text())
    assert info["converged"] is True and info["side"] == "r" and info["periodic"] is True
    assert -1e-6 <= info["min_excitation"] and info["max_excitation"] <= 1 + 1e-6
    activations = pd.read_csv(folder / "activations.csv").drop(columns="time_s").to_numpy()
    assert activations.min() >= -1e-6 and activations.max() <= 1 + 1e-6
    assert info["max_moment_error_Nm"] < 0.5
    assert 50 < info["metabolic_cost_J"] < 500
    assert 0.5 < info["cost_of_transport_J_per_m"] / info["ralston_J_per_m"] < 2.0
