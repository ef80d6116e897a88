"""``pose: chain_lsq`` (kinematics/chain_fit.py) against the segment fit on synthetic walks with known truth.

Measured (seed 1, 2 mm marker noise, 10 mm skin artefact, the hip centres displaced 25 mm in the static trial;
joint-centre RMS error over the whole trial, mm, right knee / right ankle / left knee / left ankle):

| hip error | segment_svd | chain_lsq |
| --- | --- | --- |
| none | 5.3 5.6 3.7 5.5 | 2.7 3.4 3.3 3.6 |
| 25 mm anterior | 10.0 10.2 10.8 11.9 | 4.2 3.8 4.7 4.3 |
| 25 mm superior | 11.6 11.8 8.8 8.7 | 2.9 3.5 3.3 3.7 |
| 25 mm lateral | 4.8 5.1 5.2 6.8 | 2.9 3.4 3.2 3.6 |

(A lateral error lies along the hip's flexion axis, about which the thigh mostly turns, so the segment fit hands
little of it down.) Gauss–Newton takes 9–12 iterations, about 2 s for 480 frames.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from gaitcli.core.recording import Markers, Recording
from gaitcli.dynamics.stage import IdynConfig, inverse_dynamics_stage
from gaitcli.kinematics.calibration import calibrate
from gaitcli.kinematics.chain_fit import fit_chain
from gaitcli.kinematics.conventions import moments_to_clinical
from gaitcli.kinematics.coordinates import poses_to_coordinates, track_segments
from gaitcli.kinematics.forward import forward_kinematics
from gaitcli.kinematics.markerset import with_fixed_points
from gaitcli.kinematics.model import JOINTS, MOMENTS
from gaitcli.signal.stage import FilterConfig, filter_trial
from gaitcli.synth import simulate_trial

MASS_KG = 75.0


def _with_hip_centres_moved(static: Markers, calibration, shift_m) -> Markers:
    """The static trial with the lab's virtual hip centres where Bell puts them, moved by ``shift_m``."""
    return with_fixed_points(static, {k: calibration.joint_centres_m[k] + np.asarray(shift_m)
                                      for k in ("HJCr", "HJCl")})


def test_an_exact_trial_is_a_fixed_point():
    trial = simulate_trial(seed=1, noise_mm=0.0, artefact_mm=0.0, plate_noise_N=0.0)
    calibration = calibrate(trial.static, mass_kg=MASS_KG, stature_m=1.78)
    q = poses_to_coordinates(track_segments(trial.markers, calibration))
    fit = fit_chain(q, trial.markers, calibration)
    np.testing.assert_allclose(fit.q, trial.q, atol=1e-9)
    assert fit.iterations <= 2 and np.nanmax(fit.segment_rms_m) < 1e-9


@pytest.fixture(scope="module")
def displaced():
    """Seed 1 with noise and artefact; the static trial's hip centres 25 mm anterior of the truth."""
    trial = simulate_trial(seed=1, noise_mm=2.0, plate_noise_N=0.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        filtered = filter_trial(Recording(trial.markers, trial.plates), FilterConfig()).trial
    bell = calibrate(trial.static, mass_kg=MASS_KG, stature_m=1.78)
    calibration = calibrate(_with_hip_centres_moved(trial.static, bell, [0.025, 0.0, 0.0]), mass_kg=MASS_KG,
                            stature_m=1.78, hip_method="from_file")
    results = {pose: inverse_dynamics_stage(filtered, calibration, IdynConfig(pose=pose), mass_kg=MASS_KG,
                                            mass_source="test") for pose in ("segment_svd", "chain_lsq")}
    return trial, results


def test_a_displaced_hip_centre_is_not_handed_down_to_knee_and_ankle(displaced):
    trial, results = displaced
    truth = forward_kinematics(trial.q, trial.calibration.body).joint_centre_m
    for side in ("r", "l"):
        stance = trial.feet[side]["force_N"][:, 2] > 0
        rms = {}
        for pose, result in results.items():
            error = np.linalg.norm(result.joint_centres_m - truth, axis=-1)[stance]
            rms[pose] = {j: float(np.sqrt(np.nanmean(error[:, JOINTS.index(f"{j}_{side}")] ** 2)))
                         for j in ("knee", "ankle")}
        assert max(rms["chain_lsq"].values()) < 0.005, rms  # issue 11: within 5 mm over stance
        assert all(rms["chain_lsq"][j] < 0.6 * rms["segment_svd"][j] for j in ("knee", "ankle")), rms


def test_the_ankle_moment_with_a_displaced_hip_centre(displaced):
    """Issue 11: below 0.05 N·m/kg with chain_lsq (measured 0.031 r, 0.032 l; segment_svd 0.031, 0.034: the ankle
    moment depends on the foot's pose and load, which neither fit gets wrong by much)."""
    trial, results = displaced
    want = moments_to_clinical(trial.joint_moments_Nm) / MASS_KG
    got = moments_to_clinical(results["chain_lsq"].joint_moments_Nm) / MASS_KG
    for side in ("r", "l"):
        known = results["chain_lsq"].foot_measured[side]
        k = MOMENTS.index(f"ankle_{side}_flexion_moment")
        assert np.sqrt(np.mean((got[known, k] - want[known, k]) ** 2)) < 0.05, side


def test_the_drift_down_the_chain_is_reported(displaced):
    """``joint_centre_gap_m``: each model joint centre to where the child segment's own markers put it. With the
    hip centres 25 mm off, the segment fit's knees sit far from where the shanks' own markers put them, while the
    per-segment marker error (segment_rms_m) stays at the noise's 1 mm; the chain fit closes most of it and shows
    its misfit in its own marker residuals instead. Measured RMS gaps (mm; lumbar, hip, knee, ankle r, hip, knee,
    ankle l): segment_svd 8.7 11.1 12.1 11.2 12.9 11.0 11.1 with segment errors 0.8–1.1 mm; chain_lsq 10.9 6.7 4.2
    3.0 6.9 4.7 2.9 with segment errors 2.3–7.1 mm (the pelvis's the largest)."""
    _, results = displaced
    gap = {pose: np.sqrt(np.nanmean(r.joint_centre_gap_m ** 2, axis=0)) for pose, r in results.items()}
    knees = [JOINTS.index("knee_r"), JOINTS.index("knee_l")]
    assert np.all(gap["segment_svd"][knees] > 0.008)
    assert np.all(gap["chain_lsq"][knees] < 0.5 * gap["segment_svd"][knees])
    assert np.nanmean(results["segment_svd"].segment_rms_m) < 0.005
