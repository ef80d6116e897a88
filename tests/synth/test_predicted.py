"""The synthetic walk from the shipped prediction (``gaitcli.synth.predicted``): the 27-DoF motion is the
walking model's, checked by the two models' own equations — the planar model's generalized base forces
(its Lagrangian, M ÿ + k − g) against the 3-D model's whole-body wrench (Newton–Euler) — and by the feet."""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.dynamics.inverse import required_external_wrench
from gaitcli.kinematics.calibration import calibrate
from gaitcli.kinematics.forward import forward_kinematics
from gaitcli.kinematics.markerset import landmarks_to_markers, standing_template
from gaitcli.kinematics.model import JOINTS
from gaitcli.synth import ground_reactions
from gaitcli.synth.gait import CONDITIONS
from gaitcli.synth.predicted import (
    STEP_WIDTH_PER_STATURE,
    STRIDE_PER_STATURE,
    WALK_FILE,
    WALK_SPEED_M_S,
    WALK_SUBJECT,
    phase_of,
    predicted_gait,
    predicted_period_s,
    walker_cycle,
)
from gaitcli.synth.recording import MARKER_BODY, MARKER_RATE_HZ

MASS_KG, STATURE_M = WALK_SUBJECT["mass_kg"], WALK_SUBJECT["stature_m"]


@pytest.fixture(scope="module")
def walk():
    from dataclasses import replace

    template = {k: v for k, v in standing_template(STATURE_M).items() if k in MARKER_BODY}
    params = calibrate(landmarks_to_markers(template, rate_hz=MARKER_RATE_HZ), mass_kg=MASS_KG,
                       stature_m=STATURE_M, sex="male").body
    _, durations, _ = walker_cycle(np.zeros(1))
    period = float(np.sum(durations))  # the prediction's own period: no time scaling
    design = predicted_gait(replace(CONDITIONS["normal"], period_s=period), params, stature_m=STATURE_M)
    return design, params, durations


def test_speed_stride_and_period_are_the_predictions(walk):
    design, _, durations = walk
    assert design.stride_m == pytest.approx(STRIDE_PER_STATURE * STATURE_M, abs=1e-6)  # the prescribed steps
    assert design.speed_m_s == pytest.approx(WALK_SPEED_M_S, abs=1e-4)  # (5.43) holds
    assert predicted_period_s(STATURE_M) == pytest.approx(float(np.sum(durations)), abs=0.005)
    assert predicted_period_s(1.65) == pytest.approx(predicted_period_s(STATURE_M) * np.sqrt(1.65 / 1.78), abs=0.006)


def test_the_3d_whole_body_wrench_is_the_walking_models(walk):
    """At ten instants: the planar model's base forces Q_x, Q_z and its moment about the hip (Q of the HAT and
    both absolute thighs) equal the 3-D model's required ground wrench, within 1 % of body weight and 3 N·m
    (the 3-D walk adds the sideways sway and hip adduction; its shank is 1 mm longer)."""
    from gaitcli.predict.layout import DesignLayout
    from gaitcli.predict.model import WalkerParameters, WalkingModel
    from gaitcli.predict.problem import gait_at

    design, params, durations = walk
    period = float(np.sum(durations))
    times = np.linspace(0.0, period, 11)[:-1]
    _, _, _, (y, yd, ydd, _) = gait_at(DesignLayout.build(18, symmetric=True), np.loadtxt(WALK_FILE), times)
    model = WalkingModel(WalkerParameters.from_subject(**WALK_SUBJECT))
    base = np.array([np.array(model.mass_matrix(a)) @ c + np.array(model.bias(a, b)).ravel()
                     - np.array(model.gravity(a)).ravel() for a, b, c in zip(y, yd, ydd)])
    qd, qdd, _, _ = ground_reactions(design, params)
    force, moment = required_external_wrench(design.q, qd, qdd, params)
    hips = forward_kinematics(design.q, params).joint_centre_m[:, [JOINTS.index("hip_r"), JOINTS.index("hip_l")]]
    hip = hips.mean(axis=1)
    about_hip = moment[:, 1] - (hip[:, 2] * force[:, 0] - hip[:, 0] * force[:, 2])
    rows = np.round(times / period * design.q.shape[0]).astype(int)
    weight = MASS_KG * 9.81
    np.testing.assert_allclose(force[rows, 0], base[:, 0], atol=0.01 * weight)
    np.testing.assert_allclose(force[rows, 2], base[:, 1], atol=0.01 * weight)
    np.testing.assert_allclose(about_hip[rows], base[:, 2] + base[:, 3] + base[:, 6], atol=3.0)


def test_feet_stay_planted_and_in_their_lanes(walk):
    design, params, durations = walk
    ankles = forward_kinematics(design.q, params).joint_centre_m
    phases = phase_of(durations)
    n = design.q.shape[0]
    phase = np.arange(n) / n
    for side, flat in (("r", (2, 3)), ("l", (6, 7))):  # foot flat: between its own foot-flat and heel-off
        ankle = ankles[:, JOINTS.index(f"ankle_{side}")]
        rows = (phase >= phases[flat[0]][0]) & (phase < phases[flat[1]][1])
        # the walker's contact points may move by εk = 2 mm; the 3-D shank is 1 mm longer and its ankle centre
        # 4.5 mm behind the knee's vertical when standing, so its ankle moves a little more (6.3 mm measured
        # over the foot-flat phases, 3.7–39 % of the cycle)
        assert np.ptp(ankle[rows, 0]) < 0.007 and np.ptp(ankle[rows, 2]) < 0.007
        lane = (-0.5 if side == "r" else 0.5) * STEP_WIDTH_PER_STATURE * STATURE_M
        np.testing.assert_allclose(ankle[:, 1], lane, atol=5e-4)


def test_the_feet_share_the_wrench(walk):
    """In double support the whole-body COP lies between the feet's: the share λ leaves [0, 1] by 0.2 %
    (measured) at the ends of the run, so the feet carry the whole-body force to 1 % of body weight."""
    design, params, _ = walk
    qd, qdd, feet, clip = ground_reactions(design, params)
    force, _ = required_external_wrench(design.q, qd, qdd, params)
    assert clip < 0.01
    np.testing.assert_allclose(feet["r"]["force_N"] + feet["l"]["force_N"], force, atol=0.01 * MASS_KG * 9.81)


def test_the_centre_of_pressure_rolls_and_the_trunk_is_steady(walk):
    """The walk's Jdev tracked a rolling centre of pressure and a steady trunk (WALK_TRACKING): in right single
    support the 3-D COP (from the whole-body wrench) is 15 mm ahead of the ankle at the left toe-off and rolls
    forward until heel-off (30 % of the cycle, measured) to 0.17 m; the pelvis tilts by 1.3° over the cycle."""
    design, params, durations = walk
    _, _, feet, _ = ground_reactions(design, params)
    ankle = forward_kinematics(design.q, params).joint_centre_m[:, JOINTS.index("ankle_r")]
    ahead = feet["r"]["cop_m"][:, 0] + design.speed_m_s * design.time_s - ankle[:, 0]  # the COP rides with v·t
    phase, phases = design.time_s / design.period_s, phase_of(durations)
    rolling = (phase >= phases[3][0]) & (phase < phases[3][1])  # right foot flat, left foot off the ground
    assert 0.25 < phases[3][1] < 0.45  # heel-off
    assert ahead[rolling][0] < 0.03 and 0.15 < ahead[rolling].max() < 0.25
    assert np.all(np.diff(ahead[rolling]) > -1e-3)
    assert np.degrees(np.ptp(design.q[:, 4])) < 2.0


def test_the_bundled_normal_trial_is_the_default_subjects_walk_with_a_typical_swing_hip():
    """sample_trials/normal is `gait synth --seed 1`: the default subject on the predicted walk; its truth's hip
    moment in swing (the foot off the ground) stays within ±0.3 N·m/kg (issue 11; measured −0.24 … +0.28)."""
    import pandas as pd
    import yaml

    from gaitcli.resources import sample_trials_dir

    folder = sample_trials_dir() / "normal"
    subject = yaml.safe_load((folder / "subject.yaml").read_text())
    assert (subject["mass_kg"], subject["stature_m"]) == (MASS_KG, STATURE_M)
    moments, grf = pd.read_csv(folder / "truth" / "joint_moments.csv"), pd.read_csv(folder / "truth" / "grf.csv")
    kinematics = pd.read_csv(folder / "truth" / "kinematics.csv")
    assert np.polyfit(kinematics.time_s, kinematics.pelvis_x, 1)[0] == pytest.approx(WALK_SPEED_M_S, abs=0.01)
    for side in "rl":
        swing = grf[f"foot_{side}_force_z_N"].to_numpy() <= 0
        hip = moments[f"hip_{side}_flexion_moment"].to_numpy()[swing] / MASS_KG
        assert swing.sum() > 100 and np.abs(hip).max() < 0.3
