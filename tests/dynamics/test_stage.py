"""The idyn stage as a function (``inverse_dynamics_stage``) on synthetic walks with known truth.

Exact case: ``simulate_trial`` without marker noise, skin artefact or plate noise, the stage given
the exact per-foot ground reactions of every contact (plates or not) and the true events, markers
in float64 (no C3D). Measured (normal condition, frames 2 … n−3): coordinates 2e-14 of truth;
joint moments ≤ 0.01 % of each moment's peak (≤ 0.01 N·m); pelvis residuals 0.023 N and 0.012 N·m.
The first and last two frames are left out: there the not-a-knot end conditions of the quintic
interpolating spline (gaitcli/dynamics/derivatives.py) dominate q̈ (frames 0 and n−1: 0.45 % of
peak, residual 1.0 N). The same trial through C3D (float32) and the CLI is in tests/cli/test_idyn_cli.py.

Noisy case: ``gait synth``'s normative walk (white marker noise of 2 mm RMS 3-D error, twice today's default,
10 mm peak skin artefact, 1 N plate noise), through the real filter stage (6 Hz) and the idyn stage. Sagittal
moment RMS error (N·m/kg) over the frames where that foot's load is known (swing, or stance on a
plate), seeds 0–9 (measured through the CLI):

| joint | right | left |
| --- | --- | --- |
| hip | 0.061–0.079 | 0.076–0.094 |
| knee | 0.028–0.037 | 0.071–0.076 |
| ankle | 0.030–0.036 | 0.031–0.040 |

(measured after the generator's double-support COP fix.)
With the noise read as 2 mm per axis (3.5 mm RMS in 3-D) the hip measured 0.084–0.128. The left
leg's swing includes the first and last frames of the trial, where the 6 Hz filter and the spline
ends are least accurate. Pelvis residuals in the frames where every contact is measured: RMS
46–65 N and 18–24 N·m (the noise's and the skin artefact's whole-body acceleration error); see
``test_residual_force_is_what_newtons_law_leaves_over``.
"""

from __future__ import annotations

import dataclasses
import re
import warnings

import numpy as np
import pytest

from gaitcli.core.container import FootLoad, Trial, load_known_frames
from gaitcli.core.events import Events
from gaitcli.core.recording import ForcePlate, Markers, Recording
from gaitcli.dynamics.derivatives import coordinate_derivatives
from gaitcli.dynamics.stage import (
    IdynConfig,
    body_mass,
    estimate_mass_kg,
    inverse_dynamics_stage,
    run_idyn,
    static_calibration,
    stride_period_s,
)
from gaitcli.errors import GaitWarning
from gaitcli.kinematics.calibration import calibrate
from gaitcli.kinematics.conventions import moments_to_clinical
from gaitcli.kinematics.forward import forward_kinematics
from gaitcli.kinematics.markerset import marker_set, with_fixed_points
from gaitcli.kinematics.model import BODIES, COORDINATES, JOINT_CHILD, JOINTS, MOMENTS
from gaitcli.kinematics.subject import Subject
from gaitcli.signal.stage import FilterConfig, filter_trial
from gaitcli.synth import simulate_trial
from gaitcli.synth.devices import with_knee_alignment_device
from tests.signal.conftest import make_walk
from tests.signal.test_stage import _recording as walk_recording

MASS_KG, STATURE_M = 75.0, 1.78
EDGE = 2  # frames left out at each end (spline end conditions)
NOISY_SEEDS = (1, 2, 3)
#: RMS sagittal moment error bounds, N·m/kg (issue 3: 0.1; measured at most 0.094, see above)
RMS_BOUND = {"hip": 0.1, "knee": 0.1, "ankle": 0.1}


def true_events(trial) -> Events:
    """The synthetic trial's events, those on a plate marked as plate events."""
    ev = trial.events
    return Events(frame=[e[1] for e in ev], time_s=[e[0] for e in ev], side=[e[2] for e in ev],
                  kind=[e[3] for e in ev], source=["plate" if e[4] else "kinematics" for e in ev])


def filtered_trial(markers, feet: dict, events: Events) -> Trial:
    """The container the idyn stage takes, from the synthetic truth's per-foot loads (dicts of arrays)."""
    t = markers.time_s
    loads = {}
    for side in ("r", "l"):
        load = feet.get(side)
        if load is None:
            loads[side] = FootLoad.unmeasured(t.size, load_known_frames(events, t, np.zeros(t.size, bool), side))
            continue
        force = np.asarray(load["force_N"], float)
        known = load_known_frames(events, t, np.nan_to_num(force[:, 2]) > 0, side)
        loads[side] = FootLoad(force, np.asarray(load["cop_m"], float), np.asarray(load["free_moment_Nm"], float),
                               known)
    return Trial(markers=markers, feet=loads, events=events)


def calibration_of(trial):
    return calibrate(trial.static, mass_kg=MASS_KG, stature_m=STATURE_M, sex="male")


@pytest.fixture(scope="module")
def exact():
    trial = simulate_trial(condition="normal", seed=0, noise_mm=0.0, artefact_mm=0.0, plate_noise_N=0.0)
    filtered = filtered_trial(trial.markers, trial.feet, true_events(trial))
    calibration = calibration_of(trial)
    result = inverse_dynamics_stage(filtered, calibration, IdynConfig(), mass_kg=MASS_KG, mass_source="test")
    return trial, filtered, calibration, result


def test_exact_trial_gives_the_true_coordinates(exact):
    trial, _, _, result = exact
    assert result.q.shape == (trial.markers.n_frames, len(COORDINATES))
    np.testing.assert_allclose(result.q, trial.q, rtol=0, atol=1e-9)


def test_exact_trial_gives_the_true_moments_and_no_residual(exact):
    trial, _, _, result = exact
    inner = slice(EDGE, -EDGE)
    got = moments_to_clinical(result.joint_moments_Nm)[inner]
    want = moments_to_clinical(trial.joint_moments_Nm)[inner]
    peak = np.abs(want).max(axis=0)
    assert peak.min() > 0.5  # every one of the 21 moments is exercised
    error = np.abs(got - want).max(axis=0)
    worst = MOMENTS[int(np.argmax(error / peak))]
    assert np.all(error <= 5e-4 * peak), f"{worst}: {error.max():.4f} N·m"  # 0.05 % of peak (measured 0.01 %)
    assert np.abs(result.residual_force_N[inner]).max() < 0.1
    assert np.abs(result.residual_moment_Nm[inner]).max() < 0.05
    # every contact is given, so every frame counts as measured for both feet
    assert result.measured.all() and result.foot_measured["r"].all() and result.foot_measured["l"].all()


def test_exact_trial_gait_features(exact):
    trial, _, _, result = exact
    design = trial.design
    f = result.features
    assert f.period_s == pytest.approx(design.period_s, abs=2e-3)  # events at 1 kHz, frames at 100 Hz
    assert f.stride_length_m == pytest.approx(design.stride_m, abs=2e-3)
    assert f.speed_m_s == pytest.approx(design.speed_m_s, rel=3e-3)
    stance = {}
    for side in ("r", "l"):
        on = [e[0] for e in trial.events if e[2] == side and e[3] == "heel_strike" and e[4]]
        off = [e[0] for e in trial.events if e[2] == side and e[3] == "toe_off" and e[4]]
        stance[side] = (off[0] - on[0]) / design.period_s * 100
    assert f.stance_right_pct == pytest.approx(stance["r"], abs=0.3)
    assert f.stance_left_pct == pytest.approx(stance["l"], abs=0.3)
    assert f.double_stance_pct == pytest.approx(stance["r"] + stance["l"] - 100, abs=0.5)


def test_anatomical_frames_rotate_the_same_moment_vectors(exact):
    _, filtered, calibration, reference = exact
    anatomical = inverse_dynamics_stage(filtered, calibration, IdynConfig(frames="anatomical"), mass_kg=MASS_KG,
                                        mass_source="test")
    C = calibration.reference_to_anatomical[list(JOINT_CHILD)]  # R_anatomical = R_reference @ C
    expected = np.einsum("jkl,njk->njl", C, reference.joint_moments_Nm)  # Cᵀ · reference components
    np.testing.assert_allclose(anatomical.joint_moments_Nm, expected, rtol=0, atol=1e-9)
    np.testing.assert_allclose(np.linalg.norm(anatomical.joint_moments_Nm, axis=-1),
                               np.linalg.norm(reference.joint_moments_Nm, axis=-1), rtol=1e-12, atol=1e-9)
    assert anatomical.frames == "anatomical"
    np.testing.assert_array_equal(anatomical.residual_force_N, reference.residual_force_N)


def test_body_mass_from_the_plates(exact):
    # over a periodic stride each foot's vertical impulse is m g T / 2 (2·∫Fz dt / (g T) = m)
    _, filtered, _, _ = exact
    assert estimate_mass_kg(filtered) == pytest.approx(MASS_KG, rel=1e-3)
    no_plates = dataclasses.replace(filtered, events=filtered.events.of(source="kinematics"))
    assert estimate_mass_kg(no_plates) is None


def _subject(mass_kg=None):
    return Subject(mass_kg=mass_kg, stature_m=STATURE_M, sex="male")


def _standing(weight_N: float, *, sway: float = 0.0, metadata=None) -> Recording:
    """A static trial on two plates that share the weight equally (±``sway`` of it, slowly)."""
    t = np.arange(2000) / 1000.0
    plates = []
    for k, sign in enumerate((1.0, -1.0)):
        force = np.zeros((t.size, 3))
        force[:, 2] = weight_N / 2 * (1 + sign * sway * np.sin(2 * np.pi * 0.5 * t))
        plates.append(ForcePlate(f"plate{k + 1}", force, np.zeros((t.size, 3)), np.zeros(3), np.zeros((4, 3)), 1000.0))
    return Recording(Markers(("x",), np.zeros((20, 1, 3)), 10.0), plates, subject_metadata=dict(metadata or {}))


def test_body_mass_comes_from_subject_yaml_then_the_c3d_then_standing_then_the_strides(exact):
    _, filtered, _, _ = exact  # the plates' stride estimate: MASS_KG (test above)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # nothing to warn about: every source within 5 % of the estimate
        assert body_mass(filtered, _subject(74.0), IdynConfig(), source=None)[:2] == (74.0, "subject.yaml")
        in_file = dataclasses.replace(filtered, subject_metadata={"PROCESSING:Bodymass": 76.0, "SUBJECT:WEIGHT": 1.0})
        mass, where, estimate = body_mass(in_file, _subject(), IdynConfig(), source=None)
        assert (mass, where) == (76.0, "the C3D file's PROCESSING:Bodymass")
        assert estimate == pytest.approx(MASS_KG, rel=1e-3)
        mass, where, _ = body_mass(filtered, _subject(), IdynConfig(), static=_standing(74.5 * 9.81), source=None)
        assert mass == pytest.approx(74.5) and where.startswith("quiet standing")
        # a swaying subject (±20 % between the plates, the sum steady) still stands quietly; one plate alone does not
        assert body_mass(filtered, _subject(), IdynConfig(), static=_standing(74.5 * 9.81, sway=0.2),
                         source=None)[0] == pytest.approx(74.5)
        one_plate = _standing(74.5 * 9.81, sway=0.2)
        one_plate.plates = one_plate.plates[:1]
        mass, where, _ = body_mass(filtered, _subject(), IdynConfig(), static=one_plate, source=None)
        assert mass == pytest.approx(MASS_KG, rel=1e-3) and where.startswith("estimated from the force plates")


def test_a_body_mass_from_a_vsk_is_said_to_come_from_it(exact):
    """A .vsk's Bodymass (merged into the trial's subject data, or the mass of a subject made from it alone) is
    named as the .vsk's, not the C3D's."""
    _, filtered, _, _ = exact
    vsk = dataclasses.replace(_subject(), measurements={"PROCESSING:Bodymass": 75.5}, measurements_source="S.vsk")
    in_file = dataclasses.replace(filtered, subject_metadata={"PROCESSING:Bodymass": 75.5})
    assert body_mass(in_file, vsk, IdynConfig(), source=None)[:2] == (75.5, "S.vsk's Bodymass")
    alone = dataclasses.replace(_subject(75.5), mass_source="S.vsk's Bodymass")
    assert body_mass(filtered, alone, IdynConfig(), source=None)[:2] == (75.5, "S.vsk's Bodymass")


def test_a_body_mass_far_from_the_stride_estimate_is_warned_with_both_values(exact):
    _, filtered, _, _ = exact
    in_file = dataclasses.replace(filtered, subject_metadata={"SUBJECT:WEIGHT": 82.7})
    with pytest.warns(GaitWarning, match=r"body mass 82\.7 kg \(the C3D file's SUBJECT:WEIGHT\) differs from the "
                                         r"force plates' stride estimate 75\.0 kg by 9 %"):
        assert body_mass(in_file, _subject(), IdynConfig(), source=None)[0] == 82.7
    with pytest.warns(GaitWarning, match=r"body mass 70\.0 kg \(subject\.yaml\) .* estimate 75\.0 kg by 7 %"):
        body_mass(filtered, _subject(70.0), IdynConfig(), source=None)


def test_foot_load_known_in_swing_and_on_the_plate_only():
    # right foot: stance 0.2–0.6 s, the plate sees it from 0.3 s; left foot: never on a plate,
    # on the ground from the start of the trial until 0.1 s, then from 0.5 s to the end
    t = np.arange(100) / 100
    events = Events(frame=[10, 20, 50, 60], time_s=[0.1, 0.2, 0.5, 0.6], side=["l", "r", "l", "r"],
                    kind=["toe_off", "heel_strike", "heel_strike", "toe_off"], source=["kinematics"] * 4)
    force = np.zeros((100, 3))
    force[30:61, 2] = 500.0
    feet = {"r": {"force_N": force, "cop_m": np.zeros((100, 3)), "free_moment_Nm": np.zeros(100)}}
    trial = filtered_trial(Markers((), np.zeros((100, 0, 3)), 100.0), feet, events)
    known = {side: trial.load_known(side) for side in ("r", "l")}
    expect_r = ~((t >= 0.2) & (t < 0.3))
    expect_l = (t > 0.1) & (t < 0.5)
    np.testing.assert_array_equal(known["r"], expect_r)
    np.testing.assert_array_equal(known["l"], expect_l)


def test_untracked_thigh_frames_are_nan_with_a_warning(exact):
    trial, filtered, calibration, _ = exact
    positions = trial.markers.positions_m.copy()
    labels = trial.markers.labels
    gap = slice(100, 120)  # file frames 101–120 (first frame 1)
    for name in ("GTr", "MRFr"):
        positions[gap, labels.index(name)] = np.nan
    holed = dataclasses.replace(filtered, markers=Markers(labels, positions, trial.markers.rate_hz))
    with pytest.warns(GaitWarning, match=r"thigh_r misses a tracking marker in frames 101–120"):
        result = inverse_dynamics_stage(holed, calibration, IdynConfig(), mass_kg=MASS_KG, mass_source="test")
    thigh = [COORDINATES.index(f"{j}_r_{a}") for j in ("hip", "knee") for a in ("flexion", "adduction", "rotation")]
    assert np.isnan(result.q[gap][:, thigh]).all()
    outside = np.ones(trial.markers.n_frames, dtype=bool)
    outside[gap] = False
    np.testing.assert_allclose(result.q[outside], trial.q[outside], rtol=0, atol=1e-9)
    assert np.isnan(result.joint_moments_Nm[gap]).all()
    assert np.isfinite(result.joint_moments_Nm[outside]).all()
    # each run of tracked frames is differentiated on its own: away from its two end frames the
    # moments keep the exact trial's accuracy (measured: within 0.002 N·m of the gap-free result)
    away = outside.copy()
    away[gap.start - EDGE:gap.stop + EDGE] = False
    away[:EDGE] = away[-EDGE:] = False
    got = moments_to_clinical(result.joint_moments_Nm)[away]
    want = moments_to_clinical(trial.joint_moments_Nm)[away]
    assert np.all(np.abs(got - want) <= 5e-4 * np.abs(want).max(axis=0))


# --- noisy trials through the real filter stage -----------------------------------------------------
@pytest.fixture(scope="module")
def noisy():
    """Per seed: the synthetic trial, the filtered trial and the idyn result (defaults of gait synth)."""
    out = {}
    for seed in NOISY_SEEDS:
        trial = simulate_trial(condition="normal", seed=seed, noise_mm=2.0)
        filtered = filter_trial(Recording(trial.markers, trial.plates), FilterConfig()).trial
        result = inverse_dynamics_stage(filtered, calibration_of(trial), IdynConfig(), mass_kg=MASS_KG,
                                        mass_source="test")
        out[seed] = (trial, filtered, result)
    return out


def sagittal_rms_per_kg(trial, result) -> dict[str, float]:
    """RMS error of the sagittal hip/knee/ankle moments (N·m/kg) where that leg's moments are known (its foot's load
    known, outside the filter's edge frames)."""
    got = moments_to_clinical(result.joint_moments_Nm) / MASS_KG
    want = moments_to_clinical(trial.joint_moments_Nm) / MASS_KG
    out = {}
    for side in ("r", "l"):
        known = result.moment_known[:, JOINTS.index(f"hip_{side}")]
        assert known.sum() > 0.4 * known.size  # swing plus one plate stance
        for joint in ("hip", "knee", "ankle"):
            k = MOMENTS.index(f"{joint}_{side}_flexion_moment")
            error = got[known, k] - want[known, k]
            assert np.isfinite(error).all()
            out[f"{joint}_{side}"] = float(np.sqrt(np.mean(error ** 2)))
    return out


@pytest.mark.parametrize("seed", NOISY_SEEDS)
def test_noisy_trial_sagittal_moments_within_tolerance(noisy, seed):
    trial, _, result = noisy[seed]
    rms = sagittal_rms_per_kg(trial, result)
    too_large = {name: round(value, 3) for name, value in rms.items() if value >= RMS_BOUND[name.split("_")[0]]}
    assert not too_large, f"seed {seed}: RMS errors (N·m/kg) {rms}"


@pytest.mark.parametrize("seed", NOISY_SEEDS)
def test_residual_force_is_what_newtons_law_leaves_over(noisy, seed):
    # the reported residual is the whole body's m·a + m·g − F_ground, with a = d²/dt² of the
    # mass-weighted CoM of the segments (same spline as the stage's q̈, differentiated directly)
    trial, filtered, result = noisy[seed]
    measured = result.measured
    assert measured.sum() > 50
    masses = result.parameters.mass_kg
    com = forward_kinematics(result.q, result.parameters).com_m
    _, acceleration = coordinate_derivatives(np.einsum("b,nbk->nk", masses, com), trial.markers.rate_hz)
    ground = sum(np.nan_to_num(load.force_N) for load in filtered.feet.values())
    newton = acceleration + masses.sum() * np.array([0.0, 0.0, 9.81]) - ground
    np.testing.assert_allclose(result.residual_force_N[measured], newton[measured], rtol=0, atol=0.1)
    # the noise shows in the residuals: they are not hidden (RMS 46–65 N measured over seeds 0–9)
    rms = np.sqrt(np.mean(np.sum(result.residual_force_N[measured] ** 2, axis=1)))
    assert 20.0 < rms < 250.0


def _exact_through_the_filter(shared_plate: bool):
    trial = simulate_trial(seed=0, noise_mm=0.0, artefact_mm=0.0, plate_noise_N=0.0, shared_plate=shared_plate)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        filtered = filter_trial(Recording(trial.markers, trial.plates), FilterConfig())
    result = inverse_dynamics_stage(filtered.trial, calibration_of(trial), IdynConfig(), mass_kg=MASS_KG,
                                    mass_source="test")
    return trial, filtered, result, [str(w.message) for w in caught if issubclass(w.category, GaitWarning)]


def test_a_plate_both_feet_stand_on_leaves_both_loads_unknown_in_exactly_that_double_support():
    """The left stance and the right stance after it on one plate instead of two: both legs lose exactly the
    frames in which both feet load the plate (between the right heel strike and the left toe off that the
    two-plate trial's plates time), with a warning naming them; elsewhere the moments are as accurate as with a
    plate per foot (measured, max error over the known frames: right 12.3 and left 43.7 N·m with two plates —
    the 6 Hz filter at load onsets — and no more with one shared plate)."""
    truth, two, separate, quiet = _exact_through_the_filter(False)
    _, one, shared, said = _exact_through_the_filter(True)
    assert quiet == []
    right_strike = two.events.times("r", "heel_strike", "plate")
    left_off = two.events.times("l", "toe_off", "plate")
    assert right_strike.size == left_off.size == 1 and right_strike[0] < left_off[0]
    t = two.trial.time_s
    both = np.flatnonzero((t >= right_strike[0]) & (t <= left_off[0]))
    for side, joints in (("r", [1, 2, 3]), ("l", [4, 5, 6])):
        lost = np.flatnonzero(separate.foot_measured[side] & ~shared.foot_measured[side])
        np.testing.assert_array_equal(lost, both)
        assert not (shared.foot_measured[side] & ~separate.foot_measured[side]).any()
        error = {name: np.abs(r.joint_moments_Nm[:, joints] - truth.joint_moments_Nm[:, joints])[r.foot_measured[side]]
                 for name, r in (("two", separate), ("one", shared))}
        assert error["one"].max() <= error["two"].max() + 1e-9, side
    first, last = both[0] + 1, both[-1] + 1  # file frames
    span = f"{both[0] / 100:.2f}–{both[-1] / 100:.2f} s"
    assert said == [f"plate1: both feet on it in frames {first}–{last} ({span}): no "
                    "foot is given its load there (the loads of both are unknown); the plate times only the left "
                    "heel strike and the right toe off, the steps in between are timed from the foot markers"]


@pytest.mark.parametrize("noisy", [False, True])
def test_a_functional_hip_centre_from_the_walk_itself(noisy):
    """``hip_joint_centre: score`` on a synthetic walk whose hips turn about the true (Bell) centres: exact without
    noise (residual below 1e-9 mm); with 2 mm noise and 10 mm skin artefact the walk's mostly-flexion motion
    leaves the mediolateral position weak (measured 57 and 23 mm off, seed 1), which the warning says."""
    trial = simulate_trial(seed=1, noise_mm=2.0 if noisy else 0.0, artefact_mm=10.0 if noisy else 0.0,
                           plate_noise_N=0.0)
    config = FilterConfig(cutoff_hz=6.0, force_cutoff_hz=6.0) if noisy else FilterConfig(cutoff_hz=0.0,
                                                                                          force_cutoff_hz=0.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        filtered = filter_trial(Recording(trial.markers, trial.plates), config)
    subject = Subject(mass_kg=MASS_KG, stature_m=STATURE_M, sex="male", hip_joint_centre="score")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = run_idyn(filtered.trial, Recording(trial.static, []), subject, IdynConfig())
    said = [str(w.message) for w in caught if "hip_joint_centre score" in str(w.message)]
    residual = result.reference_posture.hip_score_residual_mm
    assert set(residual) == {"r", "l"} and result.reference_posture.hip_joint_centre == "score"
    if not noisy:
        for name in ("HJCr", "HJCl"):
            np.testing.assert_allclose(result.calibration.joint_centres_m[name],
                                       trial.calibration.joint_centres_m[name], atol=1e-8)
        assert max(residual.values()) < 1e-9 and said == []
    else:
        assert 2.0 < min(residual.values()) and max(residual.values()) < 8.0
        assert len(said) == 2 and "least determined direction" in said[0]


def test_a_synthetic_cleveland_trial_needs_only_its_marker_set():
    """``gait synth --marker-set cleveland`` labels the markers as the preset does (RASI, RLFC, RMMAL, RMT5, …), leaves
    out GT, MRF and TT and puts a 3-marker cluster on each thigh and shank; with ``marker_set: cleveland`` and no
    map the sagittal moments are as accurate as with Table A.6's markers (measured, seed 2, N·m/kg r/l: hip
    0.080/0.093, knee 0.032/0.070, ankle 0.033/0.035; Table A.6, seed 1: 0.075/0.094, 0.034/0.076, 0.031/0.035)."""
    trial = simulate_trial(seed=2, marker_set="cleveland", noise_mm=2.0)
    assert {"RASI", "RLFC", "RMFC", "RLMAL", "RMT5", "RTH1", "LTB3"} <= set(trial.markers.labels)
    assert not {"GTr", "MRFr", "TTr", "ASISr"} & set(trial.markers.labels)
    preset = marker_set("cleveland")
    subject = Subject(mass_kg=MASS_KG, stature_m=STATURE_M, sex="male", marker_set="cleveland")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        filtered = filter_trial(Recording(preset.apply(trial.markers), trial.plates), FilterConfig())
        result = run_idyn(filtered.trial, Recording(preset.apply(trial.static), []), subject, IdynConfig())
    assert result.calibration.tracking_landmarks["thigh_r"] == ("LEFr", "MEFr", "RTH1", "RTH2", "RTH3")
    rms = sagittal_rms_per_kg(trial, result)
    assert max(rms.values()) < 0.1, rms


@pytest.mark.parametrize("name", ["plug_in_gait", "cast"])
def test_synthetic_plug_in_gait_and_cast_trials_need_only_their_marker_set(name):
    """``gait synth --marker-set plug_in_gait`` places RASI/RPSI, THI and TIB wands, KNE, ANK, HEE and TOE (no
    medial, trochanter, tuberosity or fifth-metatarsal markers) and writes the knee and ankle widths and the
    marker diameter as the C3D's PROCESSING group does; Davis's regression (subject.yaml: ``hip_joint_centre:
    davis``, as ``gait synth`` writes it) and the chord method then find the hip, knee and ankle centres
    (within 0.5 mm of the truth with 2 mm noise averaged over the static second) and the chained segments track
    with the joint centre above. ``cast`` has a thigh wand and a shank fibula-head marker plus wand. Measured,
    seed 2, N·m/kg r/l: plug_in_gait hip 0.056/0.059, knee 0.029/0.029, ankle 0.035/0.035 (its joint centres
    0.07–0.33 mm from the truth); cast 0.060/0.063, 0.027/0.029, 0.036/0.032 (before issue 52 the left's 0.076 and
    0.072 counted the filter's edge frames: test_no_moment_is_known_where_the_filters_start_up…)."""
    trial = simulate_trial(seed=2, marker_set=name, noise_mm=2.0)
    preset = marker_set(name)
    subject = subject_of(name)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        filtered = filter_trial(Recording(preset.apply(trial.markers), trial.plates,
                                          subject_metadata=trial.metadata), FilterConfig())
        result = run_idyn(filtered.trial, Recording(preset.apply(trial.static), [], subject_metadata=trial.metadata),
                          subject, IdynConfig())
    assert result.calibration.locked == ()
    if name == "plug_in_gait":
        assert {"RASI", "RTHI", "RKNE", "RTIB", "RANK", "RHEE", "RTOE"} <= set(trial.markers.labels)
        assert not {"RGTR", "RKNM", "RMED", "RTT"} & set(trial.markers.labels)
        assert result.calibration.tracking_landmarks["thigh_r"] == ("LEFr", "RTHI", "HJCr")
        assert result.calibration.chained == {f"{seg}_{s}": f"{jc}{s}" for s in "rl"
                                              for seg, jc in (("thigh", "HJC"), ("shank", "KJC"), ("foot", "AJC"))}
        for jc in ("HJCr", "HJCl", "KJCr", "KJCl", "AJCr", "AJCl"):
            error = np.linalg.norm(result.calibration.joint_centres_m[jc] - trial.calibration.joint_centres_m[jc])
            assert error < 5e-4, (jc, error)
    rms = sagittal_rms_per_kg(trial, result)
    assert max(rms.values()) < 0.1, rms


def test_a_plug_in_gait_session_with_a_labs_extras_gives_the_true_sagittal_moments():
    """Issue 52: a Plug-in Gait walk with medial knee and ankle markers over three plates, its static taken with a
    knee alignment device, filtered as a Plug-in Gait session is by default (``marker_set``: 8 Hz markers, Nexus's
    plates): every sagittal moment within 0.05 N·m/kg RMS of the truth, the slope of the least-squares line within
    0.95–1.05. Measured (seed 0): RMS 0.010–0.033, slopes 0.97–1.02; the same trial at the dissertation's 6/6 Hz
    0.029–0.052 (both hips over 0.05), slopes 0.93–1.00."""
    trial = simulate_trial(seed=0, marker_set="plug_in_gait", plates=3, medial_markers=True)
    preset = marker_set("plug_in_gait")
    static = with_knee_alignment_device(trial.static, trial.calibration.joint_centres_m)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        filtered = filter_trial(Recording(preset.apply(trial.markers), trial.plates, subject_metadata=trial.metadata),
                                FilterConfig(), marker_set="plug_in_gait")
        result = run_idyn(filtered.trial, Recording(preset.apply(static), [], subject_metadata=trial.metadata),
                          subject_of("plug_in_gait"), IdynConfig())
    assert (filtered.config.cutoff_hz, filtered.config.force_cutoff_hz, filtered.config.plate_frames) == \
        (8.0, 0.0, "mean")
    rms = sagittal_rms_per_kg(trial, result)
    assert max(rms.values()) <= 0.05, rms
    got, want = (moments_to_clinical(m) for m in (result.joint_moments_Nm, trial.joint_moments_Nm))
    for side in "rl":
        known = result.moment_known[:, JOINTS.index(f"hip_{side}")]
        for joint in ("hip", "knee", "ankle"):
            k = MOMENTS.index(f"{joint}_{side}_flexion_moment")
            slope = np.polyfit(want[known, k], got[known, k], 1)[0]
            assert 0.95 <= slope <= 1.05, (joint, side, slope)


def test_an_unfilled_thigh_marker_gap_leaves_nan_and_no_spike_at_its_ends():
    """``gait synth``'s noisy walk (2 mm) with the right GT marker lost for 30 frames (file frames 151–180, more
    than the filter's 10: left unfilled). The thigh is untracked across the gap, so the right leg's moments are
    NaN there, and outside it they stay near those of the same walk without the gap. Before issue 34 the thigh
    was fitted to its three other markers in the gap: its pose jumped by their skin movement at both ends and
    the hip moment spiked by 3.2 N·m/kg; measured since: at most 0.10 N·m/kg from the gap-free run, in the first
    frames after the gap (each side of a gap filtered and differentiated on its own)."""
    trial = simulate_trial(seed=2, noise_mm=2.0)
    subject = Subject(mass_kg=MASS_KG, stature_m=STATURE_M, sex="male")
    gap = slice(150, 180)

    def idyn(markers):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            filtered = filter_trial(Recording(markers, trial.plates), FilterConfig()).trial
            return run_idyn(filtered, Recording(trial.static, []), subject, IdynConfig())

    positions = trial.markers.positions_m.copy()
    positions[gap, trial.markers.labels.index("GTr")] = np.nan
    holed = idyn(dataclasses.replace(trial.markers, positions_m=positions))
    whole = idyn(trial.markers)
    right_leg = [JOINT_CHILD.index(BODIES.index(b)) for b in ("thigh_r", "shank_r", "foot_r")]
    assert np.isnan(holed.joint_moments_anatomical_Nm[gap][:, right_leg]).all()
    assert np.isnan(holed.q[gap, COORDINATES.index("hip_r_flexion")]).all()
    outside = np.ones(trial.markers.n_frames, bool)
    outside[gap] = False
    hip = right_leg[0]
    error = np.abs(holed.joint_moments_anatomical_Nm[outside, hip] - whole.joint_moments_anatomical_Nm[outside, hip])
    assert np.isfinite(error).all()
    assert error.max() / MASS_KG < 0.15, error.max() / MASS_KG


# --- a static processed in Nexus beside a raw walk (issue 34) -------------------------------------------
#: Plug-in Gait's virtual points as Nexus writes them into a processed static: the femur's origin is the knee
#: centre, the tibia's the ankle centre
NEXUS_POINTS = {"RFEO": "KJCr", "LFEO": "KJCl", "RTIO": "AJCr", "LTIO": "AJCl", "RHJC": "HJCr", "LHJC": "HJCl"}


@pytest.fixture(scope="module")
def plug_in_gait_walk():
    """``gait synth --marker-set plug_in_gait``'s walk (seed 2, 2 mm noise) through the filter stage."""
    trial = simulate_trial(seed=2, marker_set="plug_in_gait", noise_mm=2.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        filtered = filter_trial(Recording(marker_set("plug_in_gait").apply(trial.markers), trial.plates,
                                          subject_metadata=trial.metadata), FilterConfig()).trial
    return trial, filtered


def _nexus_static(trial, offset_m: float):
    """The synthetic static with Nexus's virtual joint centres added at the true static centres, the knee and
    ankle centres moved ``offset_m`` forward."""
    centres = {label: trial.calibration.joint_centres_m[jc] + [0.0 if jc.startswith("HJC") else offset_m, 0.0, 0.0]
               for label, jc in NEXUS_POINTS.items()}
    static = with_fixed_points(trial.static, centres)
    return Recording(marker_set("plug_in_gait").apply(static), [], subject_metadata=trial.metadata)


@pytest.mark.parametrize("hip", ["davis", "from_file"])
def test_a_nexus_static_with_a_raw_walk_falls_back_to_the_tools_own_centres(plug_in_gait_walk, hip):
    """The static holds RFEO/LFEO/RTIO/LTIO (15 mm off the truth here, so that which centres were used shows)
    and RHJC/LHJC, the walk none of them. Before issue 34 the virtual points were tracking points of thighs,
    shanks and feet: all six leg segments NaN in every frame, exit 0. Now the knee and ankle centres are the
    chord method's (within 0.5 mm of the truth, as without the virtual points), a note says so, and the sagittal
    moments recover the truth as in the plain Plug-in Gait test (< 0.1 N·m/kg RMS). With ``from_file`` the
    static's hip centres stay and each thigh is tracked with its hip centre placed by the pelvis."""
    trial, filtered = plug_in_gait_walk
    subject = Subject(mass_kg=MASS_KG, stature_m=STATURE_M, sex="male", marker_set="plug_in_gait",
                      hip_joint_centre=hip, segment_inertias="de_leva")
    with pytest.warns(GaitWarning, match="virtual joint centres in the static trial but not in the walking trial"):
        result = run_idyn(filtered, _nexus_static(trial, 0.015), subject, IdynConfig())
    assert np.isfinite(result.q).all()
    for jc in ("KJCr", "KJCl", "AJCr", "AJCl"):
        error = np.linalg.norm(result.calibration.joint_centres_m[jc] - trial.calibration.joint_centres_m[jc])
        assert error < 5e-4, (jc, error)
    note = next(n for n in result.notes if n.startswith("virtual joint centres in the static trial"))
    assert "KJCr (RKJC or RFEO)" in note and "the tool's own" in note
    assert result.calibration.chained["thigh_r"] == "HJCr"
    assert ("hip_joint_centre from_file" in note) == (hip == "from_file")
    rms = sagittal_rms_per_kg(trial, result)
    assert max(rms.values()) < 0.1, rms


def test_no_moment_is_known_where_the_filters_start_up_reverses_the_accelerations(plug_in_gait_walk):
    """Issue 52: the synthetic Plug-in Gait walk begins and ends with the left foot in swing (its load known: zero),
    so the left leg's moments were scored in the trial's first and last frames, where the zero-lag filter's odd
    extension reverses every acceleration (signal/butterworth.edge_frames): its hip and knee moments against the
    truth had RMS 0.071/0.070 N·m/kg against the right's 0.050/0.028 (noise-free markers: 0.067/0.070 against
    0.048/0.028; filtered but cropped by k frames at an end, the hip moment in the new end frame moved by 0.45
    N·m/kg RMS at k = 0 and 0.05 at 4, 0.02 from 5 on). Now no joint's moment is known in the first and last 5
    frames (100 Hz, 6 Hz), and the left leg scores as the right does (measured, 2 mm noise, right/left: hip
    0.056/0.059, knee 0.029/0.029, ankle 0.035/0.035)."""
    trial, filtered = plug_in_gait_walk
    subject = Subject(mass_kg=MASS_KG, stature_m=STATURE_M, sex="male", marker_set="plug_in_gait",
                      hip_joint_centre="davis", segment_inertias="de_leva")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = run_idyn(filtered, Recording(marker_set("plug_in_gait").apply(trial.static), [],
                                              subject_metadata=trial.metadata), subject, IdynConfig())
    edge = filtered.filter_edge_frames
    assert edge == 5
    known = result.moment_known
    assert not known[:edge].any() and not known[-edge:].any()
    assert known[edge:-edge, JOINTS.index("lumbar")].all()
    left = result.foot_measured["l"]
    assert left[:edge].all() and left[-edge:].all()  # the load is still known there: the kinematics are not
    rms = sagittal_rms_per_kg(trial, result)
    for joint in ("hip", "knee", "ankle"):
        assert abs(rms[f"{joint}_l"] - rms[f"{joint}_r"]) < 0.01, rms
    assert max(rms.values()) < 0.06, rms


def test_the_notes_name_one_source_per_joint_centre(plug_in_gait_walk):
    """A Plug-in Gait static with the lab's knee and ankle centres (Nexus's FEO/TIO at the truth) and the knee and
    ankle widths: the centres are the lab's, and the notes say only that. Before issue 34 they also said that
    the chord method had placed them ("KJCr: virtual marker from the lab file" beside "KJCr: Plug-in Gait's chord
    method"). The thigh and shank frames still take the lab's centre in the medial marker's place: the same
    anatomical frames as the chord's to 1° (its centres lie within 0.5 mm of the truth, some 50 mm from the
    lateral marker: 0.6°; measured at most 0.49°, the right shank)."""
    trial, _ = plug_in_gait_walk
    subject = Subject(mass_kg=MASS_KG, stature_m=STATURE_M, sex="male", marker_set="plug_in_gait",
                      hip_joint_centre="davis", segment_inertias="de_leva")
    preset = marker_set("plug_in_gait")
    with_points = static_calibration(_nexus_static(trial, 0.0).markers, None, subject, MASS_KG, source=None,
                                     metadata=trial.metadata)
    plain = static_calibration(preset.apply(trial.static), None, subject, MASS_KG, source=None,
                               metadata=trial.metadata)
    for jc in ("KJCr", "KJCl", "AJCr", "AJCl"):
        said = [n for n in with_points.notes if n.startswith(f"{jc}:")]
        assert said == [f"{jc}: virtual marker from the lab file"], said
        assert any(n.startswith(f"{jc}: Plug-in Gait's chord method") for n in plain.notes)
    assert all(with_points.anatomical_from_landmarks)
    for k in range(len(BODIES)):
        R = with_points.reference_to_anatomical[k].T @ plain.reference_to_anatomical[k]
        angle = np.degrees(np.arccos(np.clip((np.trace(R) - 1) / 2, -1, 1)))
        assert angle < 1.0, (BODIES[k], angle)


def test_the_mass_estimate_takes_each_measured_stance_with_its_own_stride():
    """A walk of 1.1 s strides (700 N, one stance per foot on a plate) that began with a slow 1.7 s stride of the
    right foot (a heel strike 1.7 s before its first, found by the markers). Each foot carries half the weight
    over its own stride: 2 ∫Fz dt / (g T) with T the stride that stance begins (``stride_period_s``), 70.2 kg
    either way (the 20 N
    threshold and the filter take 1.6 % of the impulse). Before issue 34, T was the mean of every stride in the
    trial, the slow one included: 65.7 kg, 6 % low, and a true body mass of 70 kg was warned about as 7 % off."""
    walk = make_walk(plates=[("r", 1, 0.0, 0.6, 0.4), ("l", 1, 0.0, 0.6, 0.4)], duration_s=5.0,
                     first_strike_s={"r": 1.9, "l": 2.45})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        trial = filter_trial(walk_recording(walk), FilterConfig(events="detect")).trial
    ev = trial.events
    first = ev.times("r", "heel_strike")[0]
    slow = Events(frame=[*ev.frame, int(round((first - 1.7) * trial.rate_hz))], time_s=[*ev.time_s, first - 1.7],
                  side=[*ev.side, "r"], kind=[*ev.kind, "heel_strike"], source=[*ev.source, "kinematics"])
    began_slowly = dataclasses.replace(trial, events=slow)
    true_kg = walk.body_weight_N / 9.81
    assert estimate_mass_kg(trial) == pytest.approx(true_kg, rel=0.03)
    assert estimate_mass_kg(began_slowly) == pytest.approx(estimate_mass_kg(trial), rel=1e-12)


# --- a static with a knee alignment device (issue 34) -------------------------------------------------
THIGH_WAND_TURN, SHANK_WAND_TURN = np.radians(25.0), np.radians(-15.0)


def _turned(points, pivot, towards, angle):
    """``points`` (n, 3) turned by ``angle`` about the line from ``pivot`` towards ``towards`` (Rodrigues)."""
    u = towards - pivot
    u = u / np.linalg.norm(u, axis=-1, keepdims=True)
    v = points - pivot
    return (pivot + v * np.cos(angle) + np.cross(u, v) * np.sin(angle)
            + u * np.sum(u * v, axis=-1, keepdims=True) * (1 - np.cos(angle)))


def _wands_misplaced(markers, centres):
    """The thigh wands turned 25° around each thigh (about the knee marker → true hip centre line) and the shank
    wands −15° around each shank (ankle marker → true knee centre): rigidly, as a wand stuck on off the knee axis's
    plane would sit."""
    pos, labels = markers.positions_m.copy(), markers.labels
    for s, lab in (("r", "R"), ("l", "L")):
        kne, ank = pos[:, labels.index(f"{lab}KNE")], pos[:, labels.index(f"{lab}ANK")]
        thi, tib = labels.index(f"{lab}THI"), labels.index(f"{lab}TIB")
        pos[:, thi] = _turned(pos[:, thi], kne, centres[f"HJC{s}"], THIGH_WAND_TURN)
        pos[:, tib] = _turned(pos[:, tib], ank, centres[f"KJC{s}"], SHANK_WAND_TURN)
    return dataclasses.replace(markers, positions_m=pos)


def test_a_knee_alignment_device_makes_the_wands_placement_irrelevant():
    """``gait synth --marker-set plug_in_gait`` without noise (Davis hips, wands in the planes of the true knee and
    ankle axes), its static with a knee alignment device (no knee marker) built on the true knee axis. The device
    gives Plug-in Gait's thigh and shank rotation offsets: 0° with the wands where they are, and with the wands
    turned 25° (thigh) and −15° (shank) around the segments exactly the turns back (measured to 0.05°); the
    anatomical angles are then those of the wands where they were (measured 3e-12°), the sagittal moments within
    0.02 N·m/kg. Without the device the turned wands move knee rotation by 28° and knee adduction by 18°
    (measured). Before issue 34 a static without its knee markers was refused (exit 2: RKNE missing) and the
    device ignored."""
    trial = simulate_trial(seed=2, marker_set="plug_in_gait", noise_mm=0.0, artefact_mm=0.0)
    preset = marker_set("plug_in_gait")
    subject = Subject(mass_kg=MASS_KG, stature_m=STATURE_M, sex="male", marker_set="plug_in_gait",
                      hip_joint_centre="davis", segment_inertias="de_leva")
    walk_centres = trial.joint_centres_m()
    static_centres = trial.calibration.joint_centres_m

    def idyn(markers, static):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            filtered = filter_trial(Recording(preset.apply(markers), trial.plates, subject_metadata=trial.metadata),
                                    FilterConfig(cutoff_hz=0)).trial
            return run_idyn(filtered, Recording(preset.apply(static), [], subject_metadata=trial.metadata),
                            subject, IdynConfig())

    kad_static = with_knee_alignment_device(trial.static, static_centres)
    placed = idyn(trial.markers, kad_static)
    turned = idyn(_wands_misplaced(trial.markers, walk_centres),
                  with_knee_alignment_device(_wands_misplaced(trial.static, static_centres), static_centres))
    for result in (placed, turned):
        assert result.angle_convention == "plug_in_gait"
        np.testing.assert_allclose(result.calibration.static_landmarks_m["LEFr"],
                                   trial.static.positions_m[:, trial.static.labels.index("RKNE")].mean(axis=0),
                                   atol=1e-9)  # the device's hub is where the knee marker was

    def offsets(result):
        note = next(n for n in result.notes if "knee alignment device:" in n)
        return np.array([float(x) for x in re.findall(r"(?:thigh|shank) rotation (-?[\d.]+)°", note)])

    np.testing.assert_allclose(offsets(placed), 0.0, atol=0.05)
    back = -np.degrees([THIGH_WAND_TURN, SHANK_WAND_TURN] * 2)
    np.testing.assert_allclose(offsets(turned), back, atol=0.05)
    angles = np.degrees(np.abs(turned.anatomical_angles_rad - placed.anatomical_angles_rad))
    assert np.nanmax(angles) < 1e-6, np.nanmax(angles, axis=0)
    known = placed.moment_known
    sagittal = np.abs(turned.joint_moments_anatomical_Nm[..., 1] - placed.joint_moments_anatomical_Nm[..., 1])
    assert np.nanmax(sagittal[known]) / MASS_KG < 0.02


def test_a_stride_from_a_plates_heel_strike_to_the_markers_next_one_is_not_its_period():
    """Right heel strikes at 1.1 and 3.3 s found by the markers 0.2 s late (a stiff knee's heel marker), and at
    2.0 s by the plate, in a walk of 1.1 s strides: the stride from the plate's strike would last 1.3 s; half the
    time between the markers' strikes around it is the period, 1.1 s. A stride between strikes of one source is
    its own period (the slow first stride of the walk above)."""
    events = Events(frame=[110, 200, 330, 20], time_s=[1.1, 2.0, 3.3, 0.2], side=["r", "r", "r", "l"],
                    kind=["heel_strike"] * 4, source=["kinematics", "plate", "kinematics", "plate"])
    assert stride_period_s(events, "r", 2.0) == pytest.approx(1.1, abs=1e-12)
    assert stride_period_s(events, "r", 1.1) == pytest.approx(0.9, abs=1e-12)  # 1.1 → 2.0: no source in common
    slow = Events(frame=[20, 190, 300], time_s=[0.2, 1.9, 3.0], side=["r"] * 3, kind=["heel_strike"] * 3,
                  source=["kinematics", "kinematics", "plate"])
    assert stride_period_s(slow, "r", 0.2) == pytest.approx(1.7, abs=1e-12)


# --- anatomical angles against the synthetic body's truth; the static's heading -----------------------
def subject_of(name: str) -> Subject:
    """The subject ``gait synth --marker-set name`` writes: a Plug-in Gait subject's hips are Davis's, its segments
    de Leva's as the synthetic body's."""
    return Subject(mass_kg=MASS_KG, stature_m=STATURE_M, sex="male", marker_set=name,
                   hip_joint_centre="davis" if name == "plug_in_gait" else "bell", segment_inertias="de_leva")


@pytest.mark.parametrize("name", ["plug_in_gait", "dissertation", "cleveland", "cast"])
def test_exact_anatomical_angles_are_the_bodys_true_ones(name):
    """Noise-free markers straight into the stage (no filter; true loads and events): the anatomical angles are
    the synthetic body's true ones (``SyntheticTrial.anatomical_angles_rad``, gaitcli/synth/anatomy.py: the
    definitions applied to the body's own rotations and true joint centres, no marker involved) — Plug-in Gait's
    CGM frames for plug_in_gait, ISB's for the others. Measured ≤ 1.5e-14 rad on every set (round-off)."""
    trial = simulate_trial(seed=2, marker_set=name, strides=1, noise_mm=0.0, artefact_mm=0.0, plate_noise_N=0.0)
    preset = marker_set(name)
    filtered = filtered_trial(preset.apply(trial.markers), trial.feet, true_events(trial))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = run_idyn(filtered, Recording(preset.apply(trial.static), [], subject_metadata=trial.metadata),
                          subject_of(name), IdynConfig())
    assert result.angle_convention == trial.angle_convention == ("plug_in_gait" if name == "plug_in_gait" else "isb")
    assert np.isfinite(trial.anatomical_angles_rad).all()
    np.testing.assert_allclose(result.anatomical_angles_rad, trial.anatomical_angles_rad, rtol=0, atol=1e-9)


#: (what is turned, about the vertical by deg, through which point): the static alone, or the whole walk (trial and
#: static: the subject walks the other way)
TURNS = [("static", 0.0, "origin"), ("static", 90.0, "origin"), ("static", 180.0, "origin"),
         ("static", 270.0, "origin"), ("static", 21.0, "origin"), ("static", 21.0, "pelvis"),
         ("static", 270.0, "pelvis"), ("walk", 180.0, "origin")]


def turned(recording: Recording, degrees: float, about: str) -> Recording:
    """``recording`` turned about the vertical through the lab origin or its mean pelvis centre (``about``)."""
    from gaitcli.kinematics.rotations import rot_z

    turn = rot_z(np.radians(degrees))
    m = recording.markers
    centre = np.zeros(3)
    if about == "pelvis":
        pelvis = [m.index(n) for n in ("ASISr", "ASISl", "PSISr", "PSISl")]
        centre = np.nanmean(m.positions_m[:, pelvis], axis=(0, 1)) * [1.0, 1.0, 0.0]
    plates = [dataclasses.replace(p, force_N=p.force_N @ turn.T, moment_Nm=p.moment_Nm @ turn.T,
                                  centre_m=turn @ p.centre_m, corners_m=p.corners_m @ turn.T)
              for p in recording.plates]  # about the origin (the whole walk only)
    markers = dataclasses.replace(m, positions_m=(m.positions_m - centre) @ turn.T + centre)
    return dataclasses.replace(recording, markers=markers, plates=plates)


@pytest.fixture(scope="module", params=["plug_in_gait", "dissertation"])
def walked(request):
    """A synthetic walk (seed 2, one stride, gait synth's noise), its static, and a function running filter and
    idyn on a walk and static as a reader gives them: both turned by the walk's lab → model rotation."""
    from gaitcli.io.axes import apply_rotation, infer_lab_to_model

    name = request.param
    trial = simulate_trial(seed=2, marker_set=name, strides=1)
    preset = marker_set(name)
    walk = Recording(preset.apply(trial.markers), trial.plates, subject_metadata=trial.metadata)
    static = Recording(preset.apply(trial.static), [], subject_metadata=trial.metadata)

    def run(walk: Recording, static: Recording):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            lab_to_model = infer_lab_to_model(walk.markers.positions_m, walk.plates)
            filtered = filter_trial(apply_rotation(walk, lab_to_model), FilterConfig()).trial
            return run_idyn(filtered, apply_rotation(static, lab_to_model), subject_of(name), IdynConfig())

    return name, walk, static, run, run(walk, static)


@pytest.mark.parametrize("what, degrees, about", TURNS)
def test_neither_the_statics_heading_nor_the_walking_direction_changes_a_result(walked, what, degrees, about):
    """The static turned about the vertical through the lab origin or its own pelvis centre (real Plug-in Gait
    statics stand 75–176° from the walk), or the subject walking the other way: anatomical angles, Plug-in Gait
    moments and joint powers as unturned, to 1e-6 of each one's largest value (measured ≤ 1e-11: round-off)."""
    name, walk, static, run, ahead = walked
    if what == "static":
        got = run(walk, turned(static, degrees, about))
    else:
        got = run(turned(walk, degrees, about), turned(static, degrees, about))
    for field in ("anatomical_angles_rad", "joint_moments_anatomical_Nm", "joint_powers_W", "joint_powers_sagittal_W"):
        want, value = getattr(ahead, field), getattr(got, field)
        assert np.isfinite(want).mean() > 0.9, field
        np.testing.assert_allclose(value, want, rtol=0, atol=1e-6 * np.nanmax(np.abs(want)), err_msg=f"{name} {field}")


def test_medial_markers_leave_plug_in_gaits_tracking_its_joint_centre():
    """Issue 52: a Plug-in Gait walk with medial knee and ankle markers (``medial_markers=True``: each with its own
    1 mm noise and 10 mm artefact). Each thigh and shank then has three markers of its own (KNE, KNM, THI; ANK, MED,
    TIB), and before, the joint centre above left its cluster: three markers within ~0.1 m of each other track the
    thigh, and the sagittal hip moment against the truth had RMS 0.068 (right) / 0.077 N·m/kg (left), 0.050 / 0.052
    without the medial markers. Now the segment keeps the joint centre, the medial marker joining it as a fourth
    point (measured 0.050 / 0.055, every other sagittal moment ≤ 0.034; the filter alone leaves 0.048)."""
    trial = simulate_trial(seed=2, marker_set="plug_in_gait", medial_markers=True)
    preset = marker_set("plug_in_gait")
    subject = Subject(mass_kg=MASS_KG, stature_m=STATURE_M, sex="male", marker_set="plug_in_gait",
                      hip_joint_centre="davis", segment_inertias="de_leva")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        filtered = filter_trial(Recording(preset.apply(trial.markers), trial.plates, subject_metadata=trial.metadata),
                                FilterConfig()).trial
        result = run_idyn(filtered, Recording(preset.apply(trial.static), [], subject_metadata=trial.metadata),
                          subject, IdynConfig())
    tracking = result.calibration.tracking_landmarks
    assert tracking["thigh_r"] == ("LEFr", "MEFr", "RTHI", "HJCr")
    assert tracking["shank_l"] == ("LMl", "MMl", "LTIB", "KJCl")
    rms = sagittal_rms_per_kg(trial, result)
    assert max(rms.values()) < 0.06, rms
