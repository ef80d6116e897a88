"""`gait synth`: the predicted walk refuses a locked-joint condition before writing anything; a noise-free trial's
anatomical angles through `gait idyn` are its truth's; a 120-Hz Plug-in Gait walk with medial markers gives the
true sagittal moments."""

from __future__ import annotations

import json

import ezc3d
import numpy as np
import pandas as pd
import pytest

from .conftest import gait


def test_a_predicted_walk_with_a_locked_joint_is_exit_2_and_writes_nothing(tmp_path):
    run = gait("synth", tmp_path / "boot", "--gait", "predicted", "--condition", "ski_boot", cwd=tmp_path)
    assert run.returncode == 2, run.describe()
    assert run.stderr_lines == [run.stderr_lines[0]] and "--gait" in run.stderr and "ski_boot" in run.stderr
    assert "Traceback" not in run.stderr and not (tmp_path / "boot").exists()


def test_a_period_of_no_whole_marker_frames_still_writes_a_readable_trial(tmp_path):
    # 1.068 s is 1068 analog samples: the trial is cut to whole marker frames (10 samples each)
    assert gait("synth", tmp_path / "t", "--period-s", "1.068", "--strides", "1", cwd=tmp_path).returncode == 0
    run = gait("filter", tmp_path / "t", "-o", tmp_path / "out", cwd=tmp_path)
    assert run.returncode == 0, run.describe()


#: |kinematics.csv − truth filtered alike| (deg) of a noise-free `gait synth` walk, every frame and angle. The 6 Hz
#: filter is linear in the marker positions and the angles nearly so; what it leaves is its action on the angles'
#: nonlinearity and its end conditions. Measured (seed 2, one stride of the predicted walk, 214 frames): Plug-in
#: Gait 0.17° inside (ankle flexion), 0.30° at the last frame (knee flexion); dissertation (ISB) the same. Against
#: the unfiltered truth the filter's attenuation of the knee's swing peak dominates: 1.24° max, 0.36° RMS (knee).
FILTERED_TRUTH_DEG = 0.4
#: the unfiltered truth (deg): max and RMS over frames, per angle
RAW_TRUTH_DEG = (1.5, 0.5)
#: the marker cut-off ``auto`` stands for, Hz: a Plug-in Gait session's 8, the dissertation's 6 (3.1.4)
AUTO_MARKER_CUTOFF_HZ = {"plug_in_gait": 8.0, "dissertation": 6.0}


@pytest.mark.parametrize("marker_set", ["plug_in_gait", "dissertation"])
def test_noise_free_synthetic_angles_are_the_truths_anatomical_angles(tmp_path, marker_set):
    """`gait synth --marker-set … --noise-mm 0 --artefact-mm 0` → `gait idyn`: kinematics.csv's anatomical angles
    (Plug-in Gait's CGM frames, or ISB's) against truth/anatomical_angles.csv (the body's own, synth/anatomy.py),
    both filtered by the independent reference filter at the session's cut-off (tests/cli/truth.py) and raw."""
    from .truth import lowpass_reference, read_table

    trial = tmp_path / marker_set
    made = gait("synth", trial, "--marker-set", marker_set, "--noise-mm", "0", "--artefact-mm", "0",
                "--strides", "1", "--seed", "2", cwd=tmp_path)
    assert made.returncode == 0, made.describe()
    run = gait("idyn", trial, "--no-plots", cwd=tmp_path)
    assert run.returncode == 0, run.describe()
    got = read_table(trial / "gait_out" / "idyn" / "kinematics.csv")
    truth = read_table(trial / "truth" / "anatomical_angles.csv")
    assert list(got.columns) == list(truth.columns) and len(got) == len(truth) > 200
    np.testing.assert_allclose(got["time_s"], truth["time_s"], atol=1e-9)
    angles = list(truth.columns[1:])
    error = np.abs(got[angles].to_numpy() - lowpass_reference(truth[angles].to_numpy(), 100.0,
                                                                 AUTO_MARKER_CUTOFF_HZ[marker_set]))
    assert error.max() < FILTERED_TRUTH_DEG, dict(zip(angles, error.max(axis=0).round(3)))
    raw = got[angles].to_numpy() - truth[angles].to_numpy()
    assert np.abs(raw).max() < RAW_TRUTH_DEG[0] and np.sqrt(np.mean(raw ** 2, axis=0)).max() < RAW_TRUTH_DEG[1]


def test_a_120_hz_plug_in_gait_walk_with_medial_markers_gives_the_true_sagittal_moments(tmp_path):
    """`gait synth --rate-hz 120 --medial-markers` (issue 52: a lab's 120-Hz walk with medial knee and ankle markers),
    then `gait idyn`: markers at 120 Hz, plates at 1200 Hz, the medial markers in the file, filtered as a Plug-in
    Gait session's (8 Hz markers, plates unfiltered and averaged over each frame), and every sagittal moment
    within 0.05 N·m/kg RMS of the truth where gaitcli reports it, the slope within 0.95–1.05 (the issue's
    bounds)."""
    trial = tmp_path / "walk"
    run = gait("synth", trial, "--marker-set", "plug_in_gait", "--rate-hz", "120", "--medial-markers",
               "--strides", "2", cwd=tmp_path)
    assert run.returncode == 0, run.describe()
    parameters = ezc3d.c3d(str(trial / "trial.c3d"))["parameters"]
    assert parameters["POINT"]["RATE"]["value"][0] == 120 and parameters["ANALOG"]["RATE"]["value"][0] == 1200
    assert {"RKNM", "LKNM", "RMED", "LMED"} <= set(parameters["POINT"]["LABELS"]["value"])
    assert gait("idyn", trial, "--no-plots", cwd=tmp_path).returncode == 0
    filtered = json.loads((trial / "gait_out" / "filter" / "summary.json").read_text())
    assert (filtered["cutoff_hz"], filtered["force_cutoff_hz"], filtered["plate_frames"]) == (8.0, 0.0, "mean")
    truth = pd.read_csv(trial / "truth" / "joint_moments.csv")
    got = pd.read_csv(trial / "gait_out" / "idyn" / "joint_moments.csv")
    mass_kg = 75.0  # gait synth's default subject
    for joint, name in (("hip", "extensor"), ("knee", "extensor"), ("ankle", "plantarflexor")):
        for side in "rl":
            want = truth[f"{joint}_{side}_flexion_moment"].to_numpy()  # flexion / dorsiflexion positive
            have = -got[f"{joint}_{side}_{name}_moment"].to_numpy()
            known = np.isfinite(have)
            assert known.sum() > 150
            rms = np.sqrt(np.mean((have[known] - want[known]) ** 2)) / mass_kg
            slope = np.polyfit(want[known], have[known], 1)[0]
            assert rms <= 0.05 and 0.95 <= slope <= 1.05, (joint, side, rms, slope)


def test_medial_markers_need_the_plug_in_gait_set(tmp_path):
    run = gait("synth", tmp_path / "walk", "--medial-markers", cwd=tmp_path)
    assert run.returncode == 2 and "medial_markers" in run.stderr and "plug_in_gait" in run.stderr
    assert not (tmp_path / "walk").exists()
