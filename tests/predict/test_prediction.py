"""A converged prediction of normal walking (shipped: gaitcli/predict/data, how it was made in its header), checked
on its own outputs and not by eye: every constraint group holds, the excitations stay in [0, 1], Newton's second
law holds over the cycle (∫ΣF_z dt = m·g·T within 1 %), and the gait is one a clinician recognises."""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.predict.guess import SHIPPED_WALK as STORED
from gaitcli.predict.reference import read_reference
from gaitcli.predict.stage import FEASIBILITY_TOLERANCE, PredictConfig, evaluate_design
from gaitcli.resources import bundled_reference


@pytest.fixture(scope="module")
def prediction():
    return evaluate_design(PredictConfig(), np.loadtxt(STORED), reference=read_reference(bundled_reference()))


def test_every_constraint_holds(prediction):
    assert prediction.converged, prediction.violations
    summary = prediction.summary()
    assert summary["max_moment_error_Nm"] <= 2.0 + FEASIBILITY_TOLERANCE  # εm, as the stage judges it
    assert summary["max_contact_error_m"] <= 0.002 + 1e-6  # εk
    assert -1e-6 <= summary["min_excitation"] and summary["max_excitation"] <= 1.0 + 1e-6
    assert np.all(prediction.grf_N[:, [1, 3]] >= -1e-6)  # f_z ≥ 0


def test_newton_euler_over_the_cycle(prediction):
    # the centre of mass's vertical momentum is periodic: the floor carries the body weight on average
    assert prediction.vertical_impulse_ratio() == pytest.approx(1.0, abs=0.01)


def test_it_is_a_walk(prediction):
    # stance, double support, knee swing, the two-humped vertical GRF as people walk, and the ankle's
    # plantarflexor moment peaking in late stance (at 32 % before the heel rocker's bound)
    checks = prediction.gait_checks()
    assert all(c["ok"] for c in checks.values()), checks
    assert 55 <= checks["stance_pct"]["value"] <= 68 and checks["knee_swing_peak_deg"]["value"] >= 55
    first, valley, second = checks["vertical_grf"]["value"]
    assert first > 1.0 and second > 1.0 and valley < 1.0


def test_the_kinetics_are_a_normal_walkers(prediction):
    # a knee extensor moment in loading response, the plantarflexor moment peaking between 40 and 55 % of the
    # cycle, the vasti active in early stance and no muscle saturated for more than 5 % of the cycle; with the
    # heel rocker free (foot_flat_min_pct 0) the forefoot lands at 4.7 % and the knee extensor moment is at most
    # 0.16 N·m/kg, the vasti silent, the plantarflexor peak at 32 % (benchmarks/README.md)
    r = prediction
    period = r.phase_durations_s.sum()
    pct = 100 * r.point_time_s / period
    moments = r.joint_moments_Nm / r.body_mass_kg  # hip flexion, knee flexion, ankle dorsiflexion positive
    assert -moments[(pct >= 5) & (pct <= 20), 1].min() >= 0.3
    stance = pct <= 100 * r.phase_durations_s[:6].sum() / period  # the right foot's: phases 1–6
    assert 40 <= pct[stance][np.argmin(moments[stance, 2])] <= 55
    vasti = r.activations[:, list(r.muscle_names).index("vasti_r")]
    assert vasti[r.cycle_pct <= 20].max() >= 0.1 and vasti[r.cycle_pct >= 62].max() < 0.05
    assert np.all((r.activations > 0.95).mean(axis=0) <= 0.05)
    assert 100 * r.phase_durations_s[0] / period >= 7 - 1e-6  # the bound itself


def test_the_symmetric_gait_repeats_mirrored(prediction):
    d = prediction.phase_durations_s
    np.testing.assert_allclose(d[:4], d[4:])
    half = len(prediction.time_s) // 2
    angles = prediction.clinical_angles_deg
    np.testing.assert_allclose(angles[half:, 3:], angles[:half, :3], atol=1e-9)  # left = right half a cycle on


def test_fine_grid_at_refinement_1_is_the_control_points(prediction):
    """The fine-grid evaluation (splines evaluated anew at any times, ``problem.gait_at``) reproduces the
    control-point costs on the control grid itself; 4× finer it is reported in summary.json."""
    from gaitcli.predict.model import WalkingModel
    from gaitcli.predict.stage import fine_grid

    same = fine_grid(PredictConfig(), np.loadtxt(STORED), read_reference(bundled_reference()), WalkingModel(),
                     refinement=1)
    assert same["cost_of_transport_J_per_m"] == pytest.approx(prediction.cost_of_transport_J_per_m, rel=1e-6)
    assert same["deviation"] == pytest.approx(prediction.deviation, rel=1e-6)
    assert same["max_moment_error_Nm"] <= 2.0 + 1e-4 and same["max_contact_error_m"] <= 0.002 + 1e-6
    fine = prediction.summary()["fine_grid"]
    assert fine["refinement"] == 4 and np.isfinite(fine["objective"])


def test_the_physics_holds_between_the_control_points(prediction):
    # the same solution on a grid 4× finer than the optimizer's (grid.py: dense points in every phase):
    # the cost and the moment balance hold there too, not only where the optimizer looked
    fine = prediction.fine_grid
    assert fine["cost_of_transport_J_per_m"] == pytest.approx(prediction.cost_of_transport_J_per_m, rel=0.02)
    assert fine["deviation"] == pytest.approx(prediction.deviation, rel=0.05)
    # the moment and contact errors within 1.5 εm and 1.5 εk (measured 2.33 N·m, 2.06 mm); the excitations within
    # [−0.05, 1.05] (measured −0.03 … 1.04; with 5 points in the heel rocker and 12 from heel off −0.08 … 1.11,
    # with 8 from heel off 7.2 N·m and −0.22 … 1.54: docs/decisions.md, "Control points")
    assert fine["max_moment_error_Nm"] <= 1.5 * 2.0 and fine["max_contact_error_m"] <= 1.5 * 0.002
    assert -0.05 <= fine["min_excitation"] and fine["max_excitation"] <= 1.05
