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

(re-measured 2026-12-01 after the double-support COP fix of the generator.)
With the noise read as 2 mm per axis (3.5 mm RMS in 3-D) the hip measured 0.084–0.128. The left
leg's swing includes the first and last frames of the trial, where the 6 Hz filter and the spline
ends are least accurate. Pelvis residuals in the frames where every contact is measured: RMS
46–65 N and 18–24 N·m (the noise's and the skin artefact's whole-body acceleration error); see
``test_residual_force_is_what_newtons_law_leaves_over``.
"""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest

from gaitcli.dynamics.stage import IdynConfig
from gaitcli.signal.stage import FilterConfig
from gaitcli.dynamics.derivatives import coordinate_derivatives
from gaitcli.core.container import FootLoad, Trial, load_known_frames
from gaitcli.dynamics.stage import body_mass, estimate_mass_kg, inverse_dynamics_stage, run_idyn
from gaitcli.errors import GaitWarning
from gaitcli.kinematics.calibration import calibrate
from gaitcli.kinematics.conventions import moments_to_clinical
from gaitcli.kinematics.markerset import marker_set
from gaitcli.kinematics.forward import forward_kinematics
from gaitcli.kinematics.model import COORDINATES, JOINT_CHILD, MOMENTS
from gaitcli.core.recording import ForcePlate, Markers, Recording
from gaitcli.core.events import Events
from gaitcli.signal.stage import filter_trial
from gaitcli.synth import simulate_trial
from gaitcli.trial import Subject

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
    with pytest.warns(GaitWarning, match=r"thigh_r has < 3 markers in frames 101–120"):
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
    """RMS error of the sagittal hip/knee/ankle moments (N·m/kg) where that foot's load is known."""
    got = moments_to_clinical(result.joint_moments_Nm) / MASS_KG
    want = moments_to_clinical(trial.joint_moments_Nm) / MASS_KG
    out = {}
    for side in ("r", "l"):
        known = result.foot_measured[side]
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
    seed 2, N·m/kg r/l: plug_in_gait hip 0.056/0.076, knee 0.029/0.072, ankle 0.035/0.034 (its joint centres
    0.07–0.33 mm from the truth); cast 0.060/0.081, 0.027/0.073, 0.036/0.032."""
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


# --- anatomical angles against the synthetic body's truth; the static's heading -----------------------
def subject_of(name: str) -> Subject:
    """The subject ``gait synth --marker-set name`` writes: a Plug-in Gait subject's hips are Davis's."""
    return Subject(mass_kg=MASS_KG, stature_m=STATURE_M, sex="male", marker_set=name,
                   hip_joint_centre="davis" if name == "plug_in_gait" else "bell")


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
