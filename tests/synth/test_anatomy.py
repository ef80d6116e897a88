"""The synthetic body's true anatomy (``gaitcli.synth.anatomy``): known answers, and the package's own code where it
is a second implementation of the same definition."""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.kinematics.anatomical import ANATOMICAL_ANGLES, PIG_FOOT_AXES
from gaitcli.kinematics.anatomical import anatomical_angles as package_angles
from gaitcli.kinematics.calibration import calibrate
from gaitcli.kinematics.conventions import coordinates_to_clinical
from gaitcli.kinematics.markerset import landmarks_to_markers, standing_template
from gaitcli.kinematics.model import COORDINATES
from gaitcli.kinematics.rotations import rot_x, rot_y, rot_z
from gaitcli.synth import MARKER_BODY, simulate_trial
from gaitcli.synth.anatomy import VICON_FOOT_IN_SEGMENT, anatomical_angles, static_foot_offsets_rad
from gaitcli.synth.recording import plug_in_gait_body

STATURE_M = 1.78


def _template():
    return {k: v for k, v in standing_template(STATURE_M).items() if k in MARKER_BODY}


def test_a_plug_in_gait_subjects_hips_are_where_the_calibrations_davis_puts_them():
    """The truth's Davis et al. (1991) hip centres (synth.anatomy) equal the calibration's (joint_centres.py) for
    the same standing pelvis, leg length and marker radius: two implementations of one regression."""
    template, options = plug_in_gait_body(_template())
    cal = calibrate(landmarks_to_markers(template), mass_kg=75.0, stature_m=STATURE_M, **options)
    from gaitcli.synth.anatomy import davis_hip_centres_m

    hips = davis_hip_centres_m(template, leg_length_m=options["leg_length_m"], marker_radius_m=0.007)
    for s in "rl":
        np.testing.assert_allclose(cal.joint_centres_m[f"HJC{s}"], hips[f"HJC{s}"], atol=1e-12)
    # Davis puts them lower, further back and more medial than Bell (0.30, 0.19, 0.36 of the ASIS width)
    bell = standing_template(STATURE_M, with_virtual_joint_centres=True)["HJCr"]
    assert hips["HJCr"][2] < bell[2] - 0.02 and hips["HJCr"][0] < bell[0] and hips["HJCr"][1] > bell[1]


def test_a_plug_in_gait_subjects_knee_marker_is_at_right_angles_to_the_thigh():
    """The epicondyles turned about their midpoint (the knee centre) until at right angles to the hip → knee axis,
    in the plane of that axis and the lateral direction; their distance kept (the knee width)."""
    before = _template()
    template, options = plug_in_gait_body(before)
    cal = calibrate(landmarks_to_markers(template), mass_kg=75.0, stature_m=STATURE_M, **options)
    for s, lateral in (("r", -1.0), ("l", 1.0)):
        knee, hip = cal.joint_centres_m[f"KJC{s}"], cal.joint_centres_m[f"HJC{s}"]
        to_marker = template[f"LEF{s}"] - knee
        np.testing.assert_allclose(knee, (before[f"LEF{s}"] + before[f"MEF{s}"]) / 2, atol=1e-15)
        assert np.dot(to_marker, hip - knee) == pytest.approx(0.0, abs=1e-15)
        assert np.linalg.norm(to_marker) == pytest.approx(0.025 * STATURE_M, abs=1e-15)
        assert lateral * to_marker[1] > 0.99 * np.linalg.norm(to_marker)
        assert np.linalg.det(np.stack([to_marker, hip - knee, [0.0, 1.0, 0.0]])) == pytest.approx(0.0, abs=1e-15)


def test_static_foot_offsets_of_a_heel_off_the_ankle_toe_line():
    """The heel on the toe → ankle line: no offsets; the heel raised by turning it 10° about the toe in the sagittal
    plane: plantarflexion offset +10°; turned 6° about the foot's up axis: rotation ±6° and no plantarflexion."""
    toe, ankle, y = np.array([0.15, 0.0, 0.02]), np.array([0.0, 0.0, 0.08]), np.array([0.0, 1.0, 0.0])
    heel_on_line = toe + 1.4 * (ankle - toe)
    assert static_foot_offsets_rad(ankle, toe, heel_on_line, y) == pytest.approx((0.0, 0.0), abs=1e-15)
    back = heel_on_line - toe
    raised = toe + rot_y(np.radians(10.0)) @ back
    assert np.degrees(static_foot_offsets_rad(ankle, toe, raised, y)) == pytest.approx((10.0, 0.0), abs=1e-12)
    up = np.cross(y, back / np.linalg.norm(back))  # the foot frame's x: flexion axis × long axis
    c, s = np.cos(np.radians(6.0)), np.sin(np.radians(6.0))
    turned = toe + c * back + s * np.cross(up, back)  # Rodrigues about the up axis
    pf, rotation = np.degrees(static_foot_offsets_rad(ankle, toe, turned, y))
    assert pf == pytest.approx(0.0, abs=1e-12) and abs(rotation) == pytest.approx(6.0, abs=1e-12)


@pytest.mark.parametrize("ankle", ["plug_in_gait", "isb"])
def test_the_truths_angles_decompose_frames_as_the_package_does(ankle):
    """Random pelvis, thigh, shank and foot frames: the truth's decomposition (synth.anatomy, its own Cardan
    y-x-z formulas) and the package's (kinematics.anatomical) give the same 23 angles."""
    rng = np.random.default_rng(7)
    n = 50

    def turn(scale):
        a = rng.uniform(-scale, scale, (3, n))
        return rot_y(a[0]) @ rot_x(a[1]) @ rot_z(a[2])

    frames = {"pelvis": rot_z(rng.uniform(-0.2, 0.2, n)) @ turn(0.2)}
    for s in "rl":
        frames[f"thigh_{s}"] = frames["pelvis"] @ turn(0.6)
        frames[f"shank_{s}"] = frames[f"thigh_{s}"] @ turn(0.6)
        frames[f"foot_{s}"] = frames[f"shank_{s}"] @ turn(0.4)
    truth_frames = dict(frames)
    if ankle == "plug_in_gait":
        for s in "rl":
            truth_frames[f"vicon_foot_{s}"] = frames[f"foot_{s}"] @ VICON_FOOT_IN_SEGMENT
    np.testing.assert_array_equal(VICON_FOOT_IN_SEGMENT, PIG_FOOT_AXES)
    np.testing.assert_allclose(anatomical_angles(truth_frames), package_angles(frames, ankle=ankle), atol=1e-12)


def test_where_pelvis_and_thigh_frames_stand_level_the_true_hip_angles_are_the_hip_coordinates():
    """The dissertation's standing template has a level pelvis (ASIS and PSIS at one height) and thighs whose hip
    centre (Bell) stands above the knee with the epicondyles along y: their anatomical frames are the reference
    frames, so over a whole walk the true hip angles are the model's hip coordinates (3.1), and standing the
    knee flexion is the shank's forward lean, atan(0.0025 / 0.2499) = 0.573° (mid-malleoli 0.0025 H behind and
    0.003 H above the template's ankle height)."""
    trial = simulate_trial(seed=0, strides=1, noise_mm=0.0, artefact_mm=0.0)
    got = np.degrees(trial.anatomical_angles_rad)
    coordinates = coordinates_to_clinical(trial.q)
    for side in "rl":
        for axis in ("flexion", "adduction", "rotation"):
            np.testing.assert_allclose(got[:, ANATOMICAL_ANGLES.index(f"hip_{side}_{axis}")],
                                       coordinates[:, COORDINATES.index(f"hip_{side}_{axis}")], atol=1e-10)
    from gaitcli.kinematics.forward import forward_kinematics
    from gaitcli.kinematics.model import BODIES
    from gaitcli.synth.anatomy import anatomical_frames, standing_frames

    standing = np.zeros((1, len(COORDINATES)))
    rotation = forward_kinematics(standing, trial.calibration.body).rotation
    frames = anatomical_frames({b: rotation[:, i] for i, b in enumerate(BODIES)},
                               standing_frames(_template(), trial.calibration.joint_centres_m))
    still = np.degrees(anatomical_angles(frames))[0]
    for side in "rl":
        assert still[ANATOMICAL_ANGLES.index(f"knee_{side}_flexion")] == pytest.approx(
            np.degrees(np.arctan2(0.0025, 0.2529 - 0.003)), abs=1e-9)
        assert still[ANATOMICAL_ANGLES.index(f"knee_{side}_adduction")] == pytest.approx(0.0, abs=1e-9)
        assert still[ANATOMICAL_ANGLES.index(f"hip_{side}_flexion")] == pytest.approx(0.0, abs=1e-9)
